// Sun shadows by ray tracing from the depth buffer (PowerVR's hybrid step 3: rays per G-buffer
// pixel), in compute, before shading, in every pipeline: each pixel's position comes from its depth,
// its geometric normal from its neighbours' (`shading/depth_normal.wgsl`); rays towards the sun —
// one to its centre (hard), or `frame.ray_options.y` to points of its disc (soft), which
// `shadow_filter` then smooths — give the fraction of the sun the pixel sees (x), and the mean
// distance to what blocked the rays (y, 0 when nothing did), from which the filter sizes the
// penumbra. Sky pixels see the whole sun, blocked at no distance.
#include "shading/scene_bindings.wgsl"
#include "shading/depth_normal.wgsl"
#include "$RAY_TRACE"
#include "shading/pixel_hash.wgsl"

@group(1) @binding(0) var depth: texture_depth_2d;
@group(1) @binding(1) var visibility_output: texture_storage_2d<rg32float, write>;

const GOLDEN_RATIO_CONJUGATE: f32 = 0.6180339887;

// Direction `k` of `count` towards the sun's disc of angular radius `radius` around `axis`: a
// golden-angle spiral, uniform in solid angle, turned by `rotation` (in [0, 1)).
fn sun_disc_direction(axis: vec3<f32>, radius: f32, k: u32, count: u32, rotation: f32) -> vec3<f32> {
    let cos_max = cos(radius);
    let cos_theta = 1.0 - (f32(k) + 0.5) / f32(count) * (1.0 - cos_max);
    let sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    let phi = 6.283185307 * fract(f32(k) * GOLDEN_RATIO_CONJUGATE + rotation);
    let helper = select(vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0), abs(axis.x) > 0.7);
    let u = normalize(cross(axis, helper));
    let v = cross(axis, u);
    return normalize(axis * cos_theta + (u * cos(phi) + v * sin(phi)) * sin_theta);
}

@compute @workgroup_size(8, 8)
fn ray_shadows(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let z = textureLoad(depth, id.xy, 0);
    if z == 0.0 || frame.sun_direction.w == 0.0 {
        textureStore(visibility_output, id.xy, vec4<f32>(1.0, 0.0, 0.0, 0.0));
        return;
    }
    let relative_position = depth_relative_position(vec2<f32>(id.xy) + 0.5, z);
    let n = depth_geometric_normal(depth, id.xy, relative_position, z);
    let to_sun = -frame.sun_direction.xyz;
    if dot(n, to_sun) <= 0.0 {
        // Facing away: the surface shadows itself.
        textureStore(visibility_output, id.xy, vec4<f32>(0.0));
        return;
    }
    // The depth buffer holds the surface at the pixel's centre only to its resolution.
    let origin = ray_offset_origin(relative_position + frame.world_from_view[3].xyz, n, surface_clearance(relative_position));
    let soft = frame.ray_options.x == RAY_SHADOWS_SOFT;
    let count = select(1u, frame.ray_options.y, soft);
    let rotation = pixel_hash(id.xy);
    var visible = 0.0;
    // Directions below the surface's horizon are blocked by the surface itself: they darken the pixel
    // but are no blocker at a distance, so only traced hits size the penumbra.
    var hits = 0.0;
    var blocker_distance = 0.0;
    for (var k = 0u; k < count; k += 1u) {
        let dir = select(to_sun, sun_disc_direction(to_sun, frame.ray_settings.x, k, count, rotation), soft);
        if dot(dir, n) <= 0.0 {
            continue;
        }
        let hit = trace_any_hit(origin, dir, 3.0e38);
        if hit.triangle == RAY_NO_HIT {
            visible += 1.0;
        } else {
            hits += 1.0;
            blocker_distance += hit.t;
        }
    }
    textureStore(visibility_output, id.xy, vec4<f32>(visible / f32(count), select(0.0, blocker_distance / hits, hits > 0.0), 0.0, 0.0));
}
