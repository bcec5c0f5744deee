// The deferred pipeline's G-buffer, written by `gbuffer_raster` and read by `deferred_shade`. The
// paper's 112 bits a pixel, plus emission and the glTF material extensions' parameters, which glTF
// materials have and the paper's scenes did not (packed in one target: wgpu allows 32 bytes a pixel,
// counting albedo as 8, and a compute pass 16 textures):
//   albedo              Rgba8UnormSrgb   base colour; alpha (linear): occlusion
//   normal              Rg16Float        octahedral shading normal (blendable, for deferred decals)
//   roughness_metallic  Rg8Unorm         perceptual roughness, metallic
//   material            Rgba32Uint       x: the dielectric's specular weight × F0 (√, 8 bits a
//                                        channel), the weight (7 bits) and whether it is unlit;
//                                        y, z: emitted radiance (half floats; the sign bit of
//                                        blue's says what w holds), the clear coat's strength
//                                        and perceptual roughness (8 bits each);
//                                        w: the clear coat's octahedral normal (16 + 16 bits),
//                                        or a sheen's colour (√, 8 bits a channel) and
//                                        roughness (8 bits); with both, the coat takes the
//                                        shading normal
//   depth               Depth32Float     (the frame's depth target)
// The surface is stored before decals: `deferred_shade` applies them, so bvh decals work here too;
// deferred decals (`deferred_decals.wgsl`) blend into albedo, normal and roughness-metallic instead
// (the material target is not theirs).

#include "shading/octahedral.wgsl"
#include "shading/shading_input.wgsl"

fn gbuffer_encode_normal(n: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(octahedral_encode(n), 0.0, 0.0);
}

fn gbuffer_decode_normal(texel: vec4<f32>) -> vec3<f32> {
    return octahedral_decode(texel.xy);
}

// The dielectric's reflectance as F = w·F0 + (w − w·F0)(1 − v·h)⁵ needs: w·F0 (square roots, so the
// 4 % of glTF's default material is exact in 8 bits), w, and the unlit flag.
fn gbuffer_encode_specular(s: ShadingInput) -> u32 {
    let weighted = sqrt(saturate(s.specular_weight * s.dielectric_f0));
    let bytes = vec3<u32>(round(weighted * 255.0));
    let weight = u32(round(saturate(s.specular_weight) * 127.0));
    return bytes.x | (bytes.y << 8u) | (bytes.z << 16u) | (weight << 24u) | select(0u, 1u << 31u, s.unlit);
}

// Fills `s`'s dielectric reflectance and unlit flag from `gbuffer_encode_specular`'s word.
fn gbuffer_decode_specular(word: u32, s: ptr<function, ShadingInput>) {
    let weighted = vec3<f32>(vec3<u32>(word, word >> 8u, word >> 16u) & vec3<u32>(0xffu)) / 255.0;
    let weight = f32((word >> 24u) & 0x7fu) / 127.0;
    (*s).specular_weight = weight;
    (*s).dielectric_f0 = select(vec3<f32>(0.0), weighted * weighted / weight, weight > 0.0);
    (*s).unlit = (word >> 31u) != 0u;
}

// Set in the material texel's z (the sign bit of the emission's blue half float, which is never
// negative) where w holds a sheen.
const GBUFFER_SHEEN: u32 = 0x8000u;

// The material texel: specular (`gbuffer_encode_specular`), emission, the clear coat and a sheen.
fn gbuffer_encode_material(s: ShadingInput) -> vec4<u32> {
    let coat = vec2<u32>(round(saturate(vec2<f32>(s.clearcoat, s.clearcoat_roughness)) * 255.0));
    let emission_b = pack2x16float(vec2<f32>(s.emissive.b, 0.0)) & 0x7fffu;
    var z = emission_b | (coat.x << 16u) | (coat.y << 24u);
    var w = octahedral_pack(s.clearcoat_normal, 16u);
    if has_sheen(s) {
        z |= GBUFFER_SHEEN;
        w = pack4x8unorm(vec4<f32>(sqrt(saturate(s.sheen_color)), saturate(s.sheen_roughness)));
    }
    return vec4<u32>(gbuffer_encode_specular(s), pack2x16float(s.emissive.rg), z, w);
}

// Fills `s`'s emission, dielectric reflectance, unlit flag, clear coat and sheen from the material
// texel; `s.normal` must be decoded already.
fn gbuffer_decode_material(texel: vec4<u32>, s: ptr<function, ShadingInput>) {
    gbuffer_decode_specular(texel.x, s);
    (*s).emissive = vec3<f32>(unpack2x16float(texel.y), unpack2x16float(texel.z & 0x7fffu).x);
    (*s).clearcoat = f32((texel.z >> 16u) & 0xffu) / 255.0;
    (*s).clearcoat_roughness = f32(texel.z >> 24u) / 255.0;
    if (texel.z & GBUFFER_SHEEN) != 0u {
        let sheen = unpack4x8unorm(texel.w);
        (*s).sheen_color = sheen.rgb * sheen.rgb;
        (*s).sheen_roughness = sheen.a;
        (*s).clearcoat_normal = (*s).normal;
    } else {
        (*s).clearcoat_normal = octahedral_unpack(texel.w, 16u);
    }
}
