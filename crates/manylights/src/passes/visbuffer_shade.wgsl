// Visibility-buffer resolve and shading, in compute: per pixel, rebuild the surface from the triangle
// the raster pass recorded, evaluate its material and light it with the shading core; with
// ray-traced effects, in the sun's shadow from the ray-traced mask, plus what glossy surfaces reflect.
//
// Barycentrics come from intersecting the pixel's camera ray with the triangle's plane; the rays
// through the neighbouring pixels give their screen-space derivatives analytically, which select
// texture mips (no helper lanes or quad derivatives exist in compute); decals get the same from the
// position's derivatives.
#include "shading/shade.wgsl"
#include "shading/triangle_surface.wgsl"
#include "shading/draws.wgsl"
#include "shading/sun_shadow_mask.wgsl"
#include "$REFLECTIONS"

@group(1) @binding(0) var visibility: texture_2d<u32>;
@group(1) @binding(1) var hdr_output: texture_storage_2d<rgba32float, write>;
// Reverse Z, cleared to 0: a pixel no triangle covered keeps 0, and its id is stale (ids are not cleared).
@group(1) @binding(2) var depth: texture_depth_2d;
// The sun's visibility per pixel (`passes/ray_shadows.rs`), read when SUN_SHADOW_MASK is set.
@group(1) @binding(3) var sun_shadow_mask: texture_2d<f32>;

@compute @workgroup_size(8, 8)
fn visbuffer_shade(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let pixel = vec2<f32>(id.xy) + 0.5;
    let ray = camera_ray(pixel);
    if textureLoad(depth, id.xy, 0) == 0.0 {
        textureStore(hdr_output, id.xy, vec4<f32>(sky_radiance(ray.dir), 1.0));
        return;
    }
    let visibility_id = textureLoad(visibility, id.xy, 0).x;

    let draw = draws[find_draw(visibility_id)];
    let eye = frame.world_from_view[3].xyz;
    let surface = triangle_surface(
        draw,
        visibility_id - draw.first_visibility_id,
        eye,
        ray,
        camera_ray(pixel + vec2<f32>(1.0, 0.0)),
        camera_ray(pixel + vec2<f32>(0.0, 1.0)),
    );
    let position = surface.relative_position + eye;
    var material_surface = evaluate_material(materials[draw.material], surface.frame, surface.g, surface.vertex_color, position, -ray.dir);
    material_surface.ray_normal = surface.geometric_normal;
    material_surface.ray_clearance = surface_clearance(surface.relative_position);
    let s = apply_decals(material_surface, surface.dp);
    var radiance = shade_pixel(s, sun_visibility(id.xy), id.xy);
    radiance += reflected_radiance(s, surface.geometric_normal, pixel_footprint(surface.relative_position));
    textureStore(hdr_output, id.xy, vec4<f32>(radiance, 1.0));
}
