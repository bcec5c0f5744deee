// Ray-traced reflections: from a glossy surface, a ray along the mirror direction; its hit is shaded
// by the whole shading core — material, decals, local and particle lights through the frame's
// methods, the sun with a shadow ray of its own — and, if glossy too, reflects again, up to
// `frame.ray_options.z` bounces. So lights and decals outside the view appear in reflections, as far
// as the methods reach them: the clustered lists cover the view frustum only, the acceleration
// structures the whole scene.
//
// Texture filtering at hits follows a ray cone (Akenine-Möller et al., "Texture Level of Detail
// Strategies for Real-Time Ray Tracing", 2019): it starts as wide as the pixel and spreads by the
// pixel's angle plus the surface's roughness; two rays offset across the cone meeting the hit's
// plane give the UV and position gradients, as neighbouring pixels do in the resolve.
#include "shading/shade.wgsl"
#include "shading/triangle_surface.wgsl"
#include "shading/sun_shadow.wgsl"

// How much of the mirror direction's radiance a surface reflects towards its viewer: the split-sum
// BRDF's share, as `shade` gives the prefiltered environment, zero above the roughness threshold and
// fading in over its last quarter so no edge shows where the threshold cuts.
fn reflection_weight(s: ShadingInput) -> vec3<f32> {
    if MATERIAL_EXTENSIONS && s.unlit {
        return vec3<f32>(0.0);
    }
    let threshold = frame.ray_settings.y;
    let fade = saturate((threshold - s.roughness) / (0.25 * threshold));
    return environment_specular_albedo(s) * fade;
}

// Two unit vectors perpendicular to `d` and to each other.
fn perpendicular_pair(d: vec3<f32>) -> mat2x3<f32> {
    let helper = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(d.x) > 0.7);
    let u = normalize(cross(d, helper));
    return mat2x3<f32>(u, cross(d, u));
}

// The mirror direction of `view_dir` about the shading normal, kept above the geometric surface (a
// normal map may tilt it below, where it would hit the surface it leaves).
fn mirror_direction(s: ShadingInput, geometric_normal: vec3<f32>) -> vec3<f32> {
    let r = reflect(-s.view_dir, s.normal);
    let below = dot(r, geometric_normal);
    return select(r, normalize(r - geometric_normal * (below - 1e-3)), below < 1e-3);
}

// Radiance reflected by `s` towards its viewer, `footprint` the width of its pixel's cone there.
fn reflected_radiance(s: ShadingInput, geometric_normal: vec3<f32>, footprint: f32) -> vec3<f32> {
    // A debug view shows the surface's own counts, not its reflections'.
    if frame.debug_view.x != DEBUG_VIEW_OFF {
        return vec3<f32>(0.0);
    }
    var weight = reflection_weight(s);
    var radiance = vec3<f32>(0.0);
    var surface = s;
    var normal = geometric_normal;
    var width = footprint;
    var spread = frame.ray_settings.z;
    // The first surface's position was rebuilt from a depth buffer or interpolated by the raster; hits
    // are computed from the ray itself, exact to rounding.
    var clearance = s.ray_clearance;
    for (var bounce = 0u; bounce < frame.ray_options.z; bounce += 1u) {
        if max(weight.x, max(weight.y, weight.z)) < 1e-4 {
            break;
        }
        let dir = mirror_direction(surface, normal);
        let origin = ray_offset_origin(surface.position, normal, clearance);
        clearance = 0.0;
        // The cone widens faster off rough surfaces: their reflections are blurrier.
        spread += surface.roughness * surface.roughness;
        // The traced radiance replaces the prefiltered environment that `shade` gave the surface for
        // the same share (`weight`), as much of it as the surface's occlusion let through: traced
        // rays see what occludes them.
        let replaced = environment_specular_radiance(environment_reflection_direction(surface), surface.roughness) * surface.occlusion;
        let hit = trace_closest(origin, dir, 3.0e38);
        if hit.triangle == RAY_NO_HIT {
            radiance += weight * (sky_radiance(dir) - replaced);
            break;
        }
        let instance = ray_instances[hit.instance];
        let tri = ray_triangles[hit.triangle];
        let draw = draws[ray_triangle_draw(instance, tri)];
        width += hit.t * spread;
        let across = perpendicular_pair(dir) * width;
        let ray = Ray(vec3<f32>(0.0), dir);
        let hit_surface = triangle_surface(draw, tri.triangle, origin, ray, Ray(across[0], dir), Ray(across[1], dir));
        let position = hit_surface.relative_position + origin;
        var hit_material = evaluate_material(materials[draw.material], hit_surface.frame, hit_surface.g, hit_surface.vertex_color, position, -dir);
        hit_material.ray_normal = hit_surface.geometric_normal;
        let hit_s = apply_decals(hit_material, hit_surface.dp);
        radiance += weight * (shade(hit_s, sun_visibility_traced(position, hit_surface.geometric_normal, 0.0)) - replaced);
        weight *= reflection_weight(hit_s);
        surface = hit_s;
        normal = hit_surface.geometric_normal;
    }
    return radiance;
}
