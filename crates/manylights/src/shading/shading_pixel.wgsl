// The pixel whose opaque surface the shading core is lighting, for what is kept per pixel from frame
// to frame (`restir`'s reservoirs, `shading/direct/restir.wgsl`) and for the denoiser's samples;
// NO_PIXEL at ray hits and on transparent surfaces, which keep nothing and are not denoised. Set by
// `shade_pixel` (`shading/shade.wgsl`).
#include "shading/scene_bindings.wgsl"
#include "shading/shading_input.wgsl"
#include "shading/brdf.wgsl"
#include "shading/environment.wgsl"
#include "shading/octahedral.wgsl"

const NO_PIXEL: u32 = 0xffffffffu;

var<private> shading_pixel: vec2<u32> = vec2<u32>(NO_PIXEL);

// Sampled lighting (`restir`) at pixels' opaque surfaces goes to the denoiser (`passes/denoise/`)
// rather than into the radiance: `plan::FramePlan::denoises`.
override DENOISED_LIGHTING: bool = false;

// The pixel's sampled light so far, diffuse and specular, not yet divided by the albedos.
var<private> sampled_diffuse: vec3<f32>;
var<private> sampled_specular: vec3<f32>;

// Whether sampled light at the point being shaded goes to the denoiser.
fn denoises_sampled_light() -> bool {
    return DENOISED_LIGHTING && shading_pixel.x != NO_PIXEL;
}

// Sampled `radiance` from a light at `light` (world space): the radiance to add to the point's, which
// is none where the denoiser takes it, split into the BRDF's lobes.
fn add_sampled_light(s: ShadingInput, light: vec3<f32>, radiance: vec3<f32>) -> vec3<f32> {
    if !denoises_sampled_light() {
        return radiance;
    }
    let lobes = brdf_lobes_times_cosine(s, normalize(light - s.position));
    let sum = lobes.diffuse + lobes.specular;
    let diffuse = select(vec3<f32>(0.0), radiance * lobes.diffuse / sum, sum > vec3<f32>(0.0));
    sampled_diffuse += diffuse;
    sampled_specular += radiance - diffuse;
    return vec3<f32>(0.0);
}

// `light` divided by `albedo` where it reflects anything.
fn demodulate(light: vec3<f32>, albedo: vec3<f32>) -> vec3<f32> {
    return select(vec3<f32>(0.0), light / albedo, albedo > vec3<f32>(0.0));
}

// Writes the pixel's sample for the denoiser: its sampled light divided by the albedos as they are
// kept (8 bits a channel: the same quantised albedos multiply the denoised light back), and its
// surface, with its roughness beside the diffuse albedo. `shows_light` is false where a debug view replaces the radiance: no light then.
fn keep_denoise_sample(s: ShadingInput, shows_light: bool) {
    let albedo = pack4x8unorm(vec4<f32>(s.base_color * (1.0 - s.metallic), s.roughness));
    // The sheen's lobe is sampled with the specular one.
    let specular_albedo = pack4x8unorm(vec4<f32>(environment_specular_albedo(s) + environment_sheen_albedo(s), 0.0));
    let diffuse = demodulate(sampled_diffuse, unpack4x8unorm(albedo).rgb);
    let specular = demodulate(sampled_specular, unpack4x8unorm(specular_albedo).rgb);
    let none = vec3<f32>(0.0);
    denoise_samples[shading_pixel.y * u32(frame.viewport.x) + shading_pixel.x] = DenoiseSample(
        select(none, diffuse, shows_light),
        octahedral_pack(s.normal, 16u),
        select(none, specular, shows_light),
        albedo,
        s.position,
        specular_albedo,
    );
}
