// The denoised light back into the image: each pixel's filtered lobes times the albedos its sample
// was divided by, added to the HDR image by the blender (the pass draws one triangle over the image).
// Pixels without a surface have no light to add.
#include "passes/denoise/denoise_types.wgsl"

@group(1) @binding(0) var<storage, read> denoised: array<DenoiseLight>;

@vertex
fn denoise_compose_vertex(@builtin(vertex_index) vertex: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((vertex << 1u) & 2u), f32(vertex & 2u));
    return vec4<f32>(corner * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn denoise_compose(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let index = denoise_index(vec2<u32>(position.xy));
    let light = denoised[index];
    let sample = denoise_samples[index];
    return vec4<f32>(light.diffuse.rgb * unpack4x8unorm(sample.albedo).rgb + light.specular.rgb * unpack4x8unorm(sample.specular_albedo).rgb, 0.0);
}
