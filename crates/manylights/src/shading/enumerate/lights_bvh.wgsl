// Light enumeration through the lights' acceleration structure (Hansen & Peters 2021): a point query
// reaches the leaves whose box contains the shading point (walking as a subgroup, those of its
// neighbours too, `accel/volume_query.wgsl`); each light there gets the tight test
// inside `light_contribution` (range, cone), so the result equals the brute-force loop's.
#include "shading/enumerate/light_loop.wgsl"
#include "$LIGHT_QUERY" with VOLUMES=light

// The surface being shaded, and the same surface in the space of the instance the query is in
// (`shading_input_in_group`), with the falloff that undoes the instance's scale: set as the query
// enters each instance.
var<private> light_surface: ShadingInput;
var<private> light_surface_in_group: ShadingInput;
var<private> light_falloff: f32;

fn light_query_entered(instance: VolumeInstance) {
    light_surface_in_group = shading_input_in_group(light_surface, instance);
    light_falloff = instance_light_falloff(instance);
}

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    var shadow_rays = frame.ray_options.w;
    debug_lights_reaching = 0u;
    light_surface = s;
    light_query_begin(s.position, frame.light_instance_count);
    for (var leaf = light_query_next_leaf(); leaf.x != BVH_END; leaf = light_query_next_leaf()) {
        let instance = light_instances[light_query_instance_index];
        for (var k = leaf.x; k < leaf.y; k += 1u) {
            radiance += local_light_radiance(k, instance, s, light_surface_in_group, light_falloff, &shadow_rays);
        }
    }
    debug_light_work = light_query_visits;
    return radiance;
}
