// Decal enumeration, brute force: every decal of every instance for every shading point; the
// reference for the accelerated method. Every decal enumeration module defines `apply_decals`.
#include "shading/decal_bindings.wgsl"
#include "shading/decals.wgsl"

fn apply_decals(s: ShadingInput, dp: PositionGradients) -> ShadingInput {
    decal_blend_begin();
    for (var i = 0u; i < frame.decal_instance_count; i += 1u) {
        let instance = decal_instances[i];
        let local = instance_point_to_group(instance, s.position);
        let surface = decal_surface_in_group(decal_world_surface(s, dp), instance);
        for (var k = instance.first_item; k < instance.first_item + instance.item_count; k += 1u) {
            decal_accumulate(k, instance, local, surface);
        }
    }
    return decal_blend_end(s);
}
