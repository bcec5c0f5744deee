// Decal enumeration through the GPU's ray queries (the hardware back end, `accel/hardware.rs`): a ray
// query of minimal length from the shading point into the top level over the decal groups'
// instances, whose bottom levels hold one box per decal. Every box candidate gets the exact box test
// in `decal_accumulate` and is blended without committing; blending within a layer is
// order-independent, so the result equals the brute-force loop's.
enable wgpu_ray_query;
#include "shading/decal_bindings.wgsl"
#include "shading/decals.wgsl"
#include "shading/volume_ray_query.wgsl"

// Bound after the decals' other bindings (`accel/structure.rs`, `hardware_binding`).
@group(3) @binding(7) var decal_tlas: acceleration_structure;

fn apply_decals(s: ShadingInput, dp: PositionGradients) -> ShadingInput {
    decal_blend_begin();
    let world = decal_world_surface(s, dp);
    var query: ray_query;
    rayQueryInitialize(&query, decal_tlas, volume_ray_at(s.position));
    var entered = VOLUME_RAY_NO_INSTANCE;
    var instance: VolumeInstance;
    var local = vec3<f32>(0.0);
    var surface = world;
    while rayQueryProceed(&query) {
        let candidate = rayQueryGetCandidateIntersection(&query);
        let instance_index = candidate.instance_custom_data;
        if instance_index != entered {
            entered = instance_index;
            instance = decal_instances[instance_index];
            local = instance_point_to_group(instance, s.position);
            surface = decal_surface_in_group(world, instance);
        }
        decal_accumulate(instance.first_item + candidate.primitive_index, instance, local, surface);
    }
    return decal_blend_end(s);
}
