// Particle-light structs shared by the motion, splat and resolve passes (`particles/mod.rs`; keep in
// sync with `GpuParticleParams` and `GpuParticleLight` there).

struct ParticleParams {
    count: u32,
    emitter_count: u32,
    seed: u32,
    // Threads per row of the per-particle dispatch (x workgroups × 256).
    row_threads: u32,
    time: f32,
    gravity: f32,
    swirl: f32,
    // Launch directions lie within this cosine of +Y.
    cos_cone: f32,
    lifetime_min: f32,
    lifetime_max: f32,
    radius_min: f32,
    radius_max: f32,
    intensity: f32,
    _pad0: f32,
    _pad1: f32,
    _pad2: f32,
}

// PCG hash (Jarzynski & Olano 2020): well mixed 32-bit values from 32-bit inputs.
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// A particle this frame: a point light of `color` intensity (candela per channel) reaching `radius`.
struct ParticleLight {
    position: vec3<f32>,
    radius: f32,
    color: vec3<f32>,
    _pad: f32,
}

// Where particle lights are splatted (`ParticleVolume` in `particles/mod.rs`): `cascade_count` grids of
// `dims` voxels each, stacked along z in the sums and textures; cascade k's voxel (i, j, l) is centred
// on cascades[k].xyz + (ijl + 0.5) × cascades[k].w.
struct ParticleVolume {
    dims: vec3<u32>,
    cascade_count: u32,
    // Sums are stored × fixed_scale as i32; the textures hold them × texture_scale.
    fixed_scale: f32,
    texture_scale: f32,
    _pad0: f32,
    _pad1: f32,
    cascades: array<vec4<f32>, 8>,
}
