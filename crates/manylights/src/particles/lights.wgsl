// The exact alternative to the grid (`particles/mod.rs`, `ParticleMethod::Bvh`): each particle of the
// frame becomes a point light in the lights' acceleration structure, rebuilt every frame
// (`accel/structure.rs`, `DynamicGroup`). Two passes around the group's LBVH build: `particle_boxes`
// writes each particle's box for the build; `particle_lights` then writes the light records in the
// order of the built leaves, so the lights of a leaf lie side by side in memory (a query tests a leaf's
// lights one after the other), and points the leaves at them.
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
// The structure's primitive indices: the group's leaves name items from `group.y`.
@group(0) @binding(4) var<storage, read_write> primitives: array<u32>;
// x: the first light record the particles take (after the scene's lights); y: the group's first
// primitive index.
@group(0) @binding(5) var<uniform> group: vec4<u32>;

@compute @workgroup_size(256)
fn particle_boxes(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * params.row_threads + id.x;
    if i >= params.count {
        return;
    }
    let particle = particles[i];
    // The sphere's box, as `accel::light_aabb` bounds a point light.
    boxes[i] = LightBox(vec4<f32>(particle.position - particle.radius, 0.0), vec4<f32>(particle.position + particle.radius, 0.0));
}

// Item k of the built group: the build left it naming its particle (first light + the particle's
// index); it becomes light record first light + k.
@compute @workgroup_size(256)
fn particle_lights(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.y * params.row_threads + id.x;
    if k >= params.count {
        return;
    }
    let slot = group.y + k;
    let particle = particles[primitives[slot] - group.x];
    var light: Light;
    light.position = particle.position;
    light.range = particle.radius;
    light.radiant = particle.color;
    light.kind = LIGHT_POINT;
    light.direction = vec3<f32>(0.0, -1.0, 0.0);
    light.spot_scale = 0.0;
    light.spot_offset = 1.0;
    lights[group.x + k] = light;
    primitives[slot] = group.x + k;
}
