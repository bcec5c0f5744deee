// BVH nodes as `accel/bvh.rs` lays them out (keep in sync with `BvhNode` there): an internal node's
// `a` and `b` are its children; a leaf has `a` = BVH_LEAF | first and `b` = count, naming a range of
// the primitive index array. The root is node 0. Shared by the query (`bvh.wgsl`) and the GPU builder
// (`lbvh.wgsl`).

struct BvhNode {
    min: vec3<f32>,
    a: u32,
    max: vec3<f32>,
    b: u32,
}

const BVH_LEAF: u32 = 0x80000000u;
// Depth-first traversal keeps at most one pending sibling per level: builders keep depth ≤ 48
// (`bvh::MAX_DEPTH`), so 64 entries never overflow.
const BVH_STACK_SIZE: u32 = 64u;

// Inclusive on the faces, like the CPU query: a point on a volume's boundary is inside its box.
fn bvh_node_contains(node: BvhNode, p: vec3<f32>) -> bool {
    return all(p >= node.min) && all(p <= node.max);
}
