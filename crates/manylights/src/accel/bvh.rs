//! BVH node layout shared with WGSL, the CPU builder and the CPU point query.

/// Set in `BvhNode::a` of a leaf.
pub const LEAF: u32 = 1 << 31;

/// One BVH node, 32 bytes. Keep in sync with `BvhNode` in `accel/bvh.wgsl`.
///
/// Internal node: `a` = left child, `b` = right child (node indices).
/// Leaf: `a` = `LEAF | first`, `b` = count: the leaf's primitives are
/// `Bvh::primitive_indices[first..first + count]`.
/// The root is node 0; an empty BVH has no nodes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub a: u32,
    pub max: [f32; 3],
    pub b: u32,
}

/// A BVH as uploaded: nodes (root first) and the primitive indices its leaves point into.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub primitive_indices: Vec<u32>,
}
