// The point query of `volume_query.wgsl`, walked by a whole subgroup at once: a packet traversal.
// Same template (`VOLUMES`), same cursor and same results; where the device has subgroup operations,
// passes use it for the structures it walks faster (`passes::query_walks`).
//
// Every lane of the subgroup visits the same node: a node is entered when its box holds any lane's
// point (`subgroupAny`) and skipped otherwise, so each lane still reaches every leaf whose box holds
// its own point, and a leaf is handed to the lanes whose point it holds (the others get an empty range
// and wait). Neighbouring pixels need nearly the same nodes, so this costs about one lane's walk, with
// one load per node for the whole subgroup; lanes walking alone visit the same nodes at different
// times, each load a separate memory transaction, and wait for each other at every leaf.
//
// Every lane that begins a query must call `VOLUMES_query_next_leaf` until it returns BVH_END (every
// lane gets BVH_END at once), without returning early: a lane that leaves stops steering the walk.
// Correctness never depends on which lanes run together: a lane skips a node only when its own point
// is outside it, and gets a leaf only when its point is inside. Lanes with garbage data — lavapipe runs
// fragment helper lanes with storage loads masked to zero — only make the others visit more, and end
// at a node linking to itself as in `volume_query.wgsl`.
#include "accel/bvh_types.wgsl"

var<private> VOLUMES_query_world_point: vec3<f32>;
// The lane's point in the current level's space: the world's in the top level, the group's inside an
// instance. Callers read it to test items in their group's space.
var<private> VOLUMES_query_point: vec3<f32>;
// The instance being visited and its index (the same in every lane); a query enters each instance once.
var<private> VOLUMES_query_instance: VolumeInstance;
var<private> VOLUMES_query_instance_index: u32;
// The walk's state, the same in every lane: the node to visit next, the node at or past which the
// group's walk ends, and the top-level node to resume at.
var<private> VOLUMES_query_node: u32;
var<private> VOLUMES_query_stop: u32;
var<private> VOLUMES_query_resume: u32;
var<private> VOLUMES_query_in_group: bool;
// Nodes the walk visited: the debug view of the method's work (the subgroup's shared count).
var<private> VOLUMES_query_visits: u32;

// Starts a query at a world-space point, replacing any in flight; `instance_count` must be the same in
// every lane. With one instance the walk enters its group at once, as in `volume_query.wgsl`.
fn VOLUMES_query_begin(point: vec3<f32>, instance_count: u32) {
    VOLUMES_query_world_point = point;
    VOLUMES_query_point = point;
    VOLUMES_query_node = select(BVH_END, 0u, instance_count > 0u);
    VOLUMES_query_in_group = false;
    VOLUMES_query_visits = 0u;
    if instance_count == 1u {
        VOLUMES_query_node = BVH_END;
        VOLUMES_query_enter(0u);
    }
}

// Moves the walk into an instance's group, to resume the top level at `VOLUMES_query_node` after it.
fn VOLUMES_query_enter(instance_index: u32) {
    VOLUMES_query_instance_index = instance_index;
    VOLUMES_query_instance = VOLUMES_instances[instance_index];
    VOLUMES_query_point = instance_point_to_group(VOLUMES_query_instance, VOLUMES_query_world_point);
    VOLUMES_query_resume = VOLUMES_query_node;
    let root = VOLUMES_query_instance.blas_root & ~ENTRY_GRID_FLAG;
    VOLUMES_query_node = root;
    VOLUMES_query_stop = BVH_END;
    if (VOLUMES_query_instance.blas_root & ENTRY_GRID_FLAG) != 0u {
        // Each lane's cell names a subtree, [start, stop) in node order (`accel/entry_grid.rs`;
        // groups with grids are built on the CPU, depth-first, so every step of a walk moves to a
        // higher node). The walk covers them all from the lowest start to the highest stop: what lies
        // between and holds no lane's point is skipped as usual. Empty cells (start BVH_END) add none.
        let cell = entry_grid_cell(VOLUMES_nodes[root - 1u], VOLUMES_query_point);
        // A start below the group's root is a helper lane's zero, not a cell of this group.
        let start = select(VOLUMES_primitives[cell], BVH_END, VOLUMES_primitives[cell] < root);
        let stop = select(VOLUMES_primitives[cell + 1u], 0u, start == BVH_END);
        VOLUMES_query_node = start;
        VOLUMES_query_stop = stop;
        // Only cells of one group combine: lanes running together in different instances (which
        // shared walks never start, but nothing promises) each walk their own cell.
        if subgroupAll(instance_index == subgroupBroadcastFirst(instance_index)) {
            VOLUMES_query_node = subgroupMin(start);
            VOLUMES_query_stop = subgroupMax(stop);
        }
    }
    VOLUMES_query_in_group = true;
}

// The next group leaf whose box holds any lane's point, as the range [x, y) of `VOLUMES_primitives`
// (item indices) in the lanes whose point it holds and an empty range in the others; x is BVH_END,
// in every lane, when the query is done.
fn VOLUMES_query_next_leaf() -> vec2<u32> {
    loop {
        if VOLUMES_query_node == BVH_END || (VOLUMES_query_in_group && VOLUMES_query_node >= VOLUMES_query_stop) {
            if !VOLUMES_query_in_group {
                break;
            }
            // The instance's BVH is done: back in the top level.
            VOLUMES_query_in_group = false;
            VOLUMES_query_node = VOLUMES_query_resume;
            VOLUMES_query_point = VOLUMES_query_world_point;
            continue;
        }
        let node = VOLUMES_nodes[VOLUMES_query_node];
        VOLUMES_query_visits += 1u;
        let inside = bvh_node_contains(node, VOLUMES_query_point);
        if !subgroupAny(inside) {
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
            return select(vec2<u32>(leaf.x), leaf, inside);
        }
        // A top-level leaf holds one instance: enter its group.
        VOLUMES_query_enter(VOLUMES_primitives[leaf.x]);
    }
    return vec2<u32>(BVH_END);
}
