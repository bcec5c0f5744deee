// The point query (`volume_query.wgsl`) walked by a whole subgroup at once: a packet traversal. Every
// lane visits the same node: a node is entered when its box holds any lane's point (`subgroupAny`) and
// skipped otherwise, so each lane still reaches every leaf whose box holds its own point; every leaf
// goes to every lane, whose tight tests reject the items around other lanes' points. Neighbouring pixels
// need nearly the same nodes, so this costs about one lane's walk, with one load per node for the
// whole subgroup; lanes walking alone visit the same nodes at different times, each load a separate
// memory transaction. Passes use it where it is faster (`passes::query_walks`).
#include "accel/volume_query.wgsl" with VOLUMES=VOLUMES

fn VOLUMES_walk_any(inside: bool) -> bool {
    return subgroupAny(inside);
}

// The lanes' cells name subtrees, each [start, stop) in node order; the walk covers them all from the
// lowest start to the highest stop (what lies between and holds no lane's point is skipped as usual;
// empty cells add none). This is the walk's one assumption: lanes running together entered the same
// instance, as they do when they share the top-level walk from the query's start. (Lavapipe's helper
// lanes read no grid flag and never get here.) Checking it with two more subgroup operations made
// 100k decals in fragments three times slower on the H100, with no lane ever failing it.
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
