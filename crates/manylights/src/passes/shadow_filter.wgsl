// The spatial filter of soft sun shadows: a few jittered rays per pixel leave noise in the
// penumbrae, so each pixel averages the traced visibility over its neighbourhood, weighted by a
// Gaussian in screen space and by how close each neighbour lies to the pixel's tangent plane (a joint
// bilateral filter), so shadows do not bleed across depth edges or onto other surfaces. The
// Gaussian's width is a quarter of the penumbra's there — the sun's angular diameter times the
// distance to the blockers the rays met, in pixels — so a small sun's sharp shadows stay sharp;
// pixels with no blocker nearby keep their own value.
#include "shading/scene_bindings.wgsl"
#include "shading/depth_normal.wgsl"

@group(1) @binding(0) var depth: texture_depth_2d;
@group(1) @binding(1) var visibility_input: texture_2d<f32>;
@group(1) @binding(2) var visibility_output: texture_storage_2d<rg32float, write>;

const FILTER_RADIUS: i32 = 3;

@compute @workgroup_size(8, 8)
fn shadow_filter(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let z = textureLoad(depth, id.xy, 0);
    let own = textureLoad(visibility_input, id.xy, 0);
    if z == 0.0 {
        textureStore(visibility_output, id.xy, own);
        return;
    }
    // The blockers' mean distance around the pixel gives the penumbra's width.
    var blocker_sum = 0.0;
    var blockers = 0.0;
    for (var dy = -FILTER_RADIUS; dy <= FILTER_RADIUS; dy += 1) {
        for (var dx = -FILTER_RADIUS; dx <= FILTER_RADIUS; dx += 1) {
            let p = clamp(vec2<i32>(id.xy) + vec2<i32>(dx, dy), vec2<i32>(0), vec2<i32>(size) - 1);
            let distance = textureLoad(visibility_input, p, 0).y;
            blocker_sum += distance;
            blockers += select(0.0, 1.0, distance > 0.0);
        }
    }
    if blockers == 0.0 {
        textureStore(visibility_output, id.xy, own);
        return;
    }
    let center = depth_relative_position(vec2<f32>(id.xy) + 0.5, z);
    let footprint = max(pixel_footprint(center), 1e-6);
    let penumbra_pixels = 2.0 * tan(frame.ray_settings.x) * (blocker_sum / blockers) / footprint;
    let sigma = clamp(0.25 * penumbra_pixels, 0.5, f32(FILTER_RADIUS) * 0.7);
    let n = depth_geometric_normal(depth, id.xy, center, z);
    // Neighbours further from the tangent plane than about a pixel's footprint are other surfaces.
    let plane_scale = 1.0 / footprint;
    var sum = 0.0;
    var weights = 0.0;
    for (var dy = -FILTER_RADIUS; dy <= FILTER_RADIUS; dy += 1) {
        for (var dx = -FILTER_RADIUS; dx <= FILTER_RADIUS; dx += 1) {
            let p = vec2<i32>(id.xy) + vec2<i32>(dx, dy);
            if any(p < vec2<i32>(0)) || any(p >= vec2<i32>(size)) {
                continue;
            }
            let tap = depth_sample(depth, p);
            if tap.w == 0.0 {
                continue;
            }
            let distance = dot(tap.xyz - center, n) * plane_scale;
            let w = exp(-0.5 * f32(dx * dx + dy * dy) / (sigma * sigma) - distance * distance);
            sum += textureLoad(visibility_input, p, 0).x * w;
            weights += w;
        }
    }
    textureStore(visibility_output, id.xy, vec4<f32>(sum / weights, own.y, 0.0, 0.0));
}
