// Ray traversal by the GPU's ray queries (the hardware back end, `rays/hardware.rs`; the software
// twin is `rays/trace.wgsl`, and the plan picks one as `$RAY_TRACE`): the same `trace_any_hit`,
// `trace_closest` and hits, through a top level wgpu builds over the scene's instances (custom index:
// the instance in `ray_instances`) and a bottom level per stored BLAS over the same triangles in the
// same order (primitive k: `ray_triangles[instance.first_triangle + k]`). Meshes with alpha-masked
// triangles are not opaque to the hardware: their triangles come back as candidates, confirmed where
// opaque or where the material's alpha passes, as the software traversal tests them. Both faces
// count, and t is along the world ray's direction unnormalised, as there.
enable wgpu_ray_query;
#include "rays/ray_hit.wgsl"

// After the scene's other bindings (`gpu/scene.rs`), with the hardware back end only.
@group(0) @binding(31) var ray_tlas: acceleration_structure;

fn ray_query_trace(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, flags: u32) -> RayHit {
    var query: ray_query;
    rayQueryInitialize(&query, ray_tlas, RayDesc(flags, 0xffu, 0.0, t_max, origin, dir));
    while rayQueryProceed(&query) {
        let candidate = rayQueryGetCandidateIntersection(&query);
        let instance = ray_instances[candidate.instance_custom_data];
        let tri = ray_triangles[instance.first_triangle + candidate.primitive_index];
        let b = candidate.barycentrics;
        if (tri.draw_offset & RAY_ALPHA_MASKED) == 0u || ray_alpha_covers(instance, tri, b.x, b.y) {
            rayQueryConfirmIntersection(&query);
        }
    }
    let hit = rayQueryGetCommittedIntersection(&query);
    if hit.kind == RAY_QUERY_INTERSECTION_NONE {
        return RayHit(t_max, RAY_NO_HIT, 0u, 0.0, 0.0);
    }
    let first_triangle = ray_instances[hit.instance_custom_data].first_triangle;
    return RayHit(hit.t, first_triangle + hit.primitive_index, hit.instance_custom_data, hit.barycentrics.x, hit.barycentrics.y);
}

// The first hit the hardware finds along origin + t · dir with 0 < t < t_max.
fn trace_any_hit(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> RayHit {
    return ray_query_trace(origin, dir, t_max, RAY_FLAG_TERMINATE_ON_FIRST_HIT);
}

// Whether anything lies on the segment from `origin` along `dir` before `t_max`.
fn ray_occluded(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    return trace_any_hit(origin, dir, t_max).triangle != RAY_NO_HIT;
}

// The nearest hit along origin + t · dir with 0 < t < t_max.
fn trace_closest(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> RayHit {
    return ray_query_trace(origin, dir, t_max, RAY_FLAG_NONE);
}
