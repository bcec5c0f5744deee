// Particle lights from the two 3D textures they are splatted into every frame (`particles/`): the
// colour texture holds the particles' intensity times their falloff at each voxel centre, the
// direction texture where that light comes from. Sampled at the surface point — nearest, trilinear
// or tricubic, at one point or averaged over jittered points around it (`frame.particle_filter`) —
// they light it as one point light would, through the same BRDF.

// Both grids at texture coordinates `uvw`: colour in .color, direction (unnormalised) in .direction.
struct ParticleSample {
    color: vec3<f32>,
    direction: vec3<f32>,
}

fn particle_sample_linear(uvw: vec3<f32>) -> ParticleSample {
    return ParticleSample(
        textureSampleLevel(particle_color_grid, particle_sampler, uvw, 0.0).rgb,
        textureSampleLevel(particle_direction_grid, particle_sampler, uvw, 0.0).xyz,
    );
}

fn particle_sample_nearest(uvw: vec3<f32>) -> ParticleSample {
    let dims = frame.particle_grid_dims.xyz;
    let voxel = vec3<u32>(clamp(floor(uvw * vec3<f32>(dims)), vec3<f32>(0.0), vec3<f32>(dims - 1u)));
    return ParticleSample(textureLoad(particle_color_grid, voxel, 0).rgb, textureLoad(particle_direction_grid, voxel, 0).xyz);
}

// Cubic B-spline filtering from eight trilinear taps (Sigg & Hadwiger, GPU Gems 2, ch. 20): along each
// axis the four weights become two taps placed between voxel centres.
fn particle_sample_tricubic(uvw: vec3<f32>) -> ParticleSample {
    let dims = vec3<f32>(frame.particle_grid_dims.xyz);
    let coord = uvw * dims - 0.5;
    let index = floor(coord);
    let f = coord - index;
    let w0 = (1.0 - f) * (1.0 - f) * (1.0 - f) / 6.0;
    let w1 = (4.0 - 6.0 * f * f + 3.0 * f * f * f) / 6.0;
    let w3 = f * f * f / 6.0;
    let w2 = 1.0 - w0 - w1 - w3;
    let g0 = w0 + w1;
    let g1 = w2 + w3;
    // Tap positions, in texture coordinates.
    let t0 = (index - 0.5 + w1 / g0) / dims;
    let t1 = (index + 1.5 + w3 / g1) / dims;
    var result = ParticleSample(vec3<f32>(0.0), vec3<f32>(0.0));
    for (var k = 0u; k < 8u; k += 1u) {
        let pick = (vec3<u32>(k, k >> 1u, k >> 2u) & vec3<u32>(1u)) == vec3<u32>(1u);
        let weight = select(g0, g1, pick);
        let tap = particle_sample_linear(select(t0, t1, pick));
        let w = weight.x * weight.y * weight.z;
        result.color += tap.color * w;
        result.direction += tap.direction * w;
    }
    return result;
}

// The light the grid gives at world point `p` for the surface `s`.
fn particle_light_at(s: ShadingInput, p: vec3<f32>) -> vec3<f32> {
    let dims = vec3<f32>(frame.particle_grid_dims.xyz);
    let uvw = (p - frame.particle_grid.xyz) / (frame.particle_grid.w * dims);
    if any(uvw < vec3<f32>(0.0)) || any(uvw > vec3<f32>(1.0)) {
        return vec3<f32>(0.0);
    }
    var grid: ParticleSample;
    switch frame.particle_filter.x {
        case PARTICLE_FILTER_NEAREST: {
            grid = particle_sample_nearest(uvw);
        }
        case PARTICLE_FILTER_TRICUBIC: {
            grid = particle_sample_tricubic(uvw);
        }
        default: {
            grid = particle_sample_linear(uvw);
        }
    }
    let length_sq = dot(grid.direction, grid.direction);
    if length_sq <= 0.0 {
        return vec3<f32>(0.0);
    }
    return max(grid.color, vec3<f32>(0.0)) * brdf_times_cosine(s, grid.direction * inverseSqrt(length_sq));
}

fn shade_particle_lights(s: ShadingInput) -> vec3<f32> {
    if frame.particle_grid_dims.w == 0u {
        return vec3<f32>(0.0);
    }
    let samples = max(frame.particle_filter.y, 1u);
    if samples == 1u {
        return particle_light_at(s, s.position);
    }
    // Supersampling: points on a golden-angle spiral in the surface's plane within half a voxel,
    // turned per point by a hash of its position so the pattern does not repeat from pixel to pixel.
    let tangent = normalize(select(cross(s.normal, vec3<f32>(0.0, 1.0, 0.0)), cross(s.normal, vec3<f32>(1.0, 0.0, 0.0)), abs(s.normal.y) > 0.9));
    let bitangent = cross(s.normal, tangent);
    let cell = bitcast<vec3<u32>>(s.position);
    let turn = f32((cell.x * 73856093u) ^ (cell.y * 19349663u) ^ (cell.z * 83492791u)) * (6.2831853 / 4294967296.0);
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < samples; k += 1u) {
        let radius = 0.5 * frame.particle_grid.w * sqrt((f32(k) + 0.5) / f32(samples));
        let angle = f32(k) * 2.3999632 + turn;
        sum += particle_light_at(s, s.position + radius * (cos(angle) * tangent + sin(angle) * bitangent));
    }
    return sum / f32(samples);
}
