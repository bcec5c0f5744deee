// Deferred lighting in compute: per pixel, the surface from the G-buffer (`passes/gbuffer.wgsl`) and
// the depth, then decals and lights through the shading core, exactly as the visibility-buffer
// resolve hands its surface over. Decal texture gradients come from the neighbouring pixels' rays
// meeting the surface's tangent plane (the G-buffer keeps no triangle).
#include "shading/shade.wgsl"
#include "shading/camera.wgsl"
#include "passes/gbuffer.wgsl"

@group(1) @binding(0) var depth: texture_depth_2d;
@group(1) @binding(1) var albedo: texture_2d<f32>;
@group(1) @binding(2) var normals: texture_2d<u32>;
@group(1) @binding(3) var roughness_metallic: texture_2d<f32>;
@group(1) @binding(4) var emission: texture_2d<f32>;
@group(1) @binding(5) var hdr_output: texture_storage_2d<rgba32float, write>;

// Where a ray meets the plane through `point` with normal `n` (all camera-relative).
fn ray_plane_point(ray: Ray, point: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let facing = dot(ray.dir, n);
    let t = dot(point - ray.origin, n) / select(facing, 1e-20, abs(facing) < 1e-20);
    return ray.origin + ray.dir * t;
}

@compute @workgroup_size(8, 8)
fn deferred_shade(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let pixel = vec2<f32>(id.xy) + 0.5;
    let ray = camera_ray(pixel);
    let z = textureLoad(depth, id.xy, 0);
    if z == 0.0 {
        textureStore(hdr_output, id.xy, vec4<f32>(sky_radiance(ray.dir), 1.0));
        return;
    }
    // The pixel's point at its depth, camera-relative like the rays.
    let ndc = vec2<f32>(pixel.x * frame.viewport.z * 2.0 - 1.0, 1.0 - pixel.y * frame.viewport.w * 2.0);
    let view = frame.view_from_clip * vec4<f32>(ndc, z, 1.0);
    let world_from_view = mat3x3<f32>(frame.world_from_view[0].xyz, frame.world_from_view[1].xyz, frame.world_from_view[2].xyz);
    let relative_position = world_from_view * (view.xyz / view.w);

    var s: ShadingInput;
    s.position = relative_position + frame.world_from_view[3].xyz;
    s.normal = gbuffer_decode_normal(textureLoad(normals, id.xy, 0).x);
    s.view_dir = -ray.dir;
    s.base_color = textureLoad(albedo, id.xy, 0).rgb;
    s.alpha = 1.0;
    let rm = textureLoad(roughness_metallic, id.xy, 0);
    s.roughness = rm.x;
    s.metallic = rm.y;
    s.emissive = textureLoad(emission, id.xy, 0).rgb;

    let dp = PositionGradients(
        ray_plane_point(camera_ray(pixel + vec2<f32>(1.0, 0.0)), relative_position, s.normal) - relative_position,
        ray_plane_point(camera_ray(pixel + vec2<f32>(0.0, 1.0)), relative_position, s.normal) - relative_position,
    );
    textureStore(hdr_output, id.xy, vec4<f32>(shade(apply_decals(s, dp)), 1.0));
}
