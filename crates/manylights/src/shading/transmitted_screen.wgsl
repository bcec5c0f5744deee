// `$TRANSMITTED_LIGHT` for the transparent pass: the light behind a transmissive surface is read from
// the image of the opaque surfaces (`passes/transmission_background.rs`), where the refracted ray
// leaves the medium, from the mip level its roughness blurs it to (the Khronos sample viewer's
// screen-space transmission). Transparent surfaces behind it are not seen through it.
#include "shading/scene_bindings.wgsl"
#include "shading/shading_input.wgsl"

@group(1) @binding(0) var transmission_background: texture_2d<f32>;
@group(1) @binding(1) var transmission_sampler: sampler;

fn transmitted_light(s: ShadingInput, path: vec3<f32>) -> vec3<f32> {
    let clip = frame.clip_from_world * vec4<f32>(s.position + path, 1.0);
    let uv = clip.xy / max(clip.w, 1e-6) * vec2<f32>(0.5, -0.5) + 0.5;
    let size = vec2<f32>(textureDimensions(transmission_background));
    // Rough surfaces blur as much as they bend: none at an index of 1, fully from 1.5 up.
    let lod = log2(max(size.x, size.y)) * s.roughness * saturate(s.ior * 2.0 - 2.0);
    return textureSampleLevel(transmission_background, transmission_sampler, uv, lod).rgb;
}
