// The deferred pipeline's G-buffer, written by `gbuffer_raster` and read by `deferred_shade`. The
// paper's 112 bits a pixel, plus emission, which glTF materials have and the paper's scenes did not:
//   albedo              Rgba8UnormSrgb   base colour (alpha unused)
//   normal              Rg16Float        octahedral shading normal (blendable, for deferred decals)
//   roughness_metallic  Rg8Unorm         perceptual roughness, metallic
//   depth               Depth32Float     (the frame's depth target)
//   emission            Rgba16Float      emitted radiance (not touched by decals)
// The surface is stored before decals: `deferred_shade` applies them, so bvh decals work here too;
// deferred decals (`deferred_decals.wgsl`) blend into albedo, normal and roughness-metallic instead.

// Octahedral encoding of a unit vector into [-1, 1]² (Cigolle et al. 2014).
fn octahedral_encode(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if n.z >= 0.0 {
        return p;
    }
    return (1.0 - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
}

fn octahedral_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = saturate(-n.z);
    n = vec3<f32>(n.xy + select(vec2<f32>(t), vec2<f32>(-t), n.xy >= vec2<f32>(0.0)), n.z);
    return normalize(n);
}

fn gbuffer_encode_normal(n: vec3<f32>) -> vec4<f32> {
    return vec4<f32>(octahedral_encode(n), 0.0, 0.0);
}

fn gbuffer_decode_normal(texel: vec4<f32>) -> vec3<f32> {
    return octahedral_decode(texel.xy);
}
