// The deferred pipeline's G-buffer, written by `gbuffer_raster` and read by `deferred_shade`. The
// paper's 112 bits a pixel, plus emission, which glTF materials have and the paper's scenes did not:
//   albedo              Rgba8UnormSrgb   base colour (alpha unused)
//   normal              Rg16Float        octahedral shading normal (blendable, for deferred decals)
//   roughness_metallic  Rg8Unorm         perceptual roughness, metallic
//   depth               Depth32Float     (the frame's depth target)
//   emission            Rgba16Float      emitted radiance (not touched by decals)
// The surface is stored before decals: `deferred_shade` applies them, so bvh decals work here too;
// deferred decals (`deferred_decals.wgsl`) blend into albedo, normal and roughness-metallic instead.

#include "shading/octahedral.wgsl"

fn gbuffer_encode_normal(n: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(octahedral_encode(n), 0.0, 0.0);
}

fn gbuffer_decode_normal(texel: vec4<f32>) -> vec3<f32> {
    return octahedral_decode(texel.xy);
}
