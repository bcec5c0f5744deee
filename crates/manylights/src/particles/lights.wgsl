// The exact alternative to the grid (`particles/mod.rs`, `ParticleMethod::Bvh`): each particle of the
// frame becomes a point light in the lights' acceleration structure — its record among the lights and
// its box for the group's LBVH, rebuilt every frame (`accel/structure.rs`, `DynamicGroup`).
#include "particles/types.wgsl"
#include "shading/types.wgsl"

@group(0) @binding(0) var<uniform> params: ParticleParams;
@group(0) @binding(1) var<storage, read> particles: array<ParticleLight>;
@group(0) @binding(2) var<storage, read_write> lights: array<Light>;
// Keep in sync with `GpuBox` in `accel/lbvh.rs`.
struct LightBox {
    min: vec4<f32>,
    max: vec4<f32>,
}
@group(0) @binding(3) var<storage, read_write> boxes: array<LightBox>;
// The first light record the particles take (after the scene's lights).
@group(0) @binding(4) var<uniform> first_light: vec4<u32>;

@compute @workgroup_size(256)
fn particle_lights(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * params.row_threads + id.x;
    if i >= params.count {
        return;
    }
    let particle = particles[i];
    var light: Light;
    light.position = particle.position;
    light.range = particle.radius;
    light.radiant = particle.color;
    light.kind = LIGHT_POINT;
    light.direction = vec3<f32>(0.0, -1.0, 0.0);
    light.spot_scale = 0.0;
    light.spot_offset = 1.0;
    lights[first_light.x + i] = light;
    // The sphere's box, as `accel::light_aabb` bounds a point light.
    boxes[i] = LightBox(vec4<f32>(particle.position - particle.radius, 0.0), vec4<f32>(particle.position + particle.radius, 0.0));
}
