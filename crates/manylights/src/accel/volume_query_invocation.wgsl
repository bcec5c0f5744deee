// The point query (`volume_query.wgsl`) walked by each invocation alone: it enters the nodes whose box
// holds its own point, and walks its own entry-grid cell's subtrees, one after the other.
#include "accel/volume_query.wgsl" with VOLUMES=VOLUMES

fn VOLUMES_walk_any(inside: bool) -> bool {
    return inside;
}

fn VOLUMES_walk_cells(start: u32, stop: u32) -> vec2<u32> {
    return vec2<u32>(start, stop);
}

fn VOLUMES_walk_covers() -> bool {
    return true;
}

fn VOLUMES_walk_shared() -> bool {
    return false;
}

// Sharing a leaf's items out (`volume_query_subgroup.wgsl`) with an invocation walking alone: a
// subgroup of one lane, whose box is its own point.
fn VOLUMES_walk_lanes() -> vec3<u32> {
    return vec3<u32>(0u, 1u, 1u);
}

fn VOLUMES_walk_bounds(p: vec3<f32>) -> array<vec3<f32>, 2> {
    return array<vec3<f32>, 2>(p, p);
}

fn VOLUMES_walk_ballot(keep: bool) -> vec4<u32> {
    return vec4<u32>(u32(keep), 0u, 0u, 0u);
}

fn VOLUMES_walk_lane_u32(value: u32, lane: u32) -> u32 {
    return value;
}

fn VOLUMES_walk_lane_vec4(value: vec4<f32>, lane: u32) -> vec4<f32> {
    return value;
}
