// Decal enumeration through cell lists (`accel/cell_lists.rs`): where the decals are one crowded
// group placed once (`VolumeStructure::cell_lists`), a grid over the group lists, per cell, every
// decal that may reach it, and a point's query is its cell's list — no walk. A subgroup takes its lanes'
// cells in turn: each cell's list is shared out among all the lanes as a leaf is
// (`decal_leaves_shared_out.wgsl`), each lane testing one decal against the box around the points of
// the lanes in that cell, and the decals some lane kept go, one after the other, through the tests
// and blend of those lanes alone — a lane must see its own cell's list and no other, which names each
// decal reaching its point once, top layer first and in the items' order within a layer, so that
// decals of layers hidden at the point are skipped (`decal_accumulate_top_down`) and each layer's
// sums add up in the walk's order. Lanes of a subgroup mostly share a cell or two,
// so the walk down the group's BVH, a chain of dependent loads node after node and leaf round after
// leaf round, becomes a round or two per cell. `decal_accumulate` applies the exact box test, so the
// result equals the brute-force loop's. Needs subgroup operations (the lists come with the walks that
// share leaves out, `plan::query_walks`).
#include "shading/decal_bindings.wgsl"
#include "shading/decals.wgsl"
#include "shading/decal_box.wgsl"

// A list's entry: the decal's index, and its layer in the top bits (`cell_lists::RANK_SHIFT`).
fn cell_entry_decal(entry: u32) -> u32 {
    return entry & 0x3fffffffu;
}

fn cell_entry_layer(entry: u32) -> u32 {
    return entry >> 30u;
}

fn apply_decals(s: ShadingInput, dp: PositionGradients) -> ShadingInput {
    decal_blend_begin();
    let instance = decal_first_instance.instance;
    let point = instance_point_to_group(instance, s.position);
    let world = decal_world_surface(s, dp);
    // A point more than a cell outside the grid (a reflection's hit far away) lies in no decal, and
    // one that is not finite in none that can be looked up: an empty list, rather than a border cell's
    // list. Helper lanes of fragment shaders (lavapipe) read storage as zero: an empty list too.
    let header = decal_first_instance.entry_grid_header;
    let at_cell = (point - header.min) * header.max;
    let inside = all(abs(point) < vec3<f32>(3e38)) && all(at_cell >= vec3<f32>(-1.0)) && all(at_cell <= vec3<f32>(entry_grid_dims(header) + 1u));
    let cell = entry_grid_cell(header, point);
    var list = vec2<u32>(decal_primitives[cell], decal_primitives[cell + 1u]);
    if !inside {
        list = vec2<u32>(0u);
    }
    let lanes = subgroupExclusiveAdd(1u);
    let lane_count = subgroupAdd(1u);
    let outside = vec3<f32>(bitcast<f32>(0x7f800000u));
    var pending = list.x < list.y;
    loop {
        let start = subgroupMin(select(BVH_END, list.x, pending));
        if start == BVH_END {
            break;
        }
        let mine = pending && list.x == start;
        let end = subgroupMax(select(0u, list.y, mine));
        // The box around the points of the lanes in this cell.
        let lo = subgroupMin(select(outside, point, mine));
        let hi = subgroupMax(select(-outside, point, mine));
        for (var first = start; first < end; first += lane_count) {
            // Decals below the lowest layer any lane in the cell may still show are skipped, and
            // lists run top layer first: once a round holds none that any of them shows, the
            // rounds after it hold none either.
            let lowest = subgroupMin(select(DECAL_LAYERS, decal_lowest_shown(), mine));
            let at = min(first + lanes, end - 1u);
            let entry = decal_primitives[at];
            let shown = first + lanes < end && cell_entry_layer(entry) >= lowest;
            if !subgroupAny(shown) {
                break;
            }
            let kept = subgroupBallot(shown && decal_box_meets_box(decals[cell_entry_decal(entry)].decal_from_group, lo, hi));
            for (var word = 0u; word < 4u; word += 1u) {
                for (var bits = kept[word]; bits != 0u; bits &= bits - 1u) {
                    // The list's slot, shuffled while every lane is active (as the leaves' decals
                    // are), and its decal read by the lanes that take it: a lane that read its own as
                    // zero (a helper) passes on the slot, not a wrong decal.
                    let slot = subgroupShuffle(at, word * 32u + firstTrailingBit(bits));
                    if mine {
                        let kept_entry = decal_primitives[slot];
                        decal_accumulate_top_down(cell_entry_decal(kept_entry), cell_entry_layer(kept_entry), instance, point, decal_surface_in_group(world, instance));
                    }
                }
            }
        }
        pending = pending && !mine;
    }
    return decal_blend_end(s);
}
