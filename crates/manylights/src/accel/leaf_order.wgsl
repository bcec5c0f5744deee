// Stores a structure's items in leaf order after its groups' BVHs were rebuilt on the GPU
// (`accel/leaf_order.rs`): item i becomes the scene's item `primitives[first_primitive + i]`, the
// scene index the builds (and, for CPU-built groups, the upload) left at leaf position i. Group
// leaves name their items directly, so a query reads a leaf's items side by side, without an index.

struct LeafOrderParams {
    count: u32,
    first_primitive: u32,
    vec4s_per_item: u32,
    // Invocations per row of the 2D dispatch.
    row_threads: u32,
}

@group(0) @binding(0) var<uniform> params: LeafOrderParams;
// The items in scene order.
@group(0) @binding(1) var<storage, read> scene_items: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> primitives: array<u32>;
// The items the shaders read, in leaf order.
@group(0) @binding(3) var<storage, read_write> items: array<vec4<u32>>;

// One invocation per 16 bytes: neighbouring invocations copy one item's consecutive parts, so each
// item is read and written in whole segments; an invocation per item, looping over its parts,
// strides through memory and is slower (benchmarks/LOG.md, topic 4).
@compute @workgroup_size(256)
fn leaf_order(@builtin(global_invocation_id) id: vec3<u32>) {
    let t = id.y * params.row_threads + id.x;
    let i = t / params.vec4s_per_item;
    if i >= params.count {
        return;
    }
    let part = t % params.vec4s_per_item;
    items[t] = scene_items[primitives[params.first_primitive + i] * params.vec4s_per_item + part];
}
