// Motion blur: McGuire et al.'s reconstruction filter ("A Reconstruction Filter for Plausible Motion
// Blur", I3D 2012). Each pixel's blur is its velocity (`velocity.wgsl`) times the shutter time
// (`post.motion_blur.x`, a fraction of the frame interval), capped at `post.motion_blur.z` pixels.
// `motion_blur_tiles` keeps the longest blur of each 16×16 tile; `motion_blur` samples along the
// longest blur of the 3×3 tiles around the pixel — so a moving object smears over the still
// background beside it — and weighs each sample by whether it is in front (it smears over the pixel
// as far as its own blur reaches), behind (the pixel's own blur reveals it) or both blurred alike.
// Where no blur reaches, a pixel keeps its colour exactly.
#include "shading/scene_bindings.wgsl"
#include "post/post_types.wgsl"

@group(1) @binding(0) var<uniform> post: PostUniforms;
@group(1) @binding(1) var depth: texture_depth_2d;
@group(1) @binding(2) var velocity: texture_2d<f32>;
@group(1) @binding(3) var color_input: texture_2d<f32>;
@group(1) @binding(4) var tiles: texture_2d<f32>;
@group(1) @binding(5) var tiles_output: texture_storage_2d<rg32float, write>;
@group(1) @binding(6) var color_output: texture_storage_2d<rgba32float, write>;

// Depths within this fraction of each other blend as one surface.
const SOFT_DEPTH: f32 = 0.02;

// A pixel's blur in pixels: its motion during the shutter, capped.
fn pixel_blur(pixel: vec2<u32>) -> vec2<f32> {
    let blur = textureLoad(velocity, pixel, 0).xy * post.motion_blur.x;
    let length = length(blur);
    return select(blur, blur * (post.motion_blur.z / length), length > post.motion_blur.z);
}

@compute @workgroup_size(8, 8)
fn motion_blur_tiles(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    let tile_count = (size + POST_TILE - 1u) / POST_TILE;
    if any(id.xy >= tile_count) {
        return;
    }
    let first = id.xy * POST_TILE;
    let last = min(first + POST_TILE, size);
    var longest = vec2<f32>(0.0);
    for (var y = first.y; y < last.y; y += 1u) {
        for (var x = first.x; x < last.x; x += 1u) {
            let blur = pixel_blur(vec2<u32>(x, y));
            if dot(blur, blur) > dot(longest, longest) {
                longest = blur;
            }
        }
    }
    textureStore(tiles_output, id.xy, vec4<f32>(longest, 0.0, 0.0));
}

// 1 when `a` lies in front of `b` (or level with it), fading to 0 over SOFT_DEPTH of their distance.
fn in_front(a: f32, b: f32) -> f32 {
    return saturate(1.0 - (a - b) / (SOFT_DEPTH * min(a, b)));
}

// How much of a sample `distance` pixels away a blur of length `blur` covers: fading to its end.
fn cone(distance: f32, blur: f32) -> f32 {
    return saturate(1.0 - distance / max(blur, 1e-6));
}

// Whether `distance` lies within a blur of length `blur`, with a soft edge.
fn cylinder(distance: f32, blur: f32) -> f32 {
    let b = max(blur, 1e-6);
    return 1.0 - smoothstep(0.95 * b, 1.05 * b, distance);
}

@compute @workgroup_size(8, 8)
fn motion_blur(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let center_color = textureLoad(color_input, id.xy, 0);
    let tile = vec2<i32>(id.xy / POST_TILE);
    let tile_count = vec2<i32>(textureDimensions(tiles));
    var longest = vec2<f32>(0.0);
    for (var dy = -1; dy <= 1; dy += 1) {
        for (var dx = -1; dx <= 1; dx += 1) {
            let t = clamp(tile + vec2<i32>(dx, dy), vec2<i32>(0), tile_count - 1);
            let blur = textureLoad(tiles, t, 0).xy;
            if dot(blur, blur) > dot(longest, longest) {
                longest = blur;
            }
        }
    }
    if dot(longest, longest) < 0.25 {
        textureStore(color_output, id.xy, center_color);
        return;
    }
    // A point blurred by b smears over b/2 to each side of where it is: cones and cylinders use that
    // half length (McGuire's velocities are half the motion).
    let center_blur = 0.5 * length(pixel_blur(id.xy));
    let center_distance = post_distance(depth, id.xy);
    let samples = u32(post.motion_blur.y);
    // The pixel's own weight: a pixel smeared over a reach of r shows itself over 1/r of it.
    var weight_sum = 1.0 / max(center_blur, 0.5);
    var sum = center_color.rgb * weight_sum;
    // Samples spread evenly over [−½, ½] of the longest blur, shifted per pixel to trade banding for
    // noise.
    let jitter = pixel_hash(id.xy) - 0.5;
    let pixel = vec2<f32>(id.xy) + 0.5;
    for (var k = 0u; k < samples; k += 1u) {
        let t = (f32(k) + 0.5 + jitter) / f32(samples) - 0.5;
        let offset = longest * t;
        let p = vec2<u32>(clamp(pixel + offset, vec2<f32>(0.0), vec2<f32>(size) - 0.5));
        let distance = length(offset);
        let sample_distance = post_distance(depth, p);
        let sample_blur = 0.5 * length(pixel_blur(p));
        let front = in_front(sample_distance, center_distance);
        let back = in_front(center_distance, sample_distance);
        let w = front * cone(distance, sample_blur) + back * cone(distance, center_blur)
            + 2.0 * cylinder(distance, sample_blur) * cylinder(distance, center_blur);
        sum += textureLoad(color_input, p, 0).rgb * w;
        weight_sum += w;
    }
    textureStore(color_output, id.xy, vec4<f32>(sum / weight_sum, center_color.a));
}
