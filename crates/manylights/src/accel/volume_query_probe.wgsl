// Test probe of the point query: for each point, the lights the two-level query reaches that pass the
// tight test (`light_reaches`, in the world), summarised as count, sum and sum of squares of their
// indices in the scene, which the tests compare with the CPU oracle. Runs the same query code as
// shading. The structure stores its items in leaf order; the primitive indices after the top level's
// (one per instance, at least one) hold each item's scene index (`accel/structure.rs`).
#include "shading/light_bindings.wgsl"
#include "shading/light_volume.wgsl"
#include "$LIGHT_QUERY" with VOLUMES=light

@group(1) @binding(0) var<storage, read> points: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> results: array<vec4<u32>>;
// The number of light instances (`frame.light_instance_count` in shading).
@group(1) @binding(2) var<storage, read> instance_count: u32;

// The instance the query is in, to place its lights in the world.
var<private> probe_instance: VolumeInstance;

fn light_query_entered(instance: VolumeInstance) {
    probe_instance = instance;
}

@compute @workgroup_size(64)
fn volume_query_probe(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&points) {
        return;
    }
    let p = points[id.x].xyz;
    var summary = vec4<u32>(0u);
    light_query_begin(p, instance_count);
    for (var leaf = light_query_next_leaf(); leaf.x != BVH_END; leaf = light_query_next_leaf()) {
        for (var k = leaf.x; k < leaf.y; k += 1u) {
            let light = light_primitives[max(instance_count, 1u) + k];
            if light_reaches(light_in_world(lights[k], probe_instance), p) {
                summary += vec4<u32>(1u, light, light * light, 0u);
            }
        }
    }
    results[id.x] = summary;
}
