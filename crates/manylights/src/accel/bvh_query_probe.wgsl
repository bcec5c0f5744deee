// Test probe of the point query: for each point, the lights the BVH query reaches that pass the
// tight test (`light_reaches`), summarised as count, sum and sum of squares of their indices, which
// the tests compare with the CPU oracle. Runs the same `bvh_query_*` code as shading.
#include "shading/types.wgsl"
#include "shading/light_volume.wgsl"
#include "accel/bvh.wgsl"

@group(0) @binding(0) var<storage, read> lights: array<Light>;
@group(0) @binding(1) var<storage, read> points: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> results: array<vec4<u32>>;

@compute @workgroup_size(64)
fn bvh_query_probe(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&points) {
        return;
    }
    let p = points[id.x].xyz;
    var summary = vec4<u32>(0u);
    bvh_query_begin(p, arrayLength(&bvh_nodes));
    for (var leaf = bvh_query_next_leaf(); leaf.x < leaf.y; leaf = bvh_query_next_leaf()) {
        for (var k = leaf.x; k < leaf.y; k += 1u) {
            let light = bvh_primitives[k];
            if light_reaches(lights[light], p) {
                summary += vec4<u32>(1u, light, light * light, 0u);
            }
        }
    }
    results[id.x] = summary;
}
