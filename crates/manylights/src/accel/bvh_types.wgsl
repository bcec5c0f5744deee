// BVH nodes as `accel/bvh.rs` lays them out (keep in sync with `BvhNode` there): an internal node's
// `a` and `b` are its children; a leaf has `a` = BVH_LEAF | first and `b` = count, naming a range of
// the primitive index array. A lone BVH's root is node 0; in a two-level structure the top level's root
// is node 0 and each group's is its instances' `blas_root`. Shared by the query (`volume_query.wgsl`)
// and the GPU builder (`lbvh.wgsl`).

struct BvhNode {
    min: vec3<f32>,
    a: u32,
    max: vec3<f32>,
    b: u32,
}

const BVH_LEAF: u32 = 0x80000000u;
// A two-level query's floor while it is in the top level (`volume_query.wgsl`).
const NO_FLOOR: u32 = 0xffffffffu;
// Depth-first traversal keeps at most one pending sibling per level, and a two-level query stacks a
// group's BVH on the top level's: the CPU builder keeps depth ≤ 48 (`bvh::MAX_DEPTH`), the LBVH ≤ 30
// Morton bits + 32 index bits, so 128 entries never overflow.
const BVH_STACK_SIZE: u32 = 128u;

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
