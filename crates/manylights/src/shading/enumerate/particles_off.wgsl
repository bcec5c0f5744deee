// No particle lights.

fn shade_particle_lights(s: ShadingInput) -> vec3<f32> {
    return vec3<f32>(0.0);
}
