// One step of the denoiser's edge-avoiding à-trous wavelet filter (after SVGF, Schied et al. 2017;
// Dammertz et al. 2010): a 3×3 kernel (¼, ½, ¼ each way) whose taps lie `step` pixels apart (1, 2, 4,
// 8 over the steps), each tap weighed by its surface (`denoise_surface_terms`) and, per lobe, by how
// far its luminance lies from the pixel's in units of the pixel's standard deviation (its variance
// prefiltered over 3×3 at the first step), so that noise is smoothed where the variance says it is
// noise and edges in the light stay. Variance is filtered with the squared weights. Specular light
// spreads over fewer pixels the smoother the surface (`denoise_specular_reach`): a glossy highlight
// is small. Unlike SVGF, no step's result feeds the next frame's history: the history stays the
// unblurred temporal mean, which converges to the pixel's own light under a still camera (measured:
// FLIP after 16 still frames 0.115 against 0.140 with SVGF's feedback; benchmarks/LOG.md, topic 9).
// SVGF's 5×5 kernel over five steps cost 2.5 times as much for the same error.
#include "passes/denoise/denoise_types.wgsl"

@group(1) @binding(0) var<storage, read> input: array<vec4<u32>>;
@group(1) @binding(1) var<storage, read_write> output: array<vec4<u32>>;
// x: the step between taps in pixels.
@group(1) @binding(2) var<uniform> filter_step: vec4<u32>;
@group(1) @binding(3) var<storage, read> guides: array<vec4<u32>>;

// SVGF's σ_l: luminance differences of this many standard deviations weigh 1/e.
const DENOISE_LUMINANCE_SIGMA: f32 = 2.0;

fn denoise_kernel(offset: i32) -> f32 {
    return select(0.25, 0.5, offset == 0);
}

// The lobes' variance around the pixel, over 3×3 with a Gaussian's weights.
fn denoise_local_variance(pixel: vec2<i32>, size: vec2<i32>) -> vec2<f32> {
    var variance = vec2<f32>(0.0);
    for (var dy = -1; dy <= 1; dy += 1) {
        for (var dx = -1; dx <= 1; dx += 1) {
            let q = clamp(pixel + vec2<i32>(dx, dy), vec2<i32>(0), size - 1);
            let light = denoise_unpack_light(input[denoise_index(vec2<u32>(q))]);
            let w = select(0.5, 1.0, dx == 0) * select(0.5, 1.0, dy == 0) / 4.0;
            variance += w * vec2<f32>(light.diffuse.w, light.specular.w);
        }
    }
    return variance;
}

// How far, in pixels, specular light may spread at a surface of perceptual roughness `roughness`:
// the Gaussian width of the extra weight its taps get, from a pixel for mirrors to 64 for the roughest.
fn denoise_specular_reach(roughness: f32) -> f32 {
    return 1.0 + 64.0 * roughness * roughness;
}

@compute @workgroup_size(8, 8)
fn denoise_filter(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<i32>(frame.viewport.xy);
    let pixel = vec2<i32>(id.xy);
    if any(pixel >= size) {
        return;
    }
    let index = denoise_index(id.xy);
    let guide = guides[index];
    if !denoise_guide_has_surface(guide) {
        output[index] = input[index];
        return;
    }
    let own = denoise_unpack_light(input[index]);
    let step = i32(filter_step.x);
    let position = bitcast<vec3<f32>>(guide.xyz);
    let normal = denoise_guide_normal(guide);
    let footprint = denoise_footprint(position);
    // The first step smooths the variance over 3×3 (SVGF's prefilter); later ones read the variance
    // the step before filtered.
    var variance = vec2<f32>(own.diffuse.w, own.specular.w);
    if step == 1 {
        variance = denoise_local_variance(pixel, size);
    }
    let deviation = sqrt(variance);
    let luminance_scale = 1.0 / (DENOISE_LUMINANCE_SIGMA * deviation + 1e-6);
    let own_luminance = vec2<f32>(dot(own.diffuse.rgb, DENOISE_LUMINANCE), dot(own.specular.rgb, DENOISE_LUMINANCE));
    let reach = denoise_specular_reach(unpack4x8unorm(denoise_samples[index].albedo).a);
    let centre = denoise_kernel(0) * denoise_kernel(0);
    var diffuse = centre * vec4<f32>(own.diffuse.rgb, centre * own.diffuse.w);
    var specular = centre * vec4<f32>(own.specular.rgb, centre * own.specular.w);
    var weights = vec2<f32>(centre);
    for (var dy = -1; dy <= 1; dy += 1) {
        for (var dx = -1; dx <= 1; dx += 1) {
            let q = pixel + vec2<i32>(dx, dy) * step;
            if (dx == 0 && dy == 0) || any(q < vec2<i32>(0)) || any(q >= size) {
                continue;
            }
            let other = denoise_index(vec2<u32>(q));
            let other_guide = guides[other];
            if !denoise_guide_has_surface(other_guide) {
                continue;
            }
            let light = denoise_unpack_light(input[other]);
            let apart = f32(step) * length(vec2<f32>(f32(dx), f32(dy)));
            let surface = denoise_surface_terms(normal, position, footprint, other_guide, apart);
            let luminance = vec2<f32>(dot(light.diffuse.rgb, DENOISE_LUMINANCE), dot(light.specular.rgb, DENOISE_LUMINANCE));
            let glossy = vec2<f32>(0.0, 0.5 * apart * apart / (reach * reach));
            let exponent = surface.y + glossy + abs(luminance - own_luminance) * luminance_scale;
            let w = denoise_kernel(dx) * denoise_kernel(dy) * surface.x * exp(-exponent);
            diffuse += w.x * vec4<f32>(light.diffuse.rgb, w.x * light.diffuse.w);
            specular += w.y * vec4<f32>(light.specular.rgb, w.y * light.specular.w);
            weights += w;
        }
    }
    let filtered = DenoiseLight(
        vec4<f32>(diffuse.rgb / weights.x, diffuse.w / (weights.x * weights.x)),
        vec4<f32>(specular.rgb / weights.y, specular.w / (weights.y * weights.y)),
    );
    output[index] = denoise_pack_light(filtered);
}
