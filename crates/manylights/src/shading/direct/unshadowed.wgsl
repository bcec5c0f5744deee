// Direct lighting `exact` without shadow rays (`--light-shadow-rays 0`): every light that reaches a
// point lights it. Chosen as `$DIRECT_LIGHTING` so that frames without lamp shadows compile no ray
// traversal into the light loops, whose registers it would otherwise claim.
//
// Every `$DIRECT_LIGHTING` module (`shading/direct/*.wgsl`) defines the same three functions, which
// each light enumeration module (`shading/enumerate/lights_*.wgsl`, through `light_loop.wgsl`) calls:
// `direct_lights_begin` before a point's lights, `direct_light` for each light that reaches it (its
// record, its instance's index and record, its sphere in its group's space) with its unshadowed
// radiance, and `direct_lights_end` after the last.
#include "shading/light_bindings.wgsl"

fn direct_lights_begin(s: ShadingInput) {}

fn direct_light(index: u32, instance_index: u32, sphere: vec4<f32>, instance: VolumeInstance, s: ShadingInput, radiance: vec3<f32>) -> vec3<f32> {
    return radiance;
}

fn direct_lights_end(s: ShadingInput) -> vec3<f32> {
    return vec3<f32>(0.0);
}
