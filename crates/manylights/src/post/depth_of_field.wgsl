// Depth of field of a thin lens, by gathering what each pixel's neighbours scatter onto it.
//
// A point at distance d, seen through a lens of focal length f and f-number N focused at S, spreads
// over a circle of confusion of diameter f²/N · |1/S − 1/d| · S / (S − f) on the sensor
// (`post.depth_of_field`, in pixels: `post::PostUniforms::new`). `depth_of_field_tiles` finds the largest circle in each 16×16 tile;
// `depth_of_field` then gathers, over a disc as wide as the largest circle of the 3×3 tiles around
// it, every sample whose own circle reaches the pixel, each weighted by the inverse of its circle's
// area (a scattered point spreads its light over it). Samples behind the pixel reach it no farther
// than its own circle, so a blurred background does not spill over a sharp foreground; blurred
// foregrounds do spill over what lies behind them. A pixel no circle reaches keeps its colour exactly.
#include "shading/scene_bindings.wgsl"
#include "post/post_types.wgsl"

@group(1) @binding(0) var<uniform> post: PostUniforms;
@group(1) @binding(1) var depth: texture_depth_2d;
@group(1) @binding(2) var color_input: texture_2d<f32>;
@group(1) @binding(3) var tiles: texture_2d<f32>;
@group(1) @binding(4) var tiles_output: texture_storage_2d<r32float, write>;
@group(1) @binding(5) var color_output: texture_storage_2d<rgba32float, write>;

const DOF_SAMPLES: u32 = 48u;
const GOLDEN_ANGLE: f32 = 2.39996323;

// The distance in focus: the setting, or (0) what the image's centre shows.
fn focus_distance() -> f32 {
    if post.depth_of_field.x > 0.0 {
        return post.depth_of_field.x;
    }
    return post_distance(depth, vec2<u32>(frame.viewport.xy * 0.5));
}

// The circle of confusion's radius in pixels of a point at `distance`, capped.
fn coc_radius(distance: f32, focus: f32) -> f32 {
    let focal_length = post.depth_of_field.w;
    let diameter = post.depth_of_field.y * abs(1.0 / focus - 1.0 / distance) * focus / max(focus - focal_length, 1e-6);
    return min(0.5 * diameter, post.depth_of_field.z);
}

@compute @workgroup_size(8, 8)
fn depth_of_field_tiles(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    let tile_count = (size + POST_TILE - 1u) / POST_TILE;
    if any(id.xy >= tile_count) {
        return;
    }
    let focus = focus_distance();
    let first = id.xy * POST_TILE;
    let last = min(first + POST_TILE, size);
    var largest = 0.0;
    for (var y = first.y; y < last.y; y += 1u) {
        for (var x = first.x; x < last.x; x += 1u) {
            largest = max(largest, coc_radius(post_distance(depth, vec2<u32>(x, y)), focus));
        }
    }
    textureStore(tiles_output, id.xy, vec4<f32>(largest, 0.0, 0.0, 0.0));
}

@compute @workgroup_size(8, 8)
fn depth_of_field(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let center_color = textureLoad(color_input, id.xy, 0);
    // The widest circle that may reach this pixel: the largest of the tiles around it.
    let tile = vec2<i32>(id.xy / POST_TILE);
    let tile_count = vec2<i32>(textureDimensions(tiles));
    var search = 0.0;
    for (var dy = -1; dy <= 1; dy += 1) {
        for (var dx = -1; dx <= 1; dx += 1) {
            let t = clamp(tile + vec2<i32>(dx, dy), vec2<i32>(0), tile_count - 1);
            search = max(search, textureLoad(tiles, t, 0).x);
        }
    }
    if search < 0.5 {
        textureStore(color_output, id.xy, center_color);
        return;
    }
    let focus = focus_distance();
    let center_distance = post_distance(depth, id.xy);
    let center_radius = coc_radius(center_distance, focus);
    // The pixel itself covers one pixel's area; each sample stands for 1/N of the search disc's.
    var sum = center_color.rgb / max(center_radius * center_radius, 0.25);
    var weight_sum = 1.0 / max(center_radius * center_radius, 0.25);
    let sample_area = search * search / f32(DOF_SAMPLES);
    let rotation = 6.283185307 * pixel_hash(id.xy);
    let pixel = vec2<f32>(id.xy) + 0.5;
    for (var k = 0u; k < DOF_SAMPLES; k += 1u) {
        let r = search * sqrt((f32(k) + 0.5) / f32(DOF_SAMPLES));
        let angle = f32(k) * GOLDEN_ANGLE + rotation;
        let p = vec2<u32>(clamp(pixel + r * vec2<f32>(cos(angle), sin(angle)), vec2<f32>(0.0), vec2<f32>(size) - 0.5));
        let distance = post_distance(depth, p);
        var radius = coc_radius(distance, focus);
        if distance > center_distance {
            radius = min(radius, center_radius);
        }
        let reach = saturate(radius - r + 0.5);
        let w = reach * sample_area / max(radius * radius, 0.25);
        sum += textureLoad(color_input, p, 0).rgb * w;
        weight_sum += w;
    }
    textureStore(color_output, id.xy, vec4<f32>(sum / weight_sum, center_color.a));
}
