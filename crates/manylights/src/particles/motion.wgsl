// Particle motion (`particles/mod.rs`): where every particle light is at a time, as a function of the
// time alone, so frames can be rendered again or out of order and give the same particles. Each
// particle is launched from its emitter in a cone around +Y, falls under gravity and turns about the
// emitter's vertical axis (a vortex); when its lifetime ends it is launched again with new random
// values (its generation's). The CPU twin is `ParticleSettings::particle_at`.
#include "particles/types.wgsl"

@group(0) @binding(0) var<uniform> params: ParticleParams;
@group(0) @binding(1) var<storage, read> emitters: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> particles: array<ParticleLight>;

// A uniform value in [0, 1) for (particle, generation, which value).
fn random01(particle: u32, generation: u32, k: u32) -> f32 {
    let h = pcg(pcg(pcg(particle ^ params.seed) + generation) + k);
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

// Fully saturated colour of a hue in [0, 1) (as `generators::saturated_color`).
fn hue_color(hue: f32) -> vec3<f32> {
    let k = (vec3<f32>(5.0, 3.0, 1.0) + hue * 6.0) % vec3<f32>(6.0);
    return 1.0 - clamp(min(k, 4.0 - k), vec3<f32>(0.0), vec3<f32>(1.0));
}

@compute @workgroup_size(256)
fn particle_motion(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * params.row_threads + id.x;
    if i >= params.count {
        return;
    }
    let emitter = emitters[i % params.emitter_count];
    // Each particle runs its own clock, offset so launches are spread over time.
    let lifetime = mix(params.lifetime_min, params.lifetime_max, random01(i, 0u, 0u));
    let clock = params.time + lifetime * random01(i, 0u, 1u);
    let generation = u32(floor(clock / lifetime));
    // Rounding can put the difference a hair outside the lifetime.
    let age = clamp(clock - f32(generation) * lifetime, 0.0, lifetime);

    let angle = 6.2831853 * random01(i, generation, 2u);
    let cos_tilt = mix(1.0, params.cos_cone, random01(i, generation, 3u));
    let sin_tilt = sqrt(max(1.0 - cos_tilt * cos_tilt, 0.0));
    let speed = emitter.w * mix(0.6, 1.0, random01(i, generation, 4u));
    let velocity = vec3<f32>(cos(angle) * sin_tilt, cos_tilt, sin(angle) * sin_tilt) * speed;
    var offset = velocity * age - vec3<f32>(0.0, 0.5 * params.gravity * age * age, 0.0);
    // The vortex: the horizontal offset turns about the emitter's axis at `swirl` radians a second.
    let turn = params.swirl * age;
    offset = vec3<f32>(offset.x * cos(turn) - offset.z * sin(turn), offset.y, offset.x * sin(turn) + offset.z * cos(turn));

    var light: ParticleLight;
    light.position = emitter.xyz + offset;
    light.radius = mix(params.radius_min, params.radius_max, random01(i, generation, 5u));
    light.color = hue_color(random01(i, generation, 6u)) * params.intensity;
    particles[i] = light;
}
