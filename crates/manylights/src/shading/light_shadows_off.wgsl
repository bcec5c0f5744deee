// No shadow rays towards local lights (`--light-shadow-rays 0`): every light that reaches a point
// lights it. Chosen as `$LIGHT_SHADOWS` so that frames without lamp shadows compile no ray traversal
// into the light loops, whose registers it would otherwise claim.
#include "shading/light_bindings.wgsl"

fn light_visibility(index: u32, sphere: vec4<f32>, instance: VolumeInstance, s: ShadingInput, budget: ptr<function, u32>) -> f32 {
    return 1.0;
}
