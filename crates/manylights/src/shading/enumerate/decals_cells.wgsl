// Decal enumeration through cell lists built on the GPU (`accel/rebuilt_cell_lists.rs`): where the
// decals are one sparse group placed once, built once or every frame, a grid over the group
// lists, per cell, every decal whose bounding sphere may reach it, and a point's query is its cell's
// list — no walk. `decal_accumulate` applies the exact box test and blends each layer order-
// independently, so the result equals the brute-force loop's. Points outside the grid read a cell on
// its faces, which reach out to infinity. The lists hold (instance, decal) pairs as the clustered
// lists do; the instance is the lone one, `decal_first_instance`.
#include "shading/decal_bindings.wgsl"
#include "shading/decals.wgsl"

fn apply_decals(s: ShadingInput, dp: PositionGradients) -> ShadingInput {
    decal_blend_begin();
    let instance = decal_first_instance.instance;
    let local = instance_point_to_group(instance, s.position);
    let surface = decal_surface_in_group(decal_world_surface(s, dp), instance);
    let range = decal_cluster_ranges[cell_list_index(decal_first_instance.entry_grid_header, local)];
    for (var i = range.x; i < range.x + range.y; i += 1u) {
        decal_accumulate(decal_cluster_entries[i].y, instance, local, surface);
    }
    return decal_blend_end(s);
}
