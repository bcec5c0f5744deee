// Light enumeration through clustered shading (Olsson, Billeter & Assarsson 2012): the lights listed
// for the shading point's froxel (`accel/cluster_grid.wgsl`), built this frame on the GPU
// (`accel/cluster_build.wgsl`); each gets the tight test inside `light_contribution`, so the result
// equals the brute-force loop's for every point in the view frustum. Points outside it (a
// reflection's hit point) find a froxel that does not list their lights: the method's limit.
#include "shading/enumerate/light_loop.wgsl"
#include "accel/cluster_grid.wgsl"

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    var local = s;
    var falloff = 1.0;
    var entered = 0xffffffffu;
    var instance: VolumeInstance;
    direct_lights_begin(s);
    let range = light_cluster_ranges[cluster_of(s.position)];
    debug_lights_reaching = 0u;
    debug_light_work = range.y;
    for (var i = range.x; i < range.x + range.y; i += 1u) {
        let entry = light_cluster_entries[i];
        if entry.x != entered {
            entered = entry.x;
            instance = light_instances[entry.x];
            local = shading_input_in_group(s, instance);
            falloff = instance_light_falloff(instance);
        }
        radiance += local_light_radiance(entry.y, entry.x, instance, s, local, falloff);
    }
    return radiance + direct_lights_end(s);
}
