// The point query (`volume_query.wgsl`) walked by a whole subgroup at once: a packet traversal. Every
// lane visits the same node: a node is entered when its box holds any lane's point (`subgroupAny`) and
// skipped otherwise, so each lane still reaches every leaf whose box holds its own point; every leaf
// goes to every lane, whose tight tests reject the items around other lanes' points. Neighbouring pixels
// need nearly the same nodes, so this costs about one lane's walk, with one load per node for the
// whole subgroup; lanes walking alone visit the same nodes at different times, each load a separate
// memory transaction. Passes use it where it is faster (`plan::query_walks`).
#include "accel/volume_query.wgsl" with VOLUMES=VOLUMES

fn VOLUMES_walk_any(inside: bool) -> bool {
    return subgroupAny(inside);
}

// The lanes' cells name subtrees, each [start, stop) in node order; the walk covers them all from the
// lowest start to the highest stop (what lies between and holds no lane's point is skipped as usual;
// empty cells add none). This is the walk's one assumption: lanes running together entered the same
// instance, as they do when they share the top-level walk from the query's start. (Lavapipe's helper
// lanes read no grid flag and never get here.) It is assumed, not checked: two more subgroup operations
// made crowded decals in fragments about three times slower (benchmarks/LOG.md, topic 3).
fn VOLUMES_walk_cells(start: u32, stop: u32) -> vec2<u32> {
    return vec2<u32>(subgroupMin(start), subgroupMax(stop));
}

// A cell's cover is walked whole, from its first subtree's start to its last one's stop: the lanes'
// cells are merged into one range anyway.
fn VOLUMES_walk_covers() -> bool {
    return false;
}

fn VOLUMES_walk_shared() -> bool {
    return true;
}

// A leaf's items shared out among the lanes walking together: each active lane takes one item, tests
// it against the box around every lane's point, and the subgroup then processes only the items some
// lane kept (`shading/enumerate/lights_bvh.wgsl`, `decal_leaves_shared_out.wgsl`). x: this lane's
// rank among the active lanes, y: how many are active, z: how many words of a ballot hold them (one on
// subgroups of 32 lanes or fewer).
fn VOLUMES_walk_lanes() -> vec3<u32> {
    let lanes = subgroupBallot(true);
    let words = select(select(select(1u, 2u, lanes.y != 0u), 3u, lanes.z != 0u), 4u, lanes.w != 0u);
    return vec3<u32>(subgroupExclusiveAdd(1u), subgroupAdd(1u), words);
}

// The box around the active lanes' points, as (min, max). A point that is not finite is left out: a
// fragment shader's helper lanes may compute one from storage they read as zero.
fn VOLUMES_walk_bounds(p: vec3<f32>) -> array<vec3<f32>, 2> {
    let finite = all(abs(p) < vec3<f32>(3e38));
    return array<vec3<f32>, 2>(subgroupMin(select(vec3<f32>(3e38), p, finite)), subgroupMax(select(vec3<f32>(-3e38), p, finite)));
}

// The lanes for which `keep` holds, a bit each.
fn VOLUMES_walk_ballot(keep: bool) -> vec4<u32> {
    return subgroupBallot(keep);
}

// `value` as lane `lane` holds it.
fn VOLUMES_walk_lane_u32(value: u32, lane: u32) -> u32 {
    return subgroupShuffle(value, lane);
}

fn VOLUMES_walk_lane_vec4(value: vec4<f32>, lane: u32) -> vec4<f32> {
    return subgroupShuffle(value, lane);
}
