// The boxes of a structure's dynamic group (particle lights, written by `particles/lights.wgsl`'s
// `particle_boxes` every frame in the LBVH's layout) packed as the hardware back end's bottom level is
// built from them (`accel/hardware.rs`): min then max, six floats a box.

struct LbvhBox {
    min: vec4<f32>,
    max: vec4<f32>,
}

@group(0) @binding(0) var<uniform> count: vec4<u32>;
@group(0) @binding(1) var<storage, read> boxes: array<LbvhBox>;
// Six floats a box: vec3 arrays would be padded to 16 bytes a corner.
@group(0) @binding(2) var<storage, read_write> packed: array<f32>;

@compute @workgroup_size(256)
fn hardware_boxes(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = id.x;
    if k >= count.x {
        return;
    }
    let b = boxes[k];
    for (var axis = 0u; axis < 3u; axis += 1u) {
        packed[6u * k + axis] = b.min[axis];
        packed[6u * k + 3u + axis] = b.max[axis];
    }
}
