// Light enumeration through a BVH over the lights' volumes (Hansen & Peters 2021): a point query
// reaches only the leaves whose box contains the shading point; each light there gets the tight test
// inside `light_contribution` (range, cone), so the result equals the brute-force loop's.
#include "shading/scene_bindings.wgsl"
#include "shading/lights.wgsl"
#include "accel/bvh.wgsl"

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    bvh_query_begin(s.position, select(0u, arrayLength(&bvh_nodes), frame.light_count > 0u));
    for (var leaf = bvh_query_next_leaf(); leaf.x < leaf.y; leaf = bvh_query_next_leaf()) {
        for (var k = leaf.x; k < leaf.y; k += 1u) {
            radiance += light_contribution(lights[bvh_primitives[k]], s);
        }
    }
    return radiance;
}
