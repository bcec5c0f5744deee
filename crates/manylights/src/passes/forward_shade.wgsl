// Forward shading in the fragment stage, after the depth prepass (EQUAL depth test, so each pixel is
// shaded once): the same shading core as the visibility-buffer resolve — material, decals, lights —
// with the fragment stage's derivatives instead of analytic ones for texture and decal gradients, in
// the sun's ray-traced shadow and with ray-traced reflections when the frame has them. Where shading
// keeps per-pixel state (`restir`'s reservoirs), the entry points test depth before they run
// (`ShaderDesc::testing_depth_first`): a hidden fragment must not overwrite the visible one's.
// A full-screen triangle at the cleared depth fills the sky.
#include "shading/shade.wgsl"
#include "shading/camera.wgsl"
#include "passes/surface_raster.wgsl"
#include "shading/sun_shadow_mask.wgsl"
#include "$REFLECTIONS"

// The sun's visibility per pixel (`passes/ray_shadows.rs`), read when SUN_SHADOW_MASK is set.
@group(1) @binding(0) var sun_shadow_mask: texture_2d<f32>;

fn forward_radiance(in: ForwardVertex, front_facing: bool, g: UvGradients, dp: PositionGradients) -> vec3<f32> {
    let s = apply_decals(fragment_shading_surface(in, front_facing, g, dp), dp);
    var radiance = shade_pixel(s, sun_visibility(vec2<u32>(in.clip_position.xy)), vec2<u32>(in.clip_position.xy));
    if frame.ray_options.z > 0u {
        radiance += reflected_radiance(s, s.ray_normal, pixel_footprint(in.relative_position));
    }
    return radiance;
}

@fragment
fn forward_opaque(in: ForwardVertex, @builtin(front_facing) front_facing: bool) -> @location(0) vec4<f32> {
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    let dp = PositionGradients(dpdx(in.relative_position), dpdy(in.relative_position));
    return vec4<f32>(forward_radiance(in, front_facing, g, dp), 1.0);
}

@fragment
fn forward_masked(in: ForwardVertex, @builtin(front_facing) front_facing: bool) -> @location(0) vec4<f32> {
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    let dp = PositionGradients(dpdx(in.relative_position), dpdy(in.relative_position));
    if !forward_alpha_covers(in, g) {
        discard;
    }
    return vec4<f32>(forward_radiance(in, front_facing, g, dp), 1.0);
}

// A triangle covering the screen at depth 0, the cleared (farthest, reverse Z) depth: with an EQUAL
// test it reaches exactly the pixels no geometry covered.
@vertex
fn forward_sky_vertex(@builtin(vertex_index) index: u32) -> @builtin(position) @invariant vec4<f32> {
    let corner = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn forward_sky(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(sky_radiance(camera_ray(pixel.xy).dir), 1.0);
}
