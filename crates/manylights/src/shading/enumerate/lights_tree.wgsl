// `restir`'s candidates drawn through the light tree (`shading/light_tree.wgsl`) instead of
// enumerated: LIGHT_TREE_CANDIDATES draws a point, each an instance chosen in proportion to its
// group root's importance, a leaf by descent, and one of the leaf's lights in proportion to its
// unshadowed diffuse light there. A draw's probability p is the product of the three choices, and it enters
// restir's reservoirs with weight p̂ / (M p) (`restir_candidate`): the point's cost is M descents,
// whatever the number of lights reaching it. Composed only with `restir` (`plan::restir_light_tree`).
#include "shading/enumerate/light_loop.wgsl"
#include "shading/light_tree.wgsl"

// M: draws a shading point makes.
const LIGHT_TREE_CANDIDATES: u32 = 8u;

// Instance `index`'s importance at the surface: its group root's, in the group's space, times the
// falloff that undoes the instance's scale.
fn light_tree_instance_importance(index: u32, s: ShadingInput) -> f32 {
    let instance = light_instances[index];
    let local = shading_input_in_group(s, instance);
    return light_tree_importance(instance.blas_root & ~ENTRY_GRID_FLAG, local.position, local.normal, lit_from_behind(s)) * instance_light_falloff(instance);
}

// Light `index`'s importance at the surface `local` (group space): its power through its distance
// falloff and the cosine at the surface (its size, for light from behind), zero out of range or
// below the horizon of a surface not lit from behind — p̂ without the BRDF's lobes and the spot's
// cone, which only the light drawn pays for.
fn light_tree_light_importance(index: u32, local: ShadingInput) -> f32 {
    let sphere = light_sphere(index);
    if !sphere_may_light(sphere, local) {
        return 0.0;
    }
    let to_light = sphere.xyz - local.position;
    let distance_sq = dot(to_light, to_light);
    let cosine = abs(dot(local.normal, to_light)) * inverseSqrt(max(distance_sq * dot(local.normal, local.normal), 1e-20));
    return dot(lights[index].radiant, RESTIR_LUMINANCE) * light_distance_attenuation(distance_sq, sphere.w) * cosine;
}

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    direct_lights_begin(s);
    debug_lights_reaching = 0u;
    debug_light_work = 0u;
    let instances = frame.light_instance_count;
    var total = 0.0;
    for (var i = 0u; i < instances; i += 1u) {
        total += light_tree_instance_importance(i, s);
    }
    for (var draw = 0u; draw < LIGHT_TREE_CANDIDATES && total > 0.0; draw += 1u) {
        // The instance, in proportion to its importance (the sum again, where there are several).
        var chosen = 0u;
        var importance = total;
        if instances > 1u {
            var left = random_next() * total;
            for (var i = 0u; i < instances; i += 1u) {
                chosen = i;
                importance = light_tree_instance_importance(i, s);
                if left < importance {
                    break;
                }
                left -= importance;
            }
        }
        if !(importance > 0.0) {
            continue;
        }
        let instance = light_instances[chosen];
        let local = shading_input_in_group(s, instance);
        let falloff = instance_light_falloff(instance);
        let leaf = light_tree_draw_leaf(instance.blas_root & ~ENTRY_GRID_FLAG, local.position, local.normal, lit_from_behind(s));
        if !leaf.drawn {
            continue;
        }
        // One of the leaf's lights in proportion to its own importance, streamed.
        let range = bvh_leaf_range(leaf.entry);
        var leaf_sum = 0.0;
        var light = range.x;
        var light_importance = 0.0;
        for (var k = range.x; k < range.y; k += 1u) {
            let weight = light_tree_light_importance(k, local);
            if DEBUG_VIEWS {
                debug_light_work += 1u;
            }
            if !(weight > 0.0) {
                continue;
            }
            leaf_sum += weight;
            if random_next() * leaf_sum < weight {
                light = k;
                light_importance = weight;
            }
        }
        if !(leaf_sum > 0.0) {
            continue;
        }
        if DEBUG_VIEWS {
            debug_lights_reaching += 1u;
        }
        let sphere = light_sphere(light);
        let radiance = light_contribution(light, sphere, local) * falloff;
        let probability = importance / total * leaf.probability * light_importance / leaf_sum;
        restir_candidate(light, chosen, sphere, instance, radiance, 1.0 / (f32(LIGHT_TREE_CANDIDATES) * probability));
    }
    return direct_lights_end(s);
}
