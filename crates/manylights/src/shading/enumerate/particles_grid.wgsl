// Particle lights from the two 3D textures they are splatted into every frame (`particles/`): the
// colour texture holds the particles' intensity times their falloff at each voxel centre, the
// direction texture where that light comes from. A point reads the finest cascade that holds it with
// room for the filter's footprint, and near that cascade's edge blends into the next one, so the
// switch leaves no seam. Sampled — nearest, trilinear or tricubic, at one point or averaged over
// jittered points around it (`frame.particle_filter`) — the grid lights the point as one point light
// would, through the same BRDF, as far as its light comes from one direction, and as light from all
// around for the rest (`particle_light_at`).

// Both grids at one point: colour in .color, direction (unnormalised) in .direction.
struct ParticleSample {
    color: vec3<f32>,
    direction: vec3<f32>,
}

// Voxels a cascade's filter footprint keeps from its faces (tricubic reads two voxels away), and the
// band, in voxels, over which a point blends into the next cascade.
const PARTICLE_CASCADE_MARGIN: f32 = 2.0;
const PARTICLE_CASCADE_BLEND: f32 = 4.0;

// Texture coordinates of `coord` (in voxels from cascade `c`'s corner), kept within the cascade's slab
// of the stacked textures so that filtering never reads a neighbouring cascade.
fn particle_texcoord(c: u32, coord: vec3<f32>) -> vec3<f32> {
    let dims = vec3<f32>(frame.particle_volume.xyz);
    let inside = clamp(coord, vec3<f32>(0.5), dims - 0.5);
    let stacked = vec3<f32>(inside.xy, inside.z + f32(c) * dims.z);
    return stacked / vec3<f32>(dims.xy, dims.z * f32(frame.particle_volume.w));
}

fn particle_sample_linear(c: u32, coord: vec3<f32>) -> ParticleSample {
    let uvw = particle_texcoord(c, coord);
    return ParticleSample(
        textureSampleLevel(particle_color_grid, particle_sampler, uvw, 0.0).rgb,
        textureSampleLevel(particle_direction_grid, particle_sampler, uvw, 0.0).xyz,
    );
}

fn particle_sample_nearest(c: u32, coord: vec3<f32>) -> ParticleSample {
    let dims = frame.particle_volume.xyz;
    let voxel = vec3<u32>(clamp(floor(coord), vec3<f32>(0.0), vec3<f32>(dims - 1u))) + vec3<u32>(0u, 0u, c * dims.z);
    return ParticleSample(textureLoad(particle_color_grid, voxel, 0).rgb, textureLoad(particle_direction_grid, voxel, 0).xyz);
}

// Cubic B-spline filtering from eight trilinear taps (Sigg & Hadwiger, GPU Gems 2, ch. 20): along each
// axis the four weights become two taps placed between voxel centres.
fn particle_sample_tricubic(c: u32, coord: vec3<f32>) -> ParticleSample {
    let centred = coord - 0.5;
    let index = floor(centred);
    let f = centred - index;
    let w0 = (1.0 - f) * (1.0 - f) * (1.0 - f) / 6.0;
    let w1 = (4.0 - 6.0 * f * f + 3.0 * f * f * f) / 6.0;
    let w3 = f * f * f / 6.0;
    let w2 = 1.0 - w0 - w1 - w3;
    let g0 = w0 + w1;
    let g1 = w2 + w3;
    // Tap positions, in voxels from the corner.
    let t0 = index - 0.5 + w1 / g0;
    let t1 = index + 1.5 + w3 / g1;
    var result = ParticleSample(vec3<f32>(0.0), vec3<f32>(0.0));
    for (var k = 0u; k < 8u; k += 1u) {
        let pick = (vec3<u32>(k, k >> 1u, k >> 2u) & vec3<u32>(1u)) == vec3<u32>(1u);
        let weight = select(g0, g1, pick);
        let tap = particle_sample_linear(c, select(t0, t1, pick));
        let w = weight.x * weight.y * weight.z;
        result.color += tap.color * w;
        result.direction += tap.direction * w;
    }
    return result;
}

// `p` in voxels from cascade `c`'s corner.
fn particle_cascade_coord(c: u32, p: vec3<f32>) -> vec3<f32> {
    let cascade = frame.particle_cascades[c];
    return (p - cascade.xyz) / cascade.w;
}

// Voxels from `p` to the nearest face of cascade `c`; negative outside it.
fn particle_cascade_room(c: u32, p: vec3<f32>) -> f32 {
    let coord = particle_cascade_coord(c, p);
    let room = min(coord, vec3<f32>(frame.particle_volume.xyz) - coord);
    return min(room.x, min(room.y, room.z));
}

