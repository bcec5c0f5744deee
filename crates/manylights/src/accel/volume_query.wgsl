// The point query — the paper's zero-length ray — through a two-level structure (`accel/structure.rs`):
// the top level's leaves are group instances; entering one moves the point into the group's space
// and continues in the group's BVH. A template: `VOLUMES` is replaced by the structure's prefix,
// naming its bindings `VOLUMES_nodes`, `VOLUMES_primitives`, `VOLUMES_instances` and
// `VOLUMES_first_instance`, so lights and decals each get their own cursor. Enumeration modules
// include it through a walk module, which decides how invocations walk together
// (`plan::volume_query_module`): `accel/volume_query_invocation.wgsl`, each invocation alone, or
// `accel/volume_query_subgroup.wgsl`, a whole subgroup together. A walk module defines
// `VOLUMES_walk_any(inside)`, whether to enter a node whose box holds (`inside`) or not this
// invocation's point, `VOLUMES_walk_cells(start, stop)`, the range of nodes to walk for this
// invocation's entry-grid cell, `VOLUMES_walk_covers()`, whether a cell naming several subtrees has
// them walked one by one, or as one range from the first to the last, and `VOLUMES_walk_shared()`,
// whether the subgroup walks as one (callers choose by it what to hold through the walk). For callers
// that share a leaf's items out among the lanes walking together (`shading/enumerate/lights_bvh.wgsl`,
// `shading/enumerate/decal_leaves_shared_out.wgsl`)
// it also defines `VOLUMES_walk_lanes()`, `VOLUMES_walk_bounds(p)`, `VOLUMES_walk_ballot(keep)` and
// `VOLUMES_walk_lane_u32` / `_vec4(value, lane)`: one lane's trivial versions where each invocation
// walks alone.
//
// Inside a group the query starts where the group's entry grid says, if it has one, and ends at or
// past the node after that subtree: CPU-built groups are laid out depth first, so every step of a walk
// moves to a higher node; a rebuilt group's LBVH keeps each subtree below the node after it
// (`accel/lbvh.wgsl`). Where the cell names several subtrees (a cover), it walks each in turn.
//
// A cursor: `VOLUMES_query_next_leaf` returns every group leaf whose box contains the point (and,
// walking as a subgroup, the other lanes' leaves, below), as the range of items it holds (items are stored in leaf order, `accel/structure.rs`), and the caller
// applies its own tight test to them (light range and cone, decal box) without a copy of the
// traversal per use. It hands out whole leaves, which shade faster than a cursor returning one item
// per call (benchmarks/LOG.md, topic 5). Every invocation that begins a query calls
// `VOLUMES_query_next_leaf` until it returns BVH_END, without leaving the loop early.
//
// The caller also defines `VOLUMES_query_entered(instance)`, called as the query enters an instance's
// group, before any of its leaves: there it keeps what its tests need of the instance (lights: the
// surface in the group's space; decals: the instance, the surface in the group's space walking
// alone, and the box around the lanes' points sharing leaves out). The query keeps only the instance's
// index: a copy of the whole instance held through every walk costs the shading passes more than the
// callers' own state (benchmarks/LOG.md, topic 4).
//
// An invocation skips a node only when its own point is outside it, whichever invocations walk with it.
// Walking alone it gets a leaf's items only when its point is inside; where the subgroup walks as one,
// every lane gets each leaf the walk reaches, and the caller's tight test rejects the items of a leaf
// whose box does not hold the lane's point (an item's box lies inside its leaf's): a trip count the
// same for every lane is faster than an empty range for the lanes outside (benchmarks/LOG.md,
// topic 3). A link back to the node itself ends the
// walk: no valid tree has one, but lavapipe's fragment shaders run lanes outside the triangle (helpers)
// with storage loads masked to zero, so node 0 reads as a box at the origin linking to node 0, and a
// lane looping there until llvmpipe's loop limiter (65,535 iterations, shared by every loop of the
// shader) runs out ends every later loop of its whole 8-lane vector, the light loop included. For the
// same reason a grid start below the group's root (a helper's zero) counts as an empty cell.
#include "accel/bvh_types.wgsl"
#include "shading/debug_view.wgsl"

// The query in flight. The traversal needs no stack (`bvh_types.wgsl`): the node to visit next, the
// node at or past which the walk of the current level ends (BVH_END, past every node, in the top
// level and in groups without an entry grid, so one comparison ends every walk), and the top-level
// node to resume at when the current instance is done.
var<private> VOLUMES_query_world_point: vec3<f32>;
// The point in the current level's space: the world's in the top level, the group's inside an
// instance. Callers read it to test items in their group's space.
var<private> VOLUMES_query_point: vec3<f32>;
// The index of the instance whose group the last leaf belongs to: a query enters each instance once.
var<private> VOLUMES_query_instance_index: u32;
var<private> VOLUMES_query_node: u32;
var<private> VOLUMES_query_stop: u32;
var<private> VOLUMES_query_resume: u32;
// The (start, stop) pairs of the cell's further subtrees left to walk: [cover, cover_end) of the
// primitive array.
var<private> VOLUMES_query_cover: u32;
var<private> VOLUMES_query_cover_end: u32;
var<private> VOLUMES_query_in_group: bool;
// Nodes the walk visited: the debug view of the method's work.
var<private> VOLUMES_query_visits: u32;

