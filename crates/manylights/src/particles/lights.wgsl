// The exact alternative to the grid (`particles/mod.rs`, `ParticleMethod::Bvh`): each particle of the
// frame becomes a point light in the lights' acceleration structure, rebuilt every frame
// (`accel/structure.rs`, `DynamicGroup`). Two passes around the group's LBVH build: `particle_boxes`
// writes each particle's box for the build; `particle_lights` then writes the light records in the
// order of the built leaves, which name their lights directly (`LbvhTarget::leaf_base`): a leaf's
// lights lie side by side in memory, and a query tests them one after the other.
#include "particles/types.wgsl"
#include "shading/types.wgsl"
#include "accel/bvh_types.wgsl"

@group(0) @binding(0) var<uniform> params: ParticleParams;
@group(0) @binding(1) var<storage, read> particles: array<ParticleLight>;
@group(0) @binding(2) var<storage, read_write> lights: array<Light>;
// Keep in sync with `GpuBox` in `accel/lbvh.rs`.
struct LightBox {
    min: vec4<f32>,
    max: vec4<f32>,
}
@group(0) @binding(3) var<storage, read_write> boxes: array<LightBox>;
// The structure's primitive indices: from `group.y`, the build's sorted order, each naming its
// particle as the first light + the particle's index.
@group(0) @binding(4) var<storage, read> primitives: array<u32>;
// x: the first light record the particles take (after the scene's lights); y: the group's first
// primitive index.
@group(0) @binding(5) var<uniform> group: vec4<u32>;
// Where `restir` draws through the light tree, the build also takes each particle's emitter
// (`accel/light_tree.rs`, `LightTreeNode::of_light`); a placeholder otherwise.
override LIGHT_TREE: bool = false;
@group(0) @binding(6) var<storage, read_write> emitters: array<LightTreeNode>;

@compute @workgroup_size(256)
fn particle_boxes(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * params.row_threads + id.x;
    if i >= params.count {
        return;
    }
    let particle = particles[i];
    // The sphere's box, as `accel::light_aabb` bounds a point light.
    boxes[i] = LightBox(vec4<f32>(particle.position - particle.radius, 0.0), vec4<f32>(particle.position + particle.radius, 0.0));
    if LIGHT_TREE {
        // Power as `accel::light_tree::light_power` weighs it: the luminance of the radiant colour.
        let power = max(dot(particle.color, vec3<f32>(0.2126, 0.7152, 0.0722)), 0.0);
        emitters[i] = LightTreeNode(particle.position, power, particle.position, particle.radius);
    }
}

// Position k of the built group's leaf order: the particle the build sorted there becomes light
// record first light + k, which the leaves over k name.
@compute @workgroup_size(256)
fn particle_lights(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.y * params.row_threads + id.x;
    if k >= params.count {
        return;
    }
    let particle = particles[primitives[group.y + k] - group.x];
    var light: Light;
    light.position = particle.position;
    light.range = particle.radius;
    light.radiant = particle.color;
    light.kind = LIGHT_POINT;
    light.direction = vec3<f32>(0.0, -1.0, 0.0);
    light.spot_scale = 0.0;
    light.spot_offset = 1.0;
    lights[group.x + k] = light;
}
