// Deferred lighting in compute: per pixel, the surface from the G-buffer (`passes/gbuffer.wgsl`) and
// the depth, then decals and lights through the shading core, exactly as the visibility-buffer
// resolve hands its surface over. Decal texture gradients come from the neighbouring pixels' rays
// meeting the surface's tangent plane (`gbuffer_surface.wgsl`).
#include "shading/shade.wgsl"
#include "passes/gbuffer.wgsl"
#include "passes/gbuffer_surface.wgsl"

@group(1) @binding(0) var depth: texture_depth_2d;
@group(1) @binding(1) var albedo: texture_2d<f32>;
@group(1) @binding(2) var normals: texture_2d<f32>;
@group(1) @binding(3) var roughness_metallic: texture_2d<f32>;
@group(1) @binding(4) var emission: texture_2d<f32>;
@group(1) @binding(5) var hdr_output: texture_storage_2d<rgba32float, write>;

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
    let relative_position = gbuffer_relative_position(pixel, z);

    var s: ShadingInput;
    s.position = relative_position + frame.world_from_view[3].xyz;
    s.normal = gbuffer_decode_normal(textureLoad(normals, id.xy, 0));
    s.view_dir = -ray.dir;
    s.base_color = textureLoad(albedo, id.xy, 0).rgb;
    s.alpha = 1.0;
    let rm = textureLoad(roughness_metallic, id.xy, 0);
    s.roughness = rm.x;
    s.metallic = rm.y;
    s.emissive = textureLoad(emission, id.xy, 0).rgb;

    let dp = gbuffer_position_gradients(pixel, relative_position, s.normal);
    textureStore(hdr_output, id.xy, vec4<f32>(shade(apply_decals(s, dp)), 1.0));
}
