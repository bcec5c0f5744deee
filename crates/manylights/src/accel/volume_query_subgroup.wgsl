// The point query (`volume_query.wgsl`) walked by a whole subgroup at once: a packet traversal. Every
// lane visits the same node: a node is entered when its box holds any lane's point (`subgroupAny`) and
// skipped otherwise, so each lane still reaches every leaf whose box holds its own point, and a leaf
// goes to the lanes whose point it holds (the others get an empty range and wait). Neighbouring pixels
// need nearly the same nodes, so this costs about one lane's walk, with one load per node for the
// whole subgroup; lanes walking alone visit the same nodes at different times, each load a separate
// memory transaction. Passes use it where it is faster (`passes::query_walks`).
#include "accel/volume_query.wgsl" with VOLUMES=VOLUMES

fn VOLUMES_walk_any(inside: bool) -> bool {
    return subgroupAny(inside);
}

// The lanes' cells name subtrees, each [start, stop) in node order; the walk covers them all from the
// lowest start to the highest stop (what lies between and holds no lane's point is skipped as usual;
// empty cells add none). Only cells of one group combine: lanes running together in different
// instances (which shared walks never start, but nothing promises) each walk their own cell.
fn VOLUMES_walk_cells(instance_index: u32, start: u32, stop: u32) -> vec2<u32> {
    if subgroupAll(instance_index == subgroupBroadcastFirst(instance_index)) {
        return vec2<u32>(subgroupMin(start), subgroupMax(stop));
    }
    return vec2<u32>(start, stop);
}
