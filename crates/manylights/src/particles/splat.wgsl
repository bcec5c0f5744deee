// The particle lights' two 3D textures (after "GPU-based dynamic point light particles rendering
// using 3D textures", 2020): every particle adds, into each voxel whose centre its radius reaches,
// its colour times the point-light falloff at the voxel centre, and the direction from the centre
// towards it weighted alike (by the falloff and its luminance), in every cascade of the volume. Sums
// are fixed-point i32 atomics (no float atomics in WebGPU) at a scale no crowd of particles can wrap;
// `particle_resolve` turns them into the filterable RGBA16F textures shading samples
// (`shading/enumerate/particles_grid.wgsl`).
#include "particles/types.wgsl"

@group(0) @binding(0) var<uniform> params: ParticleParams;
@group(0) @binding(1) var<uniform> volume: ParticleVolume;
@group(0) @binding(2) var<storage, read> particles: array<ParticleLight>;
// Six channels per voxel: colour rgb, direction xyz.
@group(0) @binding(3) var<storage, read_write> sums: array<atomic<i32>>;
@group(0) @binding(4) var color_grid: texture_storage_3d<rgba16float, write>;
@group(0) @binding(5) var direction_grid: texture_storage_3d<rgba16float, write>;

// The falloff a voxel centre at `distance` from a particle of `radius` receives: the glTF point-light
// attenuation (inverse square, windowed to zero at the radius) with the distance held at half a voxel
// or more, where a voxel's centre no longer stands for the points around it.
fn splat_falloff(distance: f32, radius: f32, voxel_size: f32) -> f32 {
    let ratio_sq = distance * distance / (radius * radius);
    let window = saturate(1.0 - ratio_sq * ratio_sq);
    let near = 0.5 * voxel_size;
    return window * window / max(distance * distance, near * near);
}

// Adds `value` in fixed point, rounded up or down at random (`dither` uniform in [0, 1)): the rounding
// is then unbiased, so the many equal contributions of a crowd do not all err the same way.
fn add_fixed(index: u32, value: f32, dither: f32) {
    atomicAdd(&sums[index], i32(floor(value * volume.fixed_scale + dither)));
}

// One thread per particle and cascade (the dispatch's z).
@compute @workgroup_size(256)
fn particle_splat(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * params.row_threads + id.x;
    if i >= params.count {
        return;
    }
    let cascade = volume.cascades[id.z];
    let origin = cascade.xyz;
    let voxel_size = cascade.w;
    let dims = volume.dims;
    let light = particles[i];
    let luminance = dot(light.color, vec3<f32>(0.2126, 0.7152, 0.0722));
    // The particle's dither, stepped along a golden-ratio sequence for each value it adds.
    var dither = f32(pcg(i) >> 8u) * (1.0 / 16777216.0);
    // Voxels whose centres may lie within the radius, clamped into the cascade.
    let low = (light.position - light.radius - origin) / voxel_size - 0.5;
    let high = (light.position + light.radius - origin) / voxel_size - 0.5;
    let last = vec3<f32>(dims) - 1.0;
    if any(high < vec3<f32>(0.0)) || any(low > last) {
        return;
    }
    let first = vec3<u32>(clamp(ceil(low), vec3<f32>(0.0), last));
    let end = vec3<u32>(clamp(floor(high), vec3<f32>(0.0), last));
    for (var z = first.z; z <= end.z; z += 1u) {
        for (var y = first.y; y <= end.y; y += 1u) {
            for (var x = first.x; x <= end.x; x += 1u) {
                let centre = origin + (vec3<f32>(f32(x), f32(y), f32(z)) + 0.5) * voxel_size;
                let to_light = light.position - centre;
                let distance = length(to_light);
                if distance >= light.radius {
                    continue;
                }
                let weight = splat_falloff(distance, light.radius, voxel_size);
                let direction = select(vec3<f32>(0.0), to_light / distance, distance > 0.0) * (weight * luminance);
                let voxel = 6u * (((id.z * dims.z + z) * dims.y + y) * dims.x + x);
                let values = array<f32, 6>(light.color.r * weight, light.color.g * weight, light.color.b * weight, direction.x, direction.y, direction.z);
                for (var k = 0u; k < 6u; k += 1u) {
                    dither = fract(dither + 0.618034);
                    add_fixed(voxel + k, values[k], dither);
                }
            }
        }
    }
}

// One thread per voxel of the stacked cascades: fixed-point sums into the textures.
@compute @workgroup_size(4, 4, 4)
fn particle_resolve(@builtin(global_invocation_id) voxel: vec3<u32>) {
    let dims = volume.dims;
    if any(voxel >= vec3<u32>(dims.xy, dims.z * volume.cascade_count)) {
        return;
    }
    let base = 6u * ((voxel.z * dims.y + voxel.y) * dims.x + voxel.x);
    var values: array<f32, 6>;
    for (var k = 0u; k < 6u; k += 1u) {
        values[k] = f32(atomicLoad(&sums[base + k])) * (volume.texture_scale / volume.fixed_scale);
    }
    textureStore(color_grid, voxel, vec4<f32>(values[0], values[1], values[2], 1.0));
    textureStore(direction_grid, voxel, vec4<f32>(values[3], values[4], values[5], 0.0));
}
