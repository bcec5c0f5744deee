#include "shading/scene_bindings.wgsl"
#include "shading/lights.wgsl"

// Light enumeration, brute force: every light for every shading point. The reference the accelerated
// methods are compared against. Every enumeration module defines `shade_local_lights` with this shape.

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    for (var i = 0u; i < frame.light_count; i += 1u) {
        radiance += light_contribution(lights[i], s);
    }
    return radiance;
}
