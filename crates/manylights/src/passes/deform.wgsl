// Deformed meshes (`scene/deform.rs` and `scene/pose.rs`, whose CPU twins this must match): each
// vertex of the mesh at rest either moved along its normal by a travelling sine wave at the frame's
// time, its normal tilted by the wave's slope (tangents keep their rest direction), or posed: morph
// targets' offsets added by their weights, then skinned by its joints' matrices blended by its
// weights. Written over the mesh's vertices in the scene's buffer, which every raster pass and the
// BLAS refit (`rays/refit.wgsl`) then read, with the position a frame earlier for the velocities.
#include "shading/types.wgsl"

// One deformed mesh: its vertices in the scene's buffer and in `rest`, and its wave or its pose.
struct DeformJob {
    first_vertex: u32,
    vertex_count: u32,
    rest_first: u32,
    // 0: a wave, 1: a pose.
    kind: u32,
    direction: vec3<f32>,
    amplitude: f32,
    // 2π / wavelength
    wavenumber: f32,
    speed: f32,
    time: f32,
    previous_time: f32,
    target_count: u32,
    // Morph offsets: target after target, three vec4s (position, normal, tangent) per vertex.
    offsets_first: u32,
    influence_sets: u32,
    // Skin influences: per vertex and set, a vec4 of joints and a vec4 of weights' bits.
    influences_first: u32,
    joint_count: u32,
    // The frame's joint matrices, those a frame before, then the weights now and before, in vec4s.
    state_first: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> job: DeformJob;
@group(0) @binding(1) var<storage, read> rest: array<Vertex>;
@group(0) @binding(2) var<storage, read_write> vertices: array<Vertex>;
// xyz: where the vertex was a frame before; w: 1 for a deformed vertex.
@group(0) @binding(3) var<storage, read_write> previous_positions: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> offsets: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> influences: array<vec4<u32>>;
@group(0) @binding(6) var<storage, read> pose_state: array<vec4<f32>>;

fn wave_phase(position: vec3<f32>, time: f32) -> f32 {
    return job.wavenumber * (dot(position, job.direction) - job.speed * time);
}

fn morph_weight(target_index: u32, previous: bool) -> f32 {
    let first = job.state_first + 8u * job.joint_count + select(0u, (job.target_count + 3u) / 4u, previous);
    return pose_state[first + target_index / 4u][target_index % 4u];
}

fn joint_matrix(joint: u32, previous: bool) -> mat4x4<f32> {
    let first = job.state_first + 4u * (joint + select(0u, job.joint_count, previous));
    return mat4x4<f32>(pose_state[first], pose_state[first + 1u], pose_state[first + 2u], pose_state[first + 3u]);
}

// The vertex's skinning matrix: its joints' matrices blended by its weights.
fn skin_matrix(vertex: u32, previous: bool) -> mat4x4<f32> {
    var m = mat4x4<f32>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    for (var run = 0u; run < job.influence_sets; run += 1u) {
        let at = job.influences_first + 2u * (vertex * job.influence_sets + run);
        let joints = influences[at];
        let weights = bitcast<vec4<f32>>(influences[at + 1u]);
        for (var k = 0u; k < 4u; k += 1u) {
            if weights[k] != 0.0 {
                m += joint_matrix(joints[k], previous) * weights[k];
            }
        }
    }
    return m;
}

// The vertex morphed by the weights now, and its position morphed by those a frame before.
struct Morphed {
    position: vec3<f32>,
    normal: vec3<f32>,
    tangent: vec3<f32>,
    previous_position: vec3<f32>,
}

fn morph(vertex: u32, v: Vertex) -> Morphed {
    var m = Morphed(v.position, v.normal, v.tangent.xyz, v.position);
    for (var t = 0u; t < job.target_count; t += 1u) {
        let at = job.offsets_first + 3u * (t * job.vertex_count + vertex);
        let w = morph_weight(t, false);
        let before = morph_weight(t, true);
        m.position += offsets[at].xyz * w;
        m.normal += offsets[at + 1u].xyz * w;
        m.tangent += offsets[at + 2u].xyz * w;
        m.previous_position += offsets[at].xyz * before;
    }
    return m;
}

// Normals go through the cofactor matrix of the upper 3×3 (the inverse transpose up to scale).
fn cofactor(m: mat4x4<f32>) -> mat3x3<f32> {
    return mat3x3<f32>(cross(m[1].xyz, m[2].xyz), cross(m[2].xyz, m[0].xyz), cross(m[0].xyz, m[1].xyz));
}

fn normalize_or(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    return select(fallback, normalize(v), dot(v, v) > 1e-20);
}

@compute @workgroup_size(64)
fn deform(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= job.vertex_count {
        return;
    }
    var v = rest[job.rest_first + id.x];
    let n = v.normal;
    var previous: vec3<f32>;
    if job.kind == 0u {
        let phase = wave_phase(v.position, job.time);
        previous = v.position + n * (job.amplitude * sin(wave_phase(v.position, job.previous_time)));
        v.position = v.position + n * (job.amplitude * sin(phase));
        let along = job.direction - n * dot(n, job.direction);
        let tilted = n - along * (job.amplitude * job.wavenumber * cos(phase));
        v.normal = normalize_or(tilted, n);
    } else {
        let m = morph(id.x, v);
        var position = m.position;
        var normal = m.normal;
        var tangent = m.tangent;
        previous = m.previous_position;
        if job.influence_sets > 0u {
            let now = skin_matrix(id.x, false);
            // A mirroring blend (negative determinant) turns the cofactor's normal around and the
            // tangent frame's handedness over.
            let flip = select(1.0, -1.0, determinant(mat3x3<f32>(now[0].xyz, now[1].xyz, now[2].xyz)) < 0.0);
            position = (now * vec4<f32>(position, 1.0)).xyz;
            normal = cofactor(now) * normal * flip;
            tangent = (now * vec4<f32>(tangent, 0.0)).xyz;
            v.tangent.w *= flip;
            previous = (skin_matrix(id.x, true) * vec4<f32>(previous, 1.0)).xyz;
        }
        v.position = position;
        v.normal = normalize_or(normal, n);
        v.tangent = vec4<f32>(normalize_or(tangent, v.tangent.xyz), v.tangent.w);
    }
    vertices[job.first_vertex + id.x] = v;
    previous_positions[job.first_vertex + id.x] = vec4<f32>(previous, 1.0);
}
