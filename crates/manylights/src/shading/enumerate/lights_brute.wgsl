// Light enumeration, brute force: every light of every instance for every shading point. The
// reference the accelerated methods are compared against. Every light enumeration module defines
// `shade_local_lights` with this shape.
#include "shading/enumerate/light_loop.wgsl"

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    direct_lights_begin(s);
    debug_lights_reaching = 0u;
    debug_light_work = 0u;
    for (var i = 0u; i < frame.light_instance_count; i += 1u) {
        let instance = light_instances[i];
        let local = shading_input_in_group(s, instance);
        let falloff = instance_light_falloff(instance);
        debug_light_work += instance.item_count;
        for (var k = instance.first_item; k < instance.first_item + instance.item_count; k += 1u) {
            radiance += local_light_radiance(k, i, instance, s, local, falloff);
        }
    }
    return radiance + direct_lights_end(s);
}
