// One light of a light enumeration loop, shared by every method (`lights_*.wgsl`): the range test,
// then the light's contribution, counted for the debug views, times its shadow ray's visibility.
#include "shading/light_bindings.wgsl"
#include "shading/lights.wgsl"
#include "$LIGHT_SHADOWS"
#include "shading/debug_view.wgsl"

// Whether light `index` can reach `p` (group space) by its range. Most lights a loop meets are out of
// range, so it reads the record's first 16 bytes (position and range) and the rest is loaded only for
// lights that pass: a million particle lights shade 12 % faster through the BVH (BENCHMARKS.md).
fn light_in_range(index: u32, p: vec3<f32>) -> bool {
    let to_light = lights[index].position - p;
    let range = lights[index].range;
    return dot(to_light, to_light) < range * range;
}

// The radiance light `index`, of the group `instance` places, adds at the surface: `local` is the
// surface `s` in the group's space (`shading_input_in_group`), `falloff` undoes the instance's scale,
// and `shadow_rays` is what is left of the point's budget of lamp-shadow rays.
fn local_light_radiance(
    index: u32,
    instance: VolumeInstance,
    s: ShadingInput,
    local: ShadingInput,
    falloff: f32,
    shadow_rays: ptr<function, u32>,
) -> vec3<f32> {
    if !light_in_range(index, local.position) {
        return vec3<f32>(0.0);
    }
    let light = lights[index];
    let contribution = light_contribution(light, local);
    if !any(contribution > vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    if DEBUG_VIEWS {
        debug_lights_reaching += 1u;
    }
    return contribution * falloff * light_visibility(light, instance, s, shadow_rays);
}
