// Deferred lighting in compute: per pixel, the surface from the G-buffer (`passes/gbuffer.wgsl`) and
// the depth, then decals and lights through the shading core, exactly as the visibility-buffer
// resolve hands its surface over, in the sun's ray-traced shadow and with ray-traced reflections when
// the frame has them. Decal texture gradients come from the neighbouring pixels' rays
// meeting the surface's tangent plane (`gbuffer_surface.wgsl`).
#include "shading/shade.wgsl"
#include "passes/gbuffer.wgsl"
#include "passes/gbuffer_surface.wgsl"
#include "shading/depth_normal.wgsl"
#include "shading/sun_shadow_mask.wgsl"
#include "$REFLECTIONS"

@group(1) @binding(0) var depth: texture_depth_2d;
@group(1) @binding(1) var albedo: texture_2d<f32>;
@group(1) @binding(2) var normals: texture_2d<f32>;
@group(1) @binding(3) var roughness_metallic: texture_2d<f32>;
@group(1) @binding(4) var material: texture_2d<u32>;
@group(1) @binding(5) var hdr_output: texture_storage_2d<rgba32float, write>;
// The sun's visibility per pixel (`passes/ray_shadows.rs`), read when SUN_SHADOW_MASK is set.
@group(1) @binding(6) var sun_shadow_mask: texture_2d<f32>;

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
    let relative_position = depth_relative_position(pixel, z);

    var s: ShadingInput;
    s.position = relative_position + frame.world_from_view[3].xyz;
    s.normal = gbuffer_decode_normal(textureLoad(normals, id.xy, 0));
    s.view_dir = -ray.dir;
    let albedo_occlusion = textureLoad(albedo, id.xy, 0);
    s.base_color = albedo_occlusion.rgb;
    s.occlusion = albedo_occlusion.a;
    s.alpha = 1.0;
    let rm = textureLoad(roughness_metallic, id.xy, 0);
    s.roughness = rm.x;
    s.metallic = rm.y;
    gbuffer_decode_material(textureLoad(material, id.xy, 0), &s);
    // Rays leave along the geometric normal, rebuilt from depth only for frames that trace from here.
    s.ray_normal = s.normal;
    if frame.ray_options.z > 0u || frame.ray_options.w > 0u {
        s.ray_normal = depth_geometric_normal(depth, id.xy, relative_position, z);
    }
    s.ray_clearance = surface_clearance(relative_position);

    let dp = gbuffer_position_gradients(pixel, relative_position, s.normal);
    let decaled = apply_decals(s, dp);
    var radiance = shade_pixel(decaled, sun_visibility(id.xy), id.xy);
    if frame.ray_options.z > 0u {
        radiance += reflected_radiance(decaled, s.ray_normal, pixel_footprint(relative_position));
    }
    textureStore(hdr_output, id.xy, vec4<f32>(radiance, 1.0));
}
