// A light's volume of influence, as the acceleration structures bound it (`accel/volumes.rs`).
#include "shading/types.wgsl"
#include "accel/bvh_types.wgsl"

// The tight test: whether `p` lies inside the light's range (and cone). `light_contribution`
// (`enumerate/light_loop.wgsl`) is zero wherever this is false; the CPU twin is
// `accel::volumes::light_contains`.
fn light_reaches(light: Light, p: vec3<f32>) -> bool {
    let to_light = light.position - p;
    let distance_sq = dot(to_light, to_light);
    if distance_sq >= light.range * light.range {
        return false;
    }
    if light.kind == LIGHT_SPOT && distance_sq > 0.0 {
        return dot(light.direction, -to_light) * inverseSqrt(distance_sq) * light.spot_scale + light.spot_offset > 0.0;
    }
    return true;
}

// A light stored in its group's space, placed in the world by an instance. The range scales with the
// instance; the intensity does not.
fn light_in_world(light: Light, instance: VolumeInstance) -> Light {
    var placed = light;
    placed.position = instance_point_to_world(instance, light.position);
    placed.direction = instance_direction_to_world(instance, light.direction);
    placed.range = light.range * instance.scale;
    return placed;
}
