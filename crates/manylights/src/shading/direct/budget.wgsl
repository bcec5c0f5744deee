// Direct lighting `exact` with ray-traced shadows of the local lights flagged to cast them
// (`Light::flags`, LIGHT_CASTS_SHADOWS): one ray from the shading point to the light, within the
// point's budget of `frame.ray_options.w` rays — lights the light method enumerates after the budget
// is spent light the point unshadowed. The interface: `shading/direct/unshadowed.wgsl`.
#include "shading/light_bindings.wgsl"
#include "shading/direct/shadow_ray.wgsl"

// The point's shadow rays left.
var<private> direct_shadow_rays: u32;

fn direct_lights_begin(s: ShadingInput) {
    direct_shadow_rays = frame.ray_options.w;
}

fn direct_light(index: u32, instance_index: u32, sphere: vec4<f32>, instance: VolumeInstance, s: ShadingInput, radiance: vec3<f32>) -> vec3<f32> {
    if (lights[index].flags & LIGHT_CASTS_SHADOWS) == 0u || direct_shadow_rays == 0u {
        return radiance;
    }
    direct_shadow_rays -= 1u;
    return select(radiance, vec3<f32>(0.0), light_occluded(instance_point_to_world(instance, sphere.xyz), s));
}

fn direct_lights_end(s: ShadingInput) -> vec3<f32> {
    return vec3<f32>(0.0);
}
