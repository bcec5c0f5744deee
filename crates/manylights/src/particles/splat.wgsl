// The particle lights' two 3D textures (after "GPU-based dynamic point light particles rendering
// using 3D textures", 2020): every particle adds, into each voxel whose centre its radius reaches,
// its colour times the point-light falloff at the voxel centre, and the direction from the centre
// towards it weighted alike (by the falloff and its luminance). Sums are fixed-point i32 atomics (no
// float atomics in WebGPU); `particle_resolve` turns them into the filterable RGBA16F textures shading
// samples (`shading/enumerate/particles_grid.wgsl`).
#include "particles/types.wgsl"

@group(0) @binding(0) var<uniform> params: ParticleParams;
@group(0) @binding(1) var<uniform> grid: ParticleGrid;
@group(0) @binding(2) var<storage, read> particles: array<ParticleLight>;
// Six channels per voxel: colour rgb, direction xyz.
@group(0) @binding(3) var<storage, read_write> sums: array<atomic<i32>>;
@group(0) @binding(4) var color_grid: texture_storage_3d<rgba16float, write>;
@group(0) @binding(5) var direction_grid: texture_storage_3d<rgba16float, write>;

// The falloff a voxel centre at `distance` from a particle of `radius` receives: the glTF point-light
// attenuation (inverse square, windowed to zero at the radius) with the distance held at half a voxel
// or more, where a voxel's centre no longer stands for the points around it.
fn splat_falloff(distance: f32, radius: f32) -> f32 {
    let ratio_sq = distance * distance / (radius * radius);
    let window = saturate(1.0 - ratio_sq * ratio_sq);
    let near = 0.5 * grid.voxel_size;
    return window * window / max(distance * distance, near * near);
}

fn add_fixed(index: u32, value: f32) {
    atomicAdd(&sums[index], i32(round(value * grid.scale)));
}

@compute @workgroup_size(256)
fn particle_splat(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * params.row_threads + id.x;
    if i >= params.count {
        return;
    }
    let light = particles[i];
    let luminance = dot(light.color, vec3<f32>(0.2126, 0.7152, 0.0722));
    // Voxels whose centres may lie within the radius, clamped into the grid.
    let low = (light.position - light.radius - grid.origin) / grid.voxel_size - 0.5;
    let high = (light.position + light.radius - grid.origin) / grid.voxel_size - 0.5;
    let last = vec3<f32>(grid.dims) - 1.0;
    if any(high < vec3<f32>(0.0)) || any(low > last) {
        return;
    }
    let first = vec3<u32>(clamp(ceil(low), vec3<f32>(0.0), last));
    let end = vec3<u32>(clamp(floor(high), vec3<f32>(0.0), last));
    for (var z = first.z; z <= end.z; z += 1u) {
        for (var y = first.y; y <= end.y; y += 1u) {
            for (var x = first.x; x <= end.x; x += 1u) {
                let centre = grid.origin + (vec3<f32>(f32(x), f32(y), f32(z)) + 0.5) * grid.voxel_size;
                let to_light = light.position - centre;
                let distance = length(to_light);
                if distance >= light.radius {
                    continue;
                }
                let weight = splat_falloff(distance, light.radius);
                let direction = select(vec3<f32>(0.0), to_light / distance, distance > 0.0) * (weight * luminance);
                let voxel = 6u * ((z * grid.dims.y + y) * grid.dims.x + x);
                add_fixed(voxel, light.color.r * weight);
                add_fixed(voxel + 1u, light.color.g * weight);
                add_fixed(voxel + 2u, light.color.b * weight);
                add_fixed(voxel + 3u, direction.x);
                add_fixed(voxel + 4u, direction.y);
                add_fixed(voxel + 5u, direction.z);
            }
        }
    }
}

// One thread per voxel: fixed-point sums into the textures.
@compute @workgroup_size(4, 4, 4)
fn particle_resolve(@builtin(global_invocation_id) voxel: vec3<u32>) {
    if any(voxel >= grid.dims) {
        return;
    }
    let base = 6u * ((voxel.z * grid.dims.y + voxel.y) * grid.dims.x + voxel.x);
    var values: array<f32, 6>;
    for (var k = 0u; k < 6u; k += 1u) {
        values[k] = f32(atomicLoad(&sums[base + k])) / grid.scale;
    }
    textureStore(color_grid, voxel, vec4<f32>(values[0], values[1], values[2], 1.0));
    textureStore(direction_grid, voxel, vec4<f32>(values[3], values[4], values[5], 0.0));
}
