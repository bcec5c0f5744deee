// Light enumeration through the lights' acceleration structure (Hansen & Peters 2021): a point query
// reaches only the leaves whose box contains the shading point; each light there gets the tight test
// inside `light_contribution` (range, cone), so the result equals the brute-force loop's.
#include "shading/light_bindings.wgsl"
#include "shading/lights.wgsl"
#include "accel/volume_query.wgsl" with VOLUMES=light

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    light_query_begin(s.position, frame.light_instance_count);
    for (var leaf = light_query_next_leaf(); leaf.x < leaf.y; leaf = light_query_next_leaf()) {
        for (var k = leaf.x; k < leaf.y; k += 1u) {
            radiance += light_contribution(light_in_world(lights[light_primitives[k]], light_query_instance), s);
        }
    }
    return radiance;
}
