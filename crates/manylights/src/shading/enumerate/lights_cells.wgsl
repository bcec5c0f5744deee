// Light enumeration through cell lists built on the GPU (`accel/rebuilt_cell_lists.rs`): where the
// lights are one sparse group placed once, built once or every frame, a grid over the group
// lists, per cell, every light whose sphere may reach it, and a point's query is its cell's list — no
// walk. Each light gets the tight test inside `light_contribution` (range, cone), so the result equals
// the brute-force loop's. Points outside the grid read a cell on its faces, which reach out to
// infinity, so reflections' hits far away are lit exactly too. The lists hold (instance, light) pairs
// as the clustered lists do; the instance is the lone one, `light_first_instance`.
#include "shading/enumerate/light_loop.wgsl"

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    direct_lights_begin(s);
    let instance = light_first_instance.instance;
    let local = shading_input_in_group(s, instance);
    let falloff = instance_light_falloff(instance);
    let range = light_cluster_ranges[cell_list_index(light_first_instance.entry_grid_header, local.position)];
    debug_lights_reaching = 0u;
    debug_light_work = range.y;
    for (var i = range.x; i < range.x + range.y; i += 1u) {
        radiance += local_light_radiance(light_cluster_entries[i].y, 0u, instance, s, local, falloff);
    }
    return radiance + direct_lights_end(s);
}
