#include "shading/scene_bindings.wgsl"
#include "shading/brdf.wgsl"
#include "shading/light_volume.wgsl"

// Punctual lights with the KHR_lights_punctual falloff: inverse square, windowed to reach zero at the
// light's range, and the glTF smooth spot cone.

// Radiance a light reflects towards the viewer; zero outside its range and cone.
fn light_contribution(light: Light, s: ShadingInput) -> vec3<f32> {
    let to_light = light.position - s.position;
    let distance_sq = dot(to_light, to_light);
    let range_sq = light.range * light.range;
    if distance_sq >= range_sq {
        return vec3<f32>(0.0);
    }
    let light_dir = to_light * inverseSqrt(max(distance_sq, 1e-12));
    // glTF's recommended window: (1 - (d / range)^4)^2, clamped.
    let ratio_sq = distance_sq / range_sq;
    let window = saturate(1.0 - ratio_sq * ratio_sq);
    var attenuation = window * window / max(distance_sq, 1e-4);
    if light.kind == LIGHT_SPOT {
        let cone = saturate(dot(light.direction, -light_dir) * light.spot_scale + light.spot_offset);
        attenuation *= cone * cone;
    }
    return light.radiant * attenuation * brdf_times_cosine(s, light_dir);
}


// The surface as seen from a group's space. Lighting it there with the group's lights, times
// `1 / scale²`, equals lighting the surface with the lights placed in the world: the instance turns
// and scales distances, the falloff is inverse-square, and the range window and cone depend on ratios
// and angles only. One transform per instance instead of one per light.
fn shading_input_in_group(s: ShadingInput, instance: VolumeInstance) -> ShadingInput {
    var local = s;
    local.position = instance_point_to_group(instance, s.position);
    local.normal = instance_vector_to_group(instance, s.normal) * instance.scale;
    local.view_dir = instance_vector_to_group(instance, s.view_dir) * instance.scale;
    return local;
}

// The factor that turns a group's light, shaded in the group's space, into its light in the world:
// 1 / scale² (`shading_input_in_group`).
fn instance_light_falloff(instance: VolumeInstance) -> f32 {
    return 1.0 / (instance.scale * instance.scale);
}
