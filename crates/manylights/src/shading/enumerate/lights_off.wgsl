// No local lights: the sun and ambient only, the baseline the methods' costs are measured against.
#include "shading/shading_input.wgsl"
#include "shading/debug_view.wgsl"

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    debug_lights_reaching = 0u;
    debug_light_work = 0u;
    return vec3<f32>(0.0);
}
