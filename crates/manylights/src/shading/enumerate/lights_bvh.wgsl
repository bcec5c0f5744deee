// Light enumeration through the lights' acceleration structure (Hansen & Peters 2021): a point query
// reaches only the leaves whose box contains the shading point; each light there gets the tight test
// inside `light_contribution` (range, cone), so the result equals the brute-force loop's.
#include "shading/enumerate/light_loop.wgsl"
#include "$LIGHT_QUERY" with VOLUMES=light

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    var shadow_rays = frame.ray_options.w;
    // The surface in the space of the instance being visited (`shading_input_in_group`).
    var local = s;
    var falloff = 1.0;
    var entered = 0xffffffffu;
    debug_lights_reaching = 0u;
    light_query_begin(s.position, frame.light_instance_count);
    for (var leaf = light_query_next_leaf(); leaf.x != BVH_END; leaf = light_query_next_leaf()) {
        if light_query_instance_index != entered {
            entered = light_query_instance_index;
            local = shading_input_in_group(s, light_query_instance);
            falloff = 1.0 / (light_query_instance.scale * light_query_instance.scale);
        }
        for (var k = leaf.x; k < leaf.y; k += 1u) {
            radiance += local_light_radiance(k, light_query_instance, s, local, falloff, &shadow_rays);
        }
    }
    debug_light_work = light_query_visits;
    return radiance;
}