// The finest cascade that holds `p` with room for the filter; the coarsest takes any point.
fn particle_cascade_at(p: vec3<f32>) -> u32 {
    var c = 0u;
    while c + 1u < frame.particle_volume.w && particle_cascade_room(c, p) < PARTICLE_CASCADE_MARGIN {
        c += 1u;
    }
    return c;
}

fn particle_sample_cascade(c: u32, p: vec3<f32>) -> ParticleSample {
    let coord = particle_cascade_coord(c, p);
    switch frame.particle_filter.x {
        case PARTICLE_FILTER_NEAREST: {
            return particle_sample_nearest(c, coord);
        }
        case PARTICLE_FILTER_TRICUBIC: {
            return particle_sample_tricubic(c, coord);
        }
        default: {
            return particle_sample_linear(c, coord);
        }
    }
}

// The light the grid gives at world point `p` for the surface `s`.
fn particle_light_at(s: ShadingInput, p: vec3<f32>) -> vec3<f32> {
    let c = particle_cascade_at(p);
    let room = particle_cascade_room(c, p);
    if room < 0.0 {
        return vec3<f32>(0.0);
    }
    var grid = particle_sample_cascade(c, p);
    let blend = (room - PARTICLE_CASCADE_MARGIN) / PARTICLE_CASCADE_BLEND;
    if c + 1u < frame.particle_volume.w && blend < 1.0 {
        let coarser = particle_sample_cascade(c + 1u, p);
        let t = smoothstep(0.0, 1.0, blend);
        grid.color = mix(coarser.color, grid.color, t);
        grid.direction = mix(coarser.direction, grid.direction, t);
    }
    let luminance = dot(max(grid.color, vec3<f32>(0.0)), vec3<f32>(0.2126, 0.7152, 0.0722));
    if !(luminance > 0.0) {
        return vec3<f32>(0.0);
    }
    // The textures hold the sums scaled to fit half floats (`SplatScales`). The direction sum's
    // length over the colour sum's luminance (both weighted alike) is how concentrated the light's
    // directions are: 1 where it comes from one direction, towards 0 where particles surround the
    // point. That share comes through the BRDF from the mean direction; the rest as from every
    // direction evenly, through the surface's albedo over the sphere (4π).
    let color = max(grid.color, vec3<f32>(0.0)) * frame.particle_texture_unscale.x;
    let length_sq = dot(grid.direction, grid.direction);
    let concentration = saturate(sqrt(length_sq) / luminance);
    let isotropic =
        (s.base_color * (1.0 - s.metallic) * sheen_leaves_view(s) + environment_specular_albedo(s) + environment_sheen_albedo(s)) / (4.0 * PI);
    var directional = vec3<f32>(0.0);
    if length_sq > 0.0 {
        directional = brdf_times_cosine(s, grid.direction * inverseSqrt(length_sq));
    }
    return color * (concentration * directional + (1.0 - concentration) * isotropic);
}

// The grid's colour sum at world point `p` (the debug view's slices), without a surface: zero
// outside the grid.
fn particle_grid_at(p: vec3<f32>) -> vec3<f32> {
    if frame.particle_volume.w == 0u {
        return vec3<f32>(0.0);
    }
    let c = particle_cascade_at(p);
    if particle_cascade_room(c, p) < 0.0 {
        return vec3<f32>(0.0);
    }
    return max(particle_sample_cascade(c, p).color, vec3<f32>(0.0)) * frame.particle_texture_unscale.x;
}

fn shade_particle_lights(s: ShadingInput) -> vec3<f32> {
    if frame.particle_volume.w == 0u {
        return vec3<f32>(0.0);
    }
    let samples = max(frame.particle_filter.y, 1u);
    if samples == 1u {
        return particle_light_at(s, s.position);
    }
    // Supersampling: points on a golden-angle spiral in the surface's plane within half a voxel of
    // the point's cascade, turned per point by a hash of its position so the pattern does not repeat
    // from pixel to pixel.
    let voxel_size = frame.particle_cascades[particle_cascade_at(s.position)].w;
    let tangent = normalize(select(cross(s.normal, vec3<f32>(0.0, 1.0, 0.0)), cross(s.normal, vec3<f32>(1.0, 0.0, 0.0)), abs(s.normal.y) > 0.9));
    let bitangent = cross(s.normal, tangent);
    let cell = bitcast<vec3<u32>>(s.position);
    let turn = f32((cell.x * 73856093u) ^ (cell.y * 19349663u) ^ (cell.z * 83492791u)) * (6.2831853 / 4294967296.0);
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < samples; k += 1u) {
        let radius = 0.5 * voxel_size * sqrt((f32(k) + 0.5) / f32(samples));
        let angle = f32(k) * 2.3999632 + turn;
        sum += particle_light_at(s, s.position + radius * (cos(angle) * tangent + sin(angle) * bitangent));
    }
    return sum / f32(samples);
}
