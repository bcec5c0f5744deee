// No particle lights.

fn shade_particle_lights(s: ShadingInput) -> vec3<f32> {
    return vec3<f32>(0.0);
}

// No grid to slice.
fn particle_grid_at(p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}
