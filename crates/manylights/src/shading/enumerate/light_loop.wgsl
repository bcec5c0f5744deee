// One light of a light enumeration loop, shared by every method (`lights_*.wgsl`): the range test,
// then the light's contribution, counted for the debug views, handed to the direct-lighting module
// (`$DIRECT_LIGHTING`, `shading/direct/*.wgsl`), which shadows or samples it.
#include "shading/light_bindings.wgsl"
#include "shading/lights.wgsl"
#include "$DIRECT_LIGHTING"
#include "shading/debug_view.wgsl"

// A light's sphere of influence: its position and range, the record's first 16 bytes. Most lights a
// loop meets are out of range, so it reads these and loads the rest only for lights that pass
// (benchmarks/LOG.md, topic 3).
fn light_sphere(index: u32) -> vec4<f32> {
    return vec4<f32>(lights[index].position, lights[index].range);
}

// Whether a light's sphere reaches `p` (group space): the range test.
fn sphere_reaches(sphere: vec4<f32>, p: vec3<f32>) -> bool {
    let to_light = sphere.xyz - p;
    return dot(to_light, to_light) < sphere.w * sphere.w;
}

// Whether a light's sphere can light the surface `local` (group space): within its range, and above
// the surface's horizon (`brdf_times_cosine` is zero below it, but for light through a transmissive
// surface, `lit_from_behind`). It serves crowds of lights, where
// many lights in range of a point are still below its horizon, sparing their contributions. Loops
// that meet mostly lights out of range test the range alone: there the horizon test costs more than
// it saves (benchmarks/LOG.md, topic 3).
fn sphere_may_light(sphere: vec4<f32>, local: ShadingInput) -> bool {
    return sphere_reaches(sphere, local.position) && (dot(local.normal, sphere.xyz - local.position) > 0.0 || lit_from_behind(local));
}

// Whether a light's sphere reaches some point of the box [low, high] (group space): true for every
// sphere that reaches a point inside the box.
fn sphere_meets_box(sphere: vec4<f32>, low: vec3<f32>, high: vec3<f32>) -> bool {
    let gap = max(max(low - sphere.xyz, sphere.xyz - high), vec3<f32>(0.0));
    return dot(gap, gap) < sphere.w * sphere.w;
}

// The radiance light `index`, of the group that instance `instance_index` (`instance`) places, adds at
// the surface: `local` is the surface `s` in the group's space (`shading_input_in_group`), and
// `falloff` undoes the instance's scale.
fn local_light_radiance(
    index: u32,
    instance_index: u32,
    instance: VolumeInstance,
    s: ShadingInput,
    local: ShadingInput,
    falloff: f32,
) -> vec3<f32> {
    let sphere = light_sphere(index);
    if !sphere_reaches(sphere, local.position) {
        return vec3<f32>(0.0);
    }
    return light_radiance_in_range(index, sphere, instance_index, instance, s, local, falloff);
}

// `local_light_radiance` for a light within range of the surface, its sphere read already.
fn light_radiance_in_range(
    index: u32,
    sphere: vec4<f32>,
    instance_index: u32,
    instance: VolumeInstance,
    s: ShadingInput,
    local: ShadingInput,
    falloff: f32,
) -> vec3<f32> {
    let contribution = light_contribution(index, sphere, local);
    if !any(contribution > vec3<f32>(0.0)) {
        return vec3<f32>(0.0);
    }
    if DEBUG_VIEWS {
        debug_lights_reaching += 1u;
    }
    return direct_light(index, instance_index, sphere, instance, s, contribution * falloff);
}

// Radiance light `index`, whose sphere is `sphere`, reflects towards the viewer from the surface `s`;
// zero outside its range and cone. The rest of the record is read field by field, only where needed:
// the colour and kind, and a spot's cone. Loading the whole 64-byte record at once, sphere included,
// is slower for dense and sparse lights alike (benchmarks/LOG.md, topic 3).
fn light_contribution(index: u32, sphere: vec4<f32>, s: ShadingInput) -> vec3<f32> {
    let to_light = sphere.xyz - s.position;
    let distance_sq = dot(to_light, to_light);
    if distance_sq >= sphere.w * sphere.w {
        return vec3<f32>(0.0);
    }
    let light_dir = to_light * inverseSqrt(max(distance_sq, 1e-12));
    var attenuation = light_distance_attenuation(distance_sq, sphere.w);
    if lights[index].kind == LIGHT_SPOT {
        attenuation *= spot_cone_attenuation(lights[index].direction, lights[index].spot_scale, lights[index].spot_offset, light_dir);
    }
    return lights[index].radiant * attenuation * brdf_times_cosine(s, light_dir);
}