// Starts a query at a world-space point, replacing any in flight; with no instances it finds nothing.
// With one instance the top level is a single leaf: the query enters its group at once, saving the
// two dependent loads of that leaf (the group's own boxes still bound the point), from the instance
// and grid header in `VOLUMES_first_instance`, a uniform, saving two more.
fn VOLUMES_query_begin(point: vec3<f32>, instance_count: u32) {
    VOLUMES_query_world_point = point;
    VOLUMES_query_point = point;
    VOLUMES_query_node = select(BVH_END, 0u, instance_count > 0u);
    VOLUMES_query_stop = BVH_END;
    VOLUMES_query_in_group = false;
    VOLUMES_query_visits = 0u;
    if instance_count == 1u {
        VOLUMES_query_node = BVH_END;
        VOLUMES_query_enter(0u, VOLUMES_first_instance.instance, true);
    }
}

// Moves the query into an instance's group, to resume the top level at `VOLUMES_query_node` after it;
// `first`: the instance is `VOLUMES_first_instance`'s, whose grid header is there too.
fn VOLUMES_query_enter(instance_index: u32, instance: VolumeInstance, first: bool) {
    VOLUMES_query_instance_index = instance_index;
    VOLUMES_query_entered(instance);
    VOLUMES_query_point = instance_point_to_group(instance, VOLUMES_query_world_point);
    VOLUMES_query_resume = VOLUMES_query_node;
    let root = instance.blas_root & ~ENTRY_GRID_FLAG;
    VOLUMES_query_node = root;
    VOLUMES_query_stop = BVH_END;
    VOLUMES_query_cover = 0u;
    VOLUMES_query_cover_end = 0u;
    if (instance.blas_root & ENTRY_GRID_FLAG) != 0u {
        // Start below the levels the leaves reaching the point's cell share: at their common subtree,
        // or at the first of the cell's cover of subtrees (`accel/entry_grid.rs`); an empty cell
        // starts at BVH_END.
        var header = VOLUMES_first_instance.entry_grid_header;
        if !first {
            header = VOLUMES_nodes[root - 1u];
        }
        // A rebuilt group's cells name LBVH subtrees, whose nodes do not lie in walk order: lanes
        // merging their cells into one range (`VOLUMES_walk_covers()` false) start at the root.
        if !VOLUMES_walk_covers() && (header.skip & ENTRY_GRID_REBUILT) != 0u {
            VOLUMES_query_in_group = true;
            return;
        }
        let cell = entry_grid_cell(header, VOLUMES_query_point);
        let start = select(VOLUMES_primitives[cell], BVH_END, VOLUMES_primitives[cell] < root);
        var stop = select(VOLUMES_primitives[cell + 1u], 0u, start == BVH_END);
        if (stop & ENTRY_CELL_COVER) != 0u {
            // Several subtrees: the first now, the rest after it, or all as one range.
            let pairs = entry_cell_cover_pairs(stop);
            if VOLUMES_walk_covers() {
                stop = VOLUMES_primitives[pairs.x + 1u];
                VOLUMES_query_cover = pairs.x + 2u;
                VOLUMES_query_cover_end = pairs.y;
            } else {
                stop = VOLUMES_primitives[pairs.y - 1u];
            }
        }
        let range = VOLUMES_walk_cells(start, stop);
        VOLUMES_query_node = range.x;
        VOLUMES_query_stop = range.y;
    }
    VOLUMES_query_in_group = true;
}

// The next group leaf whose box contains the point, as the range [x, y) of the items it holds; walking
// alone, an empty range when the walk visits a leaf for other invocations, walking as a subgroup, any
// leaf the walk reaches. x is BVH_END when the query is done.
fn VOLUMES_query_next_leaf() -> vec2<u32> {
    loop {
        if VOLUMES_query_node >= VOLUMES_query_stop {
            if !VOLUMES_query_in_group {
                break;
            }
            if VOLUMES_query_cover < VOLUMES_query_cover_end {
                // The cell's next subtree.
                VOLUMES_query_node = VOLUMES_primitives[VOLUMES_query_cover];
                VOLUMES_query_stop = VOLUMES_primitives[VOLUMES_query_cover + 1u];
                VOLUMES_query_cover += 2u;
                continue;
            }
            // The instance's BVH is done: back in the top level.
            VOLUMES_query_in_group = false;
            VOLUMES_query_node = VOLUMES_query_resume;
            VOLUMES_query_stop = BVH_END;
            VOLUMES_query_point = VOLUMES_query_world_point;
            continue;
        }
        let node = VOLUMES_nodes[VOLUMES_query_node];
        if DEBUG_VIEWS {
            VOLUMES_query_visits += 1u;
        }
        let inside = bvh_node_contains(node, VOLUMES_query_point);
        if !VOLUMES_walk_any(inside) {
            VOLUMES_query_node = select(node.skip, BVH_END, node.skip == VOLUMES_query_node);
            continue;
        }
        if (node.entry & BVH_LEAF) == 0u {
            VOLUMES_query_node = select(node.entry, BVH_END, node.entry == VOLUMES_query_node);
            continue;
        }
        VOLUMES_query_node = node.skip;
        let leaf = bvh_leaf_range(node.entry);
        if VOLUMES_query_in_group {
            return select(vec2<u32>(leaf.x), leaf, inside || VOLUMES_walk_shared());
        }
        // A top-level leaf names one primitive, an instance index: enter its group.
        let instance_index = VOLUMES_primitives[leaf.x];
        VOLUMES_query_enter(instance_index, VOLUMES_instances[instance_index], false);
    }
    return vec2<u32>(BVH_END);
}
