// No local lights: the sun and ambient only, the baseline the methods' costs are measured against.
#include "shading/shading_input.wgsl"

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    return vec3<f32>(0.0);
}
