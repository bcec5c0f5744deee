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

// A particle this frame: a point light of `color` intensity (candela per channel) reaching `radius`.
struct ParticleLight {
    position: vec3<f32>,
    radius: f32,
    color: vec3<f32>,
    _pad: f32,
}

// The voxel grid particle lights are splatted into: voxel (i, j, k) is centred on
// origin + (ijk + 0.5) × voxel_size.
struct ParticleGrid {
    origin: vec3<f32>,
    voxel_size: f32,
    dims: vec3<u32>,
    // Fixed-point scale of the accumulation (values are stored × scale as i32).
    scale: f32,
}
