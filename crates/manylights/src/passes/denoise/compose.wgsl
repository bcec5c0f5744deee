// The denoised light back into the image: each pixel's filtered lobes times the albedos its sample
// was divided by, added to the HDR image as shading left it (a copy: the image is written here).
// Pixels without a surface have no light to add.
#include "passes/denoise/denoise_types.wgsl"

@group(1) @binding(0) var<storage, read> denoised: array<vec4<u32>>;
@group(1) @binding(1) var shaded: texture_2d<f32>;
@group(1) @binding(2) var hdr_output: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8)
fn denoise_compose(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= vec2<u32>(frame.viewport.xy)) {
        return;
    }
    let index = denoise_index(id.xy);
    let light = denoise_unpack_light(denoised[index]);
    let sample = denoise_samples[index];
    let added = light.diffuse.rgb * unpack4x8unorm(sample.albedo).rgb + light.specular.rgb * unpack4x8unorm(sample.specular_albedo).rgb;
    let shaded_radiance = textureLoad(shaded, id.xy, 0);
    textureStore(hdr_output, id.xy, vec4<f32>(shaded_radiance.rgb + added, shaded_radiance.a));
}
