#include "accel/bvh_bindings.wgsl"

// BVH nodes as `accel/bvh.rs` lays them out (keep in sync with `BvhNode` there): an internal node's
// `a` and `b` are its children; a leaf has `a` = BVH_LEAF | first and `b` = count, naming
// `bvh_primitives[first .. first + count]`. The root is node 0.
//
// The point query — the paper's zero-length ray — is a cursor: `bvh_query_next` returns the primitives
// of every leaf whose box contains the point, one at a time, so the caller applies its own tight test
// (light range and cone, decal box) without a copy of the traversal per use.

struct BvhNode {
    min: vec3<f32>,
    a: u32,
    max: vec3<f32>,
    b: u32,
}

const BVH_LEAF: u32 = 0x80000000u;
const BVH_NONE: u32 = 0xffffffffu;
// Depth-first traversal keeps at most one pending sibling per level: builders keep depth ≤ 48
// (`bvh::MAX_DEPTH`), so 64 entries never overflow.
const BVH_STACK_SIZE: u32 = 64u;

// Inclusive on the faces, like the CPU query: a point on a volume's boundary is inside its box.
fn bvh_node_contains(node: BvhNode, p: vec3<f32>) -> bool {
    return all(p >= node.min) && all(p <= node.max);
}

struct BvhQuery {
    point: vec3<f32>,
    stack: array<u32, BVH_STACK_SIZE>,
    top: u32,
    // The rest of the current leaf's primitive range.
    next: u32,
    end: u32,
}

// Starts a point query; `node_count` 0 means an empty BVH.
fn bvh_query_begin(point: vec3<f32>, node_count: u32) -> BvhQuery {
    var query: BvhQuery;
    query.point = point;
    query.stack[0] = 0u;
    query.top = select(0u, 1u, node_count > 0u);
    query.next = 0u;
    query.end = 0u;
    return query;
}

// The next primitive of a leaf whose box contains the point, or BVH_NONE when there is none left.
fn bvh_query_next(query: ptr<function, BvhQuery>) -> u32 {
    while (*query).next < (*query).end || (*query).top > 0u {
        if (*query).next < (*query).end {
            let primitive = bvh_primitives[(*query).next];
            (*query).next += 1u;
            return primitive;
        }
        (*query).top -= 1u;
        let node = bvh_nodes[(*query).stack[(*query).top]];
        if !bvh_node_contains(node, (*query).point) {
            continue;
        }
        if (node.a & BVH_LEAF) != 0u {
            (*query).next = node.a & ~BVH_LEAF;
            (*query).end = (*query).next + node.b;
        } else {
            (*query).stack[(*query).top] = node.a;
            (*query).stack[(*query).top + 1u] = node.b;
            (*query).top += 2u;
        }
    }
    return BVH_NONE;
}
