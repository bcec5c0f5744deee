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
