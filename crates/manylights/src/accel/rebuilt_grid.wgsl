// The entry grid of a group rebuilt on the GPU (`accel/rebuilt_grid.rs`), after its LBVH build: one
// invocation per cell descends from the group's root while exactly one child's box reaches the cell,
// and writes the cell as `entry_grid_cell` reads it: the node it stopped at (a leaf, or the deepest
// node both of whose children reach the cell) and the node where a walk of its subtree ends, or
// BVH_END where no leaf reaches the cell.
#include "accel/bvh_types.wgsl"

struct GridParams {
    min: vec3<f32>,
    root: u32,
    cell_size: vec3<f32>,
    // The first cell's word in `primitives`: two words per cell, x fastest.
    first_cell: u32,
    dims: vec3<u32>,
    // One past the group's last node: the stop of a subtree whose `skip` is BVH_END, which a cell
    // cannot hold (its top bit marks a cover of several subtrees).
    node_end: u32,
    // How far each cell is widened (`RebuiltGrids::new`).
    margin: vec3<f32>,
}

@group(0) @binding(0) var<uniform> grid: GridParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read_write> primitives: array<u32>;

// Beyond any finite coordinate: the grid's faces reach out to it.
const FAR: f32 = 3.0e38;

fn reaches(node: BvhNode, low: vec3<f32>, high: vec3<f32>) -> bool {
    return all(node.min <= high) && all(low <= node.max);
}

@compute @workgroup_size(256)
fn rebuilt_grid(@builtin(global_invocation_id) id: vec3<u32>) {
    let dims = grid.dims;
    if id.x >= dims.x * dims.y * dims.z {
        return;
    }
    let cell = vec3<u32>(id.x % dims.x, (id.x / dims.x) % dims.y, id.x / (dims.x * dims.y));
    let corner = grid.min + vec3<f32>(cell) * grid.cell_size;
    // Points outside the grid look up the cell on its face (`entry_grid_cell` clamps), so those
    // cells reach past it, where volumes that moved since the grid was placed may lie.
    let low = select(corner - grid.margin, vec3<f32>(-FAR), cell == vec3<u32>(0u));
    let high = select(corner + grid.cell_size + grid.margin, vec3<f32>(FAR), cell == dims - 1u);

    var start = BVH_END;
    var stop = BVH_END;
    var node = grid.root;
    var current = nodes[node];
    if reaches(current, low, high) {
        loop {
            if (current.entry & BVH_LEAF) != 0u {
                break;
            }
            let first = nodes[current.entry];
            let second = nodes[first.skip];
            let in_first = reaches(first, low, high);
            let in_second = reaches(second, low, high);
            if in_first == in_second {
                // Both children reach the cell, or (the parent's box reaching it between them) neither.
                node = select(BVH_END, node, in_first);
                break;
            }
            node = select(first.skip, current.entry, in_first);
            if in_first {
                current = first;
            } else {
                current = second;
            }
        }
        if node != BVH_END {
            start = node;
            stop = select(current.skip, grid.node_end, current.skip == BVH_END);
        }
    }
    primitives[grid.first_cell + 2u * id.x] = start;
    primitives[grid.first_cell + 2u * id.x + 1u] = stop;
}
