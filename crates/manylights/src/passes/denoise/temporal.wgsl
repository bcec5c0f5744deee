// The denoiser's temporal accumulation (SVGF, Schied et al. 2017): each pixel's sampled light, per
// lobe, joins what its surface accumulated in earlier frames, found where the previous camera saw the
// surface (`frame.previous_clip_from_world`; an animated instance's surface where it was then,
// `previous_surface_position`) and bilinearly resampled from those of the four nearest
// pixels that saw the same surface (normals within about 25°, positions on the pixel's plane within a
// pixel's footprint or 1 % of the distance), clamped to the frame's samples around the pixel. An
// exponential moving average with weight 1/n over the
// n frames accumulated, n at most DENOISE_MAX_HISTORY, gives each lobe's light and luminance moments;
// a disocclusion starts afresh. Output: the history of this frame (for the next) and each lobe's light
// with its variance from the moments, for the filters, and the pixel's surface as they read it.
#include "passes/denoise/denoise_types.wgsl"

@group(1) @binding(0) var depth: texture_depth_2d;
@group(1) @binding(1) var<storage, read> previous: array<DenoiseHistory>;
@group(1) @binding(2) var<storage, read_write> history: array<DenoiseHistory>;
@group(1) @binding(3) var<storage, read_write> integrated: array<vec4<u32>>;
@group(1) @binding(4) var<storage, read_write> guides: array<vec4<u32>>;

// The most frames averaged: a still surface's light converges like 1/n up to this, then follows
// changes within about as many frames.
const DENOISE_MAX_HISTORY: u32 = 32u;
// The most frames averaged on an animated instance's surface, whose light changes as it moves.
const DENOISE_MOVING_HISTORY: u32 = 4u;
const DENOISE_MIN_NORMAL_COSINE: f32 = 0.9;
const DENOISE_MAX_PLANE_DISTANCE: f32 = 0.01;
// History is clamped, channel by channel, to this many standard deviations around the mean of the
// frame's samples in the 3×3 pixels around: light that moved away (a highlight sliding over a glossy
// floor as the camera moves, a light switched off) leaves no trail, while noise of the samples
// themselves, which the clamp's width follows, leaves the history alone.
const DENOISE_CLAMP_DEVIATIONS: f32 = 3.0;
const DENOISE_MOVING_CLAMP_DEVIATIONS: f32 = 1.0;

// The mean and standard deviation of the frame's samples of each lobe, channel by channel, over the
// 3×3 pixels around `pixel` that show a surface.
struct DenoiseNeighbourhood {
    diffuse_mean: vec3<f32>,
    diffuse_deviation: vec3<f32>,
    specular_mean: vec3<f32>,
    specular_deviation: vec3<f32>,
}

fn denoise_neighbourhood(pixel: vec2<i32>, size: vec2<i32>) -> DenoiseNeighbourhood {
    var diffuse = vec3<f32>(0.0);
    var diffuse_square = vec3<f32>(0.0);
    var specular = vec3<f32>(0.0);
    var specular_square = vec3<f32>(0.0);
    var count = 0.0;
    for (var dy = -1; dy <= 1; dy += 1) {
        for (var dx = -1; dx <= 1; dx += 1) {
            let q = pixel + vec2<i32>(dx, dy);
            if any(q < vec2<i32>(0)) || any(q >= size) || textureLoad(depth, q, 0) == 0.0 {
                continue;
            }
            let other = denoise_index(vec2<u32>(q));
            let sample_diffuse = denoise_samples[other].diffuse;
            let sample_specular = denoise_samples[other].specular;
            diffuse += sample_diffuse;
            diffuse_square += sample_diffuse * sample_diffuse;
            specular += sample_specular;
            specular_square += sample_specular * sample_specular;
            count += 1.0;
        }
    }
    // The pixel itself shows a surface: `count` is at least 1.
    diffuse /= count;
    specular /= count;
    return DenoiseNeighbourhood(
        diffuse,
        sqrt(max(vec3<f32>(0.0), diffuse_square / count - diffuse * diffuse)),
        specular,
        sqrt(max(vec3<f32>(0.0), specular_square / count - specular * specular)),
    );
}

fn denoise_clamp(kept: vec3<f32>, mean: vec3<f32>, reach: vec3<f32>) -> vec3<f32> {
    return clamp(kept, mean - reach, mean + reach);
}

