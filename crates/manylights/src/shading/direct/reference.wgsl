// Direct lighting `reference`: every light that reaches a point, each with a shadow ray of its own —
// the ground truth that `restir` is measured against, at the cost of a ray per light. Every light is
// shadowed, whatever its `cast_shadows` flag (which chooses the lights `exact` spends its budget on).
// The interface: `shading/direct/unshadowed.wgsl`.
#include "shading/light_bindings.wgsl"
#include "shading/direct/shadow_ray.wgsl"

fn direct_lights_begin(s: ShadingInput) {}

fn direct_light(index: u32, instance_index: u32, sphere: vec4<f32>, instance: VolumeInstance, s: ShadingInput, radiance: vec3<f32>) -> vec3<f32> {
    return select(radiance, vec3<f32>(0.0), light_occluded(instance_point_to_world(instance, sphere.xyz), s));
}

fn direct_lights_end(s: ShadingInput) -> vec3<f32> {
    return vec3<f32>(0.0);
}
