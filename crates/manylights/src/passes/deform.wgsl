// Deformed meshes (`scene/deform.rs`, whose CPU twin this must match): each vertex of the mesh at
// rest moved along its normal by a travelling sine wave at the frame's time, its normal tilted by the
// wave's slope, written over the mesh's vertices in the scene's vertex buffer, which every raster pass
// and the BLAS refit (`rays/refit.wgsl`) then read. Tangents keep their rest direction.
#include "shading/types.wgsl"

// One deformed mesh: its vertices in the scene's buffer and in `rest`, and its wave.
struct DeformJob {
    first_vertex: u32,
    vertex_count: u32,
    rest_first: u32,
    _pad0: u32,
    direction: vec3<f32>,
    amplitude: f32,
    // 2π / wavelength
    wavenumber: f32,
    speed: f32,
    time: f32,
    _pad1: f32,
}

@group(0) @binding(0) var<uniform> job: DeformJob;
@group(0) @binding(1) var<storage, read> rest: array<Vertex>;
@group(0) @binding(2) var<storage, read_write> vertices: array<Vertex>;

@compute @workgroup_size(64)
fn deform(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= job.vertex_count {
        return;
    }
    var v = rest[job.rest_first + id.x];
    let n = v.normal;
    let phase = job.wavenumber * (dot(v.position, job.direction) - job.speed * job.time);
    v.position = v.position + n * (job.amplitude * sin(phase));
    let along = job.direction - n * dot(n, job.direction);
    let tilted = n - along * (job.amplitude * job.wavenumber * cos(phase));
    v.normal = select(n, normalize(tilted), dot(tilted, tilted) > 1e-20);
    vertices[job.first_vertex + id.x] = v;
}
