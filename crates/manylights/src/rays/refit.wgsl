// Refit of a deformed mesh's BLAS (`rays/refit.rs`) after `passes/deform.wgsl` moved its vertices:
// `refit_triangles` rebuilds each stored triangle (corner and edges) from the vertex buffer, then
// `refit_nodes` runs once per height of the trees, leaves first, each node's box the union of its
// triangles' (a leaf) or of its two children's, which an earlier dispatch wrote. Every deformed mesh
// of the frame's copy goes through each dispatch together. The trees' shape stays what the SAH builder
// made at rest: a refit, not a rebuild.
#include "shading/types.wgsl"
#include "rays/ray_types.wgsl"

// One dispatch's work: `count` triangles from `first`, or `count` nodes named by `order` from `first`;
// the copy's `mesh_count` deformed meshes from `meshes` in `deformed_meshes`.
struct RefitStep {
    first: u32,
    count: u32,
    meshes: u32,
    mesh_count: u32,
}

@group(0) @binding(0) var<uniform> step: RefitStep;
@group(0) @binding(1) var<storage, read> vertices: array<Vertex>;
@group(0) @binding(2) var<storage, read> indices: array<u32>;
// Each deformed mesh's primitives: (first index, base vertex).
@group(0) @binding(3) var<storage, read> primitives: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read> order: array<u32>;
@group(0) @binding(5) var<storage, read_write> nodes: array<BvhNode>;
@group(0) @binding(6) var<storage, read_write> triangles: array<RayTriangle>;
// Per deformed mesh and copy: its triangles [x, y) and its first primitive in `primitives` (z).
@group(0) @binding(7) var<storage, read> deformed_meshes: array<vec4<u32>>;

@compute @workgroup_size(64)
fn refit_triangles(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= step.count {
        return;
    }
    let k = step.first + id.x;
    // The mesh whose copy holds the triangle; the range may span others' triangles, left alone.
    var table = 0xffffffffu;
    for (var m = step.meshes; m < step.meshes + step.mesh_count; m += 1u) {
        let mesh = deformed_meshes[m];
        if k >= mesh.x && k < mesh.y {
            table = mesh.z;
        }
    }
    if table == 0xffffffffu {
        return;
    }
    var tri = triangles[k];
    let primitive = primitives[table + (tri.draw_offset & ~RAY_ALPHA_MASKED)];
    let first = primitive.x + 3u * tri.triangle;
    let v0 = vertices[primitive.y + indices[first]].position;
    let v1 = vertices[primitive.y + indices[first + 1u]].position;
    let v2 = vertices[primitive.y + indices[first + 2u]].position;
    tri.v0 = v0;
    tri.e1 = v1 - v0;
    tri.e2 = v2 - v0;
    triangles[k] = tri;
}

@compute @workgroup_size(64)
fn refit_nodes(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= step.count {
        return;
    }
    let n = order[step.first + id.x];
    let node = nodes[n];
    var lo = vec3<f32>(3.0e38);
    var hi = vec3<f32>(-3.0e38);
    if (node.entry & BVH_LEAF) != 0u {
        let range = bvh_leaf_range(node.entry);
        for (var k = range.x; k < range.y; k += 1u) {
            let tri = triangles[k];
            let v1 = tri.v0 + tri.e1;
            let v2 = tri.v0 + tri.e2;
            lo = min(lo, min(tri.v0, min(v1, v2)));
            hi = max(hi, max(tri.v0, max(v1, v2)));
        }
    } else {
        let first = nodes[node.entry];
        let second = nodes[first.skip];
        lo = min(first.min, second.min);
        hi = max(first.max, second.max);
    }
    nodes[n] = BvhNode(lo, node.entry, hi, node.skip);
}
