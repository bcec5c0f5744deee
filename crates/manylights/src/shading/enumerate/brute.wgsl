// Light enumeration, brute force: every light for every shading point. The reference the accelerated
// methods are compared against. Every enumeration module defines `shade_local_lights` with this shape.
#include "shading/scene_bindings.wgsl"
#include "shading/lights.wgsl"

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    for (var i = 0u; i < frame.light_count; i += 1u) {
        // Most lights are out of range: test with the struct's first 16 bytes (position and range)
        // before loading the rest.
        let to_light = lights[i].position - s.position;
        let range = lights[i].range;
        if dot(to_light, to_light) < range * range {
            radiance += light_contribution(lights[i], s);
        }
    }
    return radiance;
}
