// The point query (`volume_query.wgsl`) walked by each invocation alone: it enters the nodes whose box
// holds its own point, and starts at its own entry-grid cell.
#include "accel/volume_query.wgsl" with VOLUMES=VOLUMES

fn VOLUMES_walk_any(inside: bool) -> bool {
    return inside;
}

fn VOLUMES_walk_cells(start: u32, stop: u32) -> vec2<u32> {
    return vec2<u32>(start, stop);
}
