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

// Tiles of 16 × 16 pixels, a lane per bin: a quarter of the flushes to the global histogram that
// 8 × 8 tiles make.
@compute @workgroup_size(16, 16)
fn exposure_histogram(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    atomicStore(&local_bins[local], 0u);
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
    let count = atomicLoad(&local_bins[local]);
    if count > 0u {
        atomicAdd(&histogram[local], count);
    }
}

// Counts below each bin (surfaces, background), then each bin's share of the metered pixels and of
// their log luminance, summed.
var<workgroup> counts_below: array<vec2<u32>, 128>;
var<workgroup> shares: array<vec2<f32>, 128>;

// A lane per bin: prefix sums and a sum over the workgroup instead of one lane's walk.
@compute @workgroup_size(128)
fn exposure_average(@builtin(local_invocation_index) b: u32) {
    let count = vec2<u32>(atomicLoad(&histogram[b]), atomicLoad(&histogram[HISTOGRAM_BINS + b]));
    atomicStore(&histogram[b], 0u);
    atomicStore(&histogram[HISTOGRAM_BINS + b], 0u);
    // Inclusive prefix sums of both halves (Hillis–Steele).
    counts_below[b] = count;
    for (var step = 1u; step < HISTOGRAM_BINS; step *= 2u) {
        workgroupBarrier();
        var earlier = vec2<u32>(0u);
        if b >= step {
            earlier = counts_below[b - step];
        }
        workgroupBarrier();
        counts_below[b] += earlier;
    }
    workgroupBarrier();
    let totals = counts_below[HISTOGRAM_BINS - 1u];
    let metered = select(0u, 1u, totals.x == 0u);
    let total = f32(totals[metered]);
    // The pixels from rank `low` to rank `high`, each bin's share of them at its centre.
    let low = total * LOW_PERCENTILE;
    let high = total * HIGH_PERCENTILE;
    let above = f32(counts_below[b][metered]);
    let below = above - f32(count[metered]);
    let inside = max(0.0, min(above, high) - max(below, low));
    shares[b] = vec2<f32>(inside * (MIN_LOG2_LUMINANCE + (f32(b) + 0.5) / BINS_PER_STOP), inside);
    for (var half = HISTOGRAM_BINS / 2u; half > 0u; half /= 2u) {
        workgroupBarrier();
        if b < half {
            shares[b] += shares[b + half];
        }
    }
    if b != 0u {
        return;
    }
    let log_sum = shares[0].x;
    let counted = shares[0].y;
    let measured = exposure_state.y != 0.0;
    // A black image gives nothing to measure: keep the exposure (1 if none was measured yet).
    var target_log = select(0.0, exposure_state.x, measured);
    if counted > 0.0 {
        target_log = log2(post.exposure.x) - log_sum / counted;
    }
    let rate = select(1.0, post.exposure.z, measured);
    exposure_state = vec4<f32>(mix(exposure_state.x, target_log, rate), 1.0, 0.0, 0.0);
}
