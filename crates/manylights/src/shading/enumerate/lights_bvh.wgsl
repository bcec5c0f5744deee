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
// Walking as a subgroup: the box around the lanes' surfaces in the group's space.
var<private> light_walk_box: array<vec3<f32>, 2>;

fn light_query_entered(instance: VolumeInstance) {
    light_surface_in_group = shading_input_in_group(light_surface, instance);
    light_falloff = instance_light_falloff(instance);
    if light_walk_shared() {
        light_walk_box = light_walk_bounds(light_surface_in_group.position);
    }
}

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    direct_lights_begin(s);
    debug_lights_reaching = 0u;
    light_surface = s;
    light_query_begin(s.position, frame.light_instance_count);
    // Counted once, so every lane counted here must stay in the query to its end, or its share of
    // each later leaf goes untested: every loop of the shared walk runs the same trips in every lane
    // (docs/ARCHITECTURE.md, "Acceleration structures", the point query: helper lanes, reflections).
    let lanes = light_walk_lanes();
    for (var leaf = light_query_next_leaf(); leaf.x != BVH_END; leaf = light_query_next_leaf()) {
        let instance_index = light_query_instance_index;
        let instance = light_instances[instance_index];
        if !light_walk_shared() {
            for (var k = leaf.x; k < leaf.y; k += 1u) {
                radiance += local_light_radiance(k, instance_index, instance, s, light_surface_in_group, light_falloff);
            }
            continue;
        }
        // The subgroup's leaf: each lane tests one light against the box around all the lanes'
        // points, then every lane takes the lights some lane kept, one after the other, their index
        // and sphere from the lanes that read them. The shuffles run before any lane's own test: a
        // lane shuffles only from active lanes (SPIR-V leaves a shuffle from an inactive lane undefined).
        // Lanes past the leaf's end read its last light and keep none. Only the ballot's words that
        // hold lanes are read: one on 32-lane subgroups.
        for (var first = leaf.x; first < leaf.y; first += lanes.y) {
            let k = first + lanes.x;
            let sphere = light_sphere(min(k, leaf.y - 1u));
            let kept = light_walk_ballot(k < leaf.y && sphere_meets_box(sphere, light_walk_box[0], light_walk_box[1]));
            for (var word = 0u; word < lanes.z; word += 1u) {
                for (var bits = kept[word]; bits != 0u; bits &= bits - 1u) {
                    let lane = word * 32u + firstTrailingBit(bits);
                    let light = light_walk_lane_u32(k, lane);
                    let lane_sphere = light_walk_lane_vec4(sphere, lane);
                    if sphere_may_light(lane_sphere, light_surface_in_group) {
                        radiance += light_radiance_in_range(light, lane_sphere, instance_index, instance, s, light_surface_in_group, light_falloff);
                    }
                }
            }
        }
    }
    debug_light_work = light_query_visits;
    return radiance + direct_lights_end(s);
}
