// Particle lights from the two 3D textures they are splatted into every frame (`particles/`): the
// colour texture holds the particles' intensity times their falloff at each voxel centre, the
// direction texture where that light comes from. Sampled trilinearly at the surface point, they light
// it as one point light would, through the same BRDF.

fn shade_particle_lights(s: ShadingInput) -> vec3<f32> {
    if frame.particle_grid_dims.w == 0u {
        return vec3<f32>(0.0);
    }
    let dims = vec3<f32>(frame.particle_grid_dims.xyz);
    let uvw = (s.position - frame.particle_grid.xyz) / (frame.particle_grid.w * dims);
    if any(uvw < vec3<f32>(0.0)) || any(uvw > vec3<f32>(1.0)) {
        return vec3<f32>(0.0);
    }
    let color = textureSampleLevel(particle_color_grid, particle_sampler, uvw, 0.0).rgb;
    let direction = textureSampleLevel(particle_direction_grid, particle_sampler, uvw, 0.0).xyz;
    let length_sq = dot(direction, direction);
    if length_sq <= 0.0 {
        return vec3<f32>(0.0);
    }
    return max(color, vec3<f32>(0.0)) * brdf_times_cosine(s, direction * inverseSqrt(length_sq));
}
