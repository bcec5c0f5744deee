// Group 2: a BVH (`accel/gpu.rs`, `LightBvhBuffers`). Keep in sync with its layout.
@group(2) @binding(0) var<storage, read> bvh_nodes: array<BvhNode>;
@group(2) @binding(1) var<storage, read> bvh_primitives: array<u32>;
