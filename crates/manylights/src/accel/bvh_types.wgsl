// BVH nodes as `accel/bvh.rs` lays them out (keep in sync with `BvhNode` there), for a traversal
// without a stack: `entry` is an internal node's first child (its second is that child's `skip`), or a
// leaf's `BVH_LEAF | (count − 1) << 24 | first`, naming a range of what the BVH's leaves index (a group's
// items in a volume structure, stored in leaf order; a top level's primitive indices); `skip`
// is the node after the subtree, where the traversal goes when the point is outside the box or after
// a leaf (BVH_END after the last). A lone BVH's root is node 0; in a two-level structure the top
// level's root is node 0 and each group's is its instances' `blas_root` (without ENTRY_GRID_FLAG). Shared by the query
// (`volume_query.wgsl`) and the GPU builder (`lbvh.wgsl`).

struct BvhNode {
    min: vec3<f32>,
    entry: u32,
    max: vec3<f32>,
    skip: u32,
}

// A light-structure node's emitters (`accel/light_tree.rs`, `LightTreeNode`): the box around its
// lights' positions, their total power and their largest range.
struct LightTreeNode {
    min: vec3<f32>,
    power: f32,
    max: vec3<f32>,
    range: f32,
}

const BVH_LEAF: u32 = 0x80000000u;
const BVH_END: u32 = 0xffffffffu;
const BVH_LEAF_COUNT_SHIFT: u32 = 24u;
const BVH_LEAF_FIRST_MASK: u32 = 0x00ffffffu;

// The range [x, y) a leaf's `entry` names.
fn bvh_leaf_range(entry: u32) -> vec2<u32> {
    let first = entry & BVH_LEAF_FIRST_MASK;
    return vec2<u32>(first, first + ((entry & ~BVH_LEAF) >> BVH_LEAF_COUNT_SHIFT) + 1u);
}

// One placement of a group of volumes (`accel/structure.rs`, `GpuVolumeInstance`): a similarity
// transform, stored as rows applied as `vec4(p, 1.0) * matrix`.
struct VolumeInstance {
    group_from_world: mat3x4<f32>,
    world_from_group: mat3x4<f32>,
    first_item: u32,
    item_count: u32,
    blas_root: u32,
    // Uniform scale of `world_from_group`.
    scale: f32,
}

// Instance 0 and its group's entry-grid or cell-list header (`accel/structure.rs`, `GpuFirstInstance`),
// in a uniform buffer: a query over a lone instance starts from them without two dependent storage
// loads.
struct FirstInstance {
    instance: VolumeInstance,
    entry_grid_header: BvhNode,
}

// Set in `VolumeInstance::blas_root` when the group has an entry grid (`accel/entry_grid.rs`).
const ENTRY_GRID_FLAG: u32 = 0x80000000u;

// Set in an entry-grid header's `skip`, above the cells per axis, when the grid is of a group rebuilt
// on the GPU (`accel/rebuilt_grid.rs`): its cells name single subtrees of an LBVH, which walks alone
// start at; walks merging their lanes' cells into one range start at the root instead.
const ENTRY_GRID_REBUILT: u32 = 0x40000000u;

// Set in an entry-grid cell's second word when the cell names a cover of several subtrees
// (`accel/entry_grid.rs`, `CELL_COVER`): bits 27–30 hold their count − 1, bits 0–26 the primitive
// index where their (start, stop) pairs begin.
const ENTRY_CELL_COVER: u32 = 0x80000000u;

// The range [x, y) of the primitive array holding a cover's (start, stop) pairs, from its cell's
// second word.
fn entry_cell_cover_pairs(word: u32) -> vec2<u32> {
    let first = word & 0x07ffffffu;
    return vec2<u32>(first, first + 2u * (((word >> 27u) & 15u) + 1u));
}

// Cells per axis of the grid `header` describes (`entry_grid_cell`).
fn entry_grid_dims(header: BvhNode) -> vec3<u32> {
    return (vec3<u32>(header.skip) >> vec3<u32>(0u, 10u, 20u)) & vec3<u32>(1023u);
}

// The first word of the entry-grid cell holding the group-space point `p`, clamped into the grid (the
// CPU's twin is `EntryGrid::cell_of`; cell lists, `accel/cell_lists.rs`, share the header and lookup,
// their cells two words too: where the cell's list begins and ends). `header` is the node before the group's root (`structure.rs`,
// `GroupGrid::gpu_words`): the grid's corner (min), its first cell in the primitives array (entry), cells
// per unit length (max) and cells per axis, 10 bits each (skip). A cell is two words: the node to
// start at and the node the query stops at, or, with ENTRY_CELL_COVER, where its cover's pairs are.
fn entry_grid_cell(header: BvhNode, p: vec3<f32>) -> u32 {
    return header.entry + 2u * cell_list_index(header, p);
}

// The index of the grid cell holding the group-space point `p`, clamped into the grid, x fastest: the
// cell of an entry grid or of cell lists (`entry_grid_cell`), or of lists built on the GPU
// (`accel/rebuilt_cell_lists.rs`, whose header has no first cell; the CPU's twin is
// `ListPlacement::cell_of`).
fn cell_list_index(header: BvhNode, p: vec3<f32>) -> u32 {
    let dims = entry_grid_dims(header);
    let cell = vec3<u32>(clamp(floor((p - header.min) * header.max), vec3<f32>(0.0), vec3<f32>(dims - 1u)));
    return (cell.z * dims.y + cell.y) * dims.x + cell.x;
}

fn instance_point_to_group(instance: VolumeInstance, p: vec3<f32>) -> vec3<f32> {
    return vec4<f32>(p, 1.0) * instance.group_from_world;
}

fn instance_point_to_world(instance: VolumeInstance, p: vec3<f32>) -> vec3<f32> {
    return vec4<f32>(p, 1.0) * instance.world_from_group;
}

fn instance_vector_to_group(instance: VolumeInstance, v: vec3<f32>) -> vec3<f32> {
    return vec4<f32>(v, 0.0) * instance.group_from_world;
}

// Rotates a direction into the world, keeping its length (the scale is divided out).
fn instance_direction_to_world(instance: VolumeInstance, d: vec3<f32>) -> vec3<f32> {
    return (vec4<f32>(d, 0.0) * instance.world_from_group) / instance.scale;
}

// Inclusive on the faces, like the CPU query: a point on a volume's boundary is inside its box.
fn bvh_node_contains(node: BvhNode, p: vec3<f32>) -> bool {
    return all(p >= node.min) && all(p <= node.max);
}
