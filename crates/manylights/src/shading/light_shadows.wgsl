// Ray-traced shadows of local lights flagged to cast them (`Light::flags`, LIGHT_CASTS_SHADOWS): one
// ray from the shading point to the light, within the point's budget of `frame.ray_options.w` rays —
// lights the light method enumerates after the budget is spent light the point unshadowed. Every
// light enumeration module calls it for each light that lights the point, so every method, pipeline
// and reflection hit is shadowed alike.
#include "shading/light_bindings.wgsl"
#include "rays/trace.wgsl"

// 0 when something lies between the point and light `index` (its sphere `sphere`, in its group's space,
// placed by `instance`), else 1. `budget` counts the point's remaining shadow rays down.
fn light_visibility(index: u32, sphere: vec4<f32>, instance: VolumeInstance, s: ShadingInput, budget: ptr<function, u32>) -> f32 {
    if (lights[index].flags & LIGHT_CASTS_SHADOWS) == 0u || *budget == 0u {
        return 1.0;
    }
    *budget -= 1u;
    let origin = ray_offset_origin(s.position, s.ray_normal, s.ray_clearance);
    // The segment to the light, short of it by a hair: t runs from 0 at the origin to 1 at the light.
    let to_light = instance_point_to_world(instance, sphere.xyz) - origin;
    return select(1.0, 0.0, ray_occluded(origin, to_light, 0.9999));
}
