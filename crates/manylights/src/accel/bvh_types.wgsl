// BVH nodes as `accel/bvh.rs` lays them out (keep in sync with `BvhNode` there), for a traversal
// without a stack: `entry` is an internal node's first child (its second is that child's `skip`), or a
// leaf's `BVH_LEAF | (count − 1) << 27 | first`, naming a range of the primitive index array; `skip`
// is the node after the subtree, where the traversal goes when the point is outside the box or after
// a leaf (BVH_END after the last). A lone BVH's root is node 0; in a two-level structure the top
// level's root is node 0 and each group's is its instances' `blas_root`. Shared by the query
// (`volume_query.wgsl`) and the GPU builder (`lbvh.wgsl`).

struct BvhNode {
    min: vec3<f32>,
    entry: u32,
    max: vec3<f32>,
    skip: u32,
}

const BVH_LEAF: u32 = 0x80000000u;
const BVH_END: u32 = 0xffffffffu;
const BVH_LEAF_COUNT_SHIFT: u32 = 27u;
const BVH_LEAF_FIRST_MASK: u32 = 0x07ffffffu;

// The range [x, y) of the primitive index array a leaf's `entry` names.
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
    // The group's entry grid (`accel/entry_grid.rs`), in group space: its corner, its first cell's
    // word in the primitives array (NO_ENTRY_GRID: queries start at `blas_root`), cells per unit
    // length, and cells per axis, 10 bits each, x lowest. A cell is two words: where the query starts
    // (a node, or with BVH_LEAF set a leaf's range) and the node it stops at.
    grid_min: vec3<f32>,
    grid_first_cell: u32,
    grid_cells_per_unit: vec3<f32>,
    grid_dims: u32,
}

const NO_ENTRY_GRID: u32 = 0xffffffffu;

// The first word of the entry-grid cell holding the group-space point `p`, clamped into the grid (the
// CPU's twin is `EntryGrid::cell_of`). The instance must have a grid.
fn instance_grid_cell(instance: VolumeInstance, p: vec3<f32>) -> u32 {
    let dims = (vec3<u32>(instance.grid_dims) >> vec3<u32>(0u, 10u, 20u)) & vec3<u32>(1023u);
    let cell = vec3<u32>(clamp(floor((p - instance.grid_min) * instance.grid_cells_per_unit), vec3<f32>(0.0), vec3<f32>(dims - 1u)));
    return instance.grid_first_cell + 2u * ((cell.z * dims.y + cell.y) * dims.x + cell.x);
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
