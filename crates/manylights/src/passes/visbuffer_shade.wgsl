// Visibility-buffer resolve and shading, in compute: per pixel, rebuild the surface from the triangle
// the raster pass recorded, evaluate its material and light it with the shading core.
//
// Barycentrics come from intersecting the pixel's camera ray with the triangle's plane; the rays
// through the neighbouring pixels give their screen-space derivatives analytically, which select
// texture mips (no helper lanes or quad derivatives exist in compute); decals get the same from the
// position's derivatives.
#include "shading/shade.wgsl"
#include "shading/material.wgsl"
#include "shading/camera.wgsl"

@group(1) @binding(0) var visibility: texture_2d<u32>;
@group(1) @binding(1) var hdr_output: texture_storage_2d<rgba32float, write>;
// Reverse Z, cleared to 0: a pixel no triangle covered keeps 0, and its id is stale (ids are not cleared).
@group(1) @binding(2) var depth: texture_depth_2d;

// Barycentrics (b0, b1, b2) where the ray meets the triangle's plane (Möller–Trumbore without the
// inside test: neighbouring pixels may fall outside the triangle, which is what derivatives need).
fn ray_plane_barycentrics(ray: Ray, p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>) -> vec3<f32> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pvec = cross(ray.dir, e2);
    let det = dot(e1, pvec);
    let inv_det = 1.0 / select(det, 1e-20, abs(det) < 1e-20);
    let tvec = ray.origin - p0;
    let b1 = dot(tvec, pvec) * inv_det;
    let b2 = dot(ray.dir, cross(tvec, e1)) * inv_det;
    return vec3<f32>(1.0 - b1 - b2, b1, b2);
}

fn interpolate2(b: vec3<f32>, a0: vec2<f32>, a1: vec2<f32>, a2: vec2<f32>) -> vec2<f32> {
    return a0 * b.x + a1 * b.y + a2 * b.z;
}

fn interpolate3(b: vec3<f32>, a0: vec3<f32>, a1: vec3<f32>, a2: vec3<f32>) -> vec3<f32> {
    return a0 * b.x + a1 * b.y + a2 * b.z;
}

// The draw whose visibility ids contain `id`: the last one starting at or before it.
fn find_draw(id: u32) -> u32 {
    var low = 0u;
    var high = arrayLength(&draws) - 1u;
    while low < high {
        let mid = (low + high + 1u) / 2u;
        if draws[mid].first_visibility_id <= id {
            low = mid;
        } else {
            high = mid - 1u;
        }
    }
    return low;
}

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
    let first = draw.first_index + (visibility_id - draw.first_visibility_id) * 3u;
    let v0 = vertices[draw.base_vertex + indices[first]];
    let v1 = vertices[draw.base_vertex + indices[first + 1u]];
    let v2 = vertices[draw.base_vertex + indices[first + 2u]];
    // Camera-relative positions, like the rays.
    let eye = frame.world_from_view[3].xyz;
    let p0 = (draw.world_from_local * vec4<f32>(v0.position, 1.0)).xyz - eye;
    let p1 = (draw.world_from_local * vec4<f32>(v1.position, 1.0)).xyz - eye;
    let p2 = (draw.world_from_local * vec4<f32>(v2.position, 1.0)).xyz - eye;

    let b = ray_plane_barycentrics(ray, p0, p1, p2);
    let b_dx = ray_plane_barycentrics(camera_ray(pixel + vec2<f32>(1.0, 0.0)), p0, p1, p2);
    let b_dy = ray_plane_barycentrics(camera_ray(pixel + vec2<f32>(0.0, 1.0)), p0, p1, p2);

    let uv0 = vec2<f32>(v0.u, v0.v);
    let uv1 = vec2<f32>(v1.u, v1.v);
    let uv2 = vec2<f32>(v2.u, v2.v);
    let uv = interpolate2(b, uv0, uv1, uv2);
    let g = UvGradients(uv, interpolate2(b_dx, uv0, uv1, uv2) - uv, interpolate2(b_dy, uv0, uv1, uv2) - uv);

    let relative_position = interpolate3(b, p0, p1, p2);
    let position = relative_position + eye;
    let dp = PositionGradients(interpolate3(b_dx, p0, p1, p2) - relative_position, interpolate3(b_dy, p0, p1, p2) - relative_position);
    let view_dir = -ray.dir;
    var surface: SurfaceFrame;
    surface.normal = normalize(world_normal(draw, interpolate3(b, v0.normal, v1.normal, v2.normal)));
    surface.tangent = world_direction(draw, interpolate3(b, v0.tangent.xyz, v1.tangent.xyz, v2.tangent.xyz));
    surface.bitangent_sign = v0.tangent.w * sign(draw.normal_from_local[0].w);
    // Back faces only reach here on double-sided materials: light them as seen from the viewer's side.
    // Mirrored instances reverse the winding, hence the handedness sign.
    let geometric_normal = cross(p1 - p0, p2 - p0) * sign(draw.normal_from_local[0].w);
    if dot(geometric_normal, view_dir) < 0.0 {
        // The whole tangent frame turns over, so normal maps bump the same way on both sides.
        surface.normal = -surface.normal;
        surface.tangent = -surface.tangent;
        surface.bitangent_sign = -surface.bitangent_sign;
    }

    let material = materials[draw.material];
    let s = apply_decals(evaluate_material(material, surface, g, position, view_dir), dp);
    textureStore(hdr_output, id.xy, vec4<f32>(shade(s), 1.0));
}
