// The scene's ray-tracing hierarchy (`rays/mod.rs`, keep in sync with `RayTriangle` and
// `RayInstance` there): BVH nodes as the volume structures lay them out (`accel/bvh_types.wgsl`),
// the top level (TLAS) from node 0 with one instance per leaf, each mesh's BLAS after it; a leaf's
// `entry` names its triangles (BLAS) or its instance (TLAS) directly.
#include "accel/bvh_types.wgsl"

// Set in `RayTriangle::draw_offset` for alpha-masked materials.
const RAY_ALPHA_MASKED: u32 = 0x80000000u;

// A triangle in its mesh's space: one corner and the two edges from it.
struct RayTriangle {
    v0: vec3<f32>,
    // The primitive within the mesh (the draw is the instance's `first_draw` plus this), with
    // RAY_ALPHA_MASKED.
    draw_offset: u32,
    e1: vec3<f32>,
    // The triangle within its primitive: indices from `draw.first_index + 3 · triangle`.
    triangle: u32,
    e2: vec3<f32>,
    _pad0: u32,
}

struct RayInstance {
    // Rows of the map from the world into the mesh's space, applied as `vec4(p, 1.0) * local_from_world`.
    local_from_world: mat3x4<f32>,
    blas_root: u32,
    first_draw: u32,
    scene_instance: u32,
    // The first triangle of its BLAS in `ray_triangles` (the hardware back end's primitive 0).
    first_triangle: u32,
}
