// Auto exposure from the image's luminance histogram. `exposure_histogram` counts pixels into 128
// bins of log2 luminance, a quarter stop each from 2⁻¹⁶ to 2¹⁶ (black pixels are left out), surfaces
// and background (depth at the far plane: the sky, an environment or the void of the uniform
// ambient) apart. `exposure_average` meters the surfaces, or the background where no surface is in
// view — so a model on an empty background is exposed for the model, whatever units its lights are
// in — taking the mean log luminance of the pixels between the 10th and the 90th percentile, so a
// few lamps or a dark corner do not swing it. It sets the exposure that maps it to the key (middle
// grey × 2^compensation), moving from the previous frame's exposure by `post.exposure.z` (1: at
// once), and clears the histogram for the next frame.
#include "shading/scene_bindings.wgsl"
#include "post/post_types.wgsl"

@group(1) @binding(0) var<uniform> post: PostUniforms;
@group(1) @binding(1) var color_input: texture_2d<f32>;
// Bins 0–127: surfaces; 128–255: background.
@group(1) @binding(2) var<storage, read_write> histogram: array<atomic<u32>, 256>;
// x: log2 of the exposure in use (read by `tonemap`); y: 1 once it has been measured.
@group(1) @binding(3) var<storage, read_write> exposure_state: vec4<f32>;
@group(1) @binding(4) var depth: texture_depth_2d;

const HISTOGRAM_BINS: u32 = 128u;
const MIN_LOG2_LUMINANCE: f32 = -16.0;
const BINS_PER_STOP: f32 = 4.0;
const LOW_PERCENTILE: f32 = 0.1;
const HIGH_PERCENTILE: f32 = 0.9;

var<workgroup> local_bins: array<atomic<u32>, 256>;

@compute @workgroup_size(8, 8)
fn exposure_histogram(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    for (var b = local; b < 2u * HISTOGRAM_BINS; b += 64u) {
        atomicStore(&local_bins[b], 0u);
    }
    workgroupBarrier();
    if all(id.xy < vec2<u32>(frame.viewport.xy)) {
        let luminance = dot(textureLoad(color_input, id.xy, 0).rgb, vec3<f32>(0.2126, 0.7152, 0.0722));
        let bin = (log2(luminance) - MIN_LOG2_LUMINANCE) * BINS_PER_STOP;
        if luminance > 0.0 && bin >= 0.0 {
            let background = select(0u, HISTOGRAM_BINS, textureLoad(depth, id.xy, 0) == 0.0);
            atomicAdd(&local_bins[background + min(u32(bin), HISTOGRAM_BINS - 1u)], 1u);
        }
    }
    workgroupBarrier();
    for (var b = local; b < 2u * HISTOGRAM_BINS; b += 64u) {
        let count = atomicLoad(&local_bins[b]);
        if count > 0u {
            atomicAdd(&histogram[b], count);
        }
    }
}

@compute @workgroup_size(1)
fn exposure_average() {
    var surfaces = 0.0;
    var background = 0.0;
    for (var b = 0u; b < HISTOGRAM_BINS; b += 1u) {
        surfaces += f32(atomicLoad(&histogram[b]));
        background += f32(atomicLoad(&histogram[HISTOGRAM_BINS + b]));
    }
    let first = select(0u, HISTOGRAM_BINS, surfaces == 0.0);
    let total = select(surfaces, background, surfaces == 0.0);
    // The pixels from rank `low` to rank `high`, each bin's share of them at its centre.
    let low = total * LOW_PERCENTILE;
    let high = total * HIGH_PERCENTILE;
    var below = 0.0;
    var log_sum = 0.0;
    var counted = 0.0;
    for (var b = 0u; b < HISTOGRAM_BINS; b += 1u) {
        let count = f32(atomicLoad(&histogram[first + b]));
        let inside = max(0.0, min(below + count, high) - max(below, low));
        log_sum += inside * (MIN_LOG2_LUMINANCE + (f32(b) + 0.5) / BINS_PER_STOP);
        counted += inside;
        below += count;
    }
    for (var b = 0u; b < 2u * HISTOGRAM_BINS; b += 1u) {
        atomicStore(&histogram[b], 0u);
    }
    let measured = exposure_state.y != 0.0;
    // A black image gives nothing to measure: keep the exposure (1 if none was measured yet).
    var target_log = select(0.0, exposure_state.x, measured);
    if counted > 0.0 {
        target_log = log2(post.exposure.x) - log_sum / counted;
    }
    let rate = select(1.0, post.exposure.z, measured);
    exposure_state = vec4<f32>(mix(exposure_state.x, target_log, rate), 1.0, 0.0, 0.0);
}
