// Light enumeration through the GPU's ray queries (the hardware back end, `accel/hardware.rs`), as
// Hansen & Peters do it: a ray query of minimal length from the shading point into the top level
// over the light groups' instances, whose bottom levels hold one box per light. Every box candidate
// is a light whose box holds the point; it gets the same tight test as every other method inside
// `local_light_radiance` (range, cone) and is accumulated without committing, so the query runs
// through every candidate and the result equals the brute-force loop's.
enable wgpu_ray_query;
#include "shading/enumerate/light_loop.wgsl"
#include "shading/volume_ray_query.wgsl"

// Bound after the lights' other bindings (`accel/structure.rs`, `hardware_binding`).
@group(2) @binding(8) var light_tlas: acceleration_structure;

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    direct_lights_begin(s);
    debug_lights_reaching = 0u;
    debug_light_work = 0u;
    var query: ray_query;
    rayQueryInitialize(&query, light_tlas, volume_ray_at(s.position));
    // Candidates come instance by instance in practice, so the surface is taken into an instance's
    // space when the instance changes.
    var entered = VOLUME_RAY_NO_INSTANCE;
    var local = s;
    var falloff = 1.0;
    var instance: VolumeInstance;
    while rayQueryProceed(&query) {
        let candidate = rayQueryGetCandidateIntersection(&query);
        let instance_index = candidate.instance_custom_data;
        if instance_index != entered {
            entered = instance_index;
            instance = light_instances[instance_index];
            local = shading_input_in_group(s, instance);
            falloff = instance_light_falloff(instance);
        }
        debug_light_work += 1u;
        radiance += local_light_radiance(instance.first_item + candidate.primitive_index, instance_index, instance, s, local, falloff);
    }
    return radiance + direct_lights_end(s);
}