@compute @workgroup_size(8, 8)
fn denoise_temporal(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let index = denoise_index(id.xy);
    let none = vec4<f32>(0.0);
    if textureLoad(depth, id.xy, 0) == 0.0 {
        history[index] = DenoiseHistory(none, vec3<f32>(0.0), 0u, none, none);
        integrated[index] = vec4<u32>(0u);
        guides[index] = vec4<u32>(0u);
        return;
    }
    let sample = denoise_samples[index];
    let normal = denoise_normal(sample);
    guides[index] = denoise_guide(sample.position, normal);
    let tolerance = max(DENOISE_MAX_PLANE_DISTANCE * length(sample.position - frame.world_from_view[3].xyz), denoise_footprint(sample.position));

    // Where the surface was a frame ago (carried by its instance, if animated), in pixel coordinates
    // of the pixels' centres.
    let previous_position = previous_surface_position(id.xy, sample.position);
    let clip = frame.previous_clip_from_world * vec4<f32>(previous_position, 1.0);
    let ndc = clip.xy / clip.w;
    let at = vec2<f32>((ndc.x * 0.5 + 0.5) * frame.viewport.x, (0.5 - ndc.y * 0.5) * frame.viewport.y) - 0.5;
    let corner = floor(at);
    let f = at - corner;
    var kept_moments = vec4<f32>(0.0);
    var kept_diffuse = vec3<f32>(0.0);
    var kept_specular = vec3<f32>(0.0);
    var kept_length = 0.0;
    var weights = 0.0;
    for (var tap = 0u; tap < 4u && clip.w > 0.0; tap += 1u) {
        let offset = vec2<u32>(tap & 1u, tap >> 1u);
        let p = corner + vec2<f32>(offset);
        if any(p < vec2<f32>(0.0)) || any(p >= frame.viewport.xy) {
            continue;
        }
        let kept = previous[denoise_index(vec2<u32>(p))];
        let frames = kept.normal_length >> 24u;
        if frames == 0u || dot(octahedral_unpack(kept.normal_length, 12u), normal) < DENOISE_MIN_NORMAL_COSINE
            || abs(dot(normal, kept.position - previous_position)) > tolerance {
            continue;
        }
        let w = select(1.0 - f.x, f.x, offset.x == 1u) * select(1.0 - f.y, f.y, offset.y == 1u);
        kept_moments += w * kept.moments;
        kept_diffuse += w * kept.diffuse.rgb;
        kept_specular += w * kept.specular.rgb;
        kept_length += w * f32(frames);
        weights += w;
    }
    var frames = 1u;
    if weights > 1e-4 {
        let around = denoise_neighbourhood(vec2<i32>(id.xy), vec2<i32>(size));
        kept_moments /= weights;
        let moving = any(previous_position != sample.position);
        let deviations = select(DENOISE_CLAMP_DEVIATIONS, DENOISE_MOVING_CLAMP_DEVIATIONS, moving);
        kept_diffuse = denoise_clamp(kept_diffuse / weights, around.diffuse_mean, deviations * around.diffuse_deviation);
        kept_specular = denoise_clamp(kept_specular / weights, around.specular_mean, deviations * around.specular_deviation);
        frames = min(u32(round(kept_length / weights)) + 1u, select(DENOISE_MAX_HISTORY, DENOISE_MOVING_HISTORY, moving));
    }
    let alpha = 1.0 / f32(frames);
    let diffuse_luminance = dot(sample.diffuse, DENOISE_LUMINANCE);
    let specular_luminance = dot(sample.specular, DENOISE_LUMINANCE);
    let moments = mix(
        kept_moments,
        vec4<f32>(diffuse_luminance, diffuse_luminance * diffuse_luminance, specular_luminance, specular_luminance * specular_luminance),
        alpha,
    );
    let diffuse = mix(kept_diffuse, sample.diffuse, alpha);
    let specular = mix(kept_specular, sample.specular, alpha);
    history[index] = DenoiseHistory(moments, sample.position, octahedral_pack_counted(normal, frames), vec4<f32>(diffuse, 0.0), vec4<f32>(specular, 0.0));
    // The variance of the mean of the frames accumulated, not of one frame's sample: the spatial
    // filters then stop at smaller differences as the history grows, so a still surface converges
    // to its own mean rather than its neighbourhood's.
    let variance = max(vec2<f32>(0.0), moments.yw - moments.xz * moments.xz) / f32(frames);
    integrated[index] = denoise_pack_light(DenoiseLight(vec4<f32>(diffuse, variance.x), vec4<f32>(specular, variance.y)));
}
