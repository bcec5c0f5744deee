#include "accel/bvh_types.wgsl"
#include "accel/bvh_bindings.wgsl"

// The point query — the paper's zero-length ray — is a cursor: `bvh_query_next_leaf` returns every leaf
// whose box contains the point, and the caller applies its own tight test to the leaf's primitives
// (light range and cone, decal box) without a copy of the traversal per use.

// The query in flight, one per invocation. It hands out whole leaves, and the caller loops over their
// primitives: a cursor returning one primitive per call measured 20 % slower shading on the H200.
var<private> bvh_query_point: vec3<f32>;
var<private> bvh_query_stack: array<u32, BVH_STACK_SIZE>;
var<private> bvh_query_top: u32;

// Starts a point query, replacing any query in flight; `node_count` 0 means an empty BVH.
fn bvh_query_begin(point: vec3<f32>, node_count: u32) {
    bvh_query_point = point;
    bvh_query_stack[0] = 0u;
    bvh_query_top = select(0u, 1u, node_count > 0u);
}

// The next leaf whose box contains the point, as the range [x, y) of `bvh_primitives`; an empty range
// when the query is done (leaves are never empty).
fn bvh_query_next_leaf() -> vec2<u32> {
    while bvh_query_top > 0u {
        bvh_query_top -= 1u;
        let node = bvh_nodes[bvh_query_stack[bvh_query_top]];
        if !bvh_node_contains(node, bvh_query_point) {
            continue;
        }
        if (node.a & BVH_LEAF) != 0u {
            let first = node.a & ~BVH_LEAF;
            return vec2<u32>(first, first + node.b);
        }
        bvh_query_stack[bvh_query_top] = node.a;
        bvh_query_stack[bvh_query_top + 1u] = node.b;
        bvh_query_top += 2u;
    }
    return vec2<u32>(0u);
}
