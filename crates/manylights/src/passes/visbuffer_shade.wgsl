// Visibility-buffer resolve and shading, in compute: per pixel, rebuild the surface from the triangle
// the raster pass recorded, evaluate its material and light it with the shading core; with
// ray-traced effects, in the sun's shadow from the ray-traced mask, plus what glossy surfaces reflect.
//
// Barycentrics come from intersecting the pixel's camera ray with the triangle's plane; the rays
// through the neighbouring pixels give their screen-space derivatives analytically, which select
// texture mips (no helper lanes or quad derivatives exist in compute); decals get the same from the
// position's derivatives.
#include "shading/pixel_surface.wgsl"
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
    let surface = pixel_surface(textureLoad(visibility, id.xy, 0).x, pixel);
    let s = surface.shading;
    var radiance = shade_pixel(s, sun_visibility(id.xy), id.xy);
    radiance += reflected_radiance(s, surface.triangle.geometric_normal, pixel_footprint(surface.triangle.relative_position));
    textureStore(hdr_output, id.xy, vec4<f32>(radiance, 1.0));
}
