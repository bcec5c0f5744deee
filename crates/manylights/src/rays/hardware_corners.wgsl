// The corners the hardware back end's bottom levels are built from (`rays/hardware.rs`), for a
// deformed mesh's copy after its refit (`refit.wgsl`): three positions per stored triangle in
// [range.x, range.y), from its corner and edges.
#include "rays/ray_types.wgsl"

@group(0) @binding(0) var<uniform> range: vec4<u32>;
@group(0) @binding(1) var<storage, read> triangles: array<RayTriangle>;
// Nine floats a triangle: vec3 arrays would be padded to 16 bytes a corner.
@group(0) @binding(2) var<storage, read_write> corners: array<f32>;

@compute @workgroup_size(64)
fn hardware_corners(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = range.x + id.x;
    if k >= range.y {
        return;
    }
    let tri = triangles[k];
    let points = array<vec3<f32>, 3>(tri.v0, tri.v0 + tri.e1, tri.v0 + tri.e2);
    for (var c = 0u; c < 3u; c += 1u) {
        for (var axis = 0u; axis < 3u; axis += 1u) {
            corners[9u * k + 3u * c + axis] = points[c][axis];
        }
    }
}
