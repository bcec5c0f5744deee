#include "shading/scene_bindings.wgsl"
#include "shading/brdf.wgsl"
#include "shading/light_volume.wgsl"

// Punctual lights with the KHR_lights_punctual falloff: inverse square, windowed to reach zero at the
// light's range, and the glTF smooth spot cone.

// The attenuation at squared distance `distance_sq` (within the range) of a light of range `range`:
// inverse square times glTF's recommended window, (1 - (d / range)^4)^2, clamped.
fn light_distance_attenuation(distance_sq: f32, range: f32) -> f32 {
    let ratio_sq = distance_sq / (range * range);
    let window = saturate(1.0 - ratio_sq * ratio_sq);
    return window * window / max(distance_sq, 1e-4);
}

// The glTF smooth spot cone towards `light_dir` (from the surface to the light) of a spot pointing
// along `axis`, its cone as glTF's scale and offset.
fn spot_cone_attenuation(axis: vec3<f32>, scale: f32, offset: f32, light_dir: vec3<f32>) -> f32 {
    let cone = saturate(dot(axis, -light_dir) * scale + offset);
    return cone * cone;
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
