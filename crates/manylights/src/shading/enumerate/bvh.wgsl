// Light enumeration through a BVH over the lights' volumes (Hansen & Peters 2021): a point query —
// the paper's zero-length ray — descends only into nodes whose box contains the shading point; each
// light in a reached leaf gets the tight test inside `light_contribution` (sphere, cone), so the
// result equals the brute-force loop's.
#include "shading/scene_bindings.wgsl"
#include "shading/lights.wgsl"
#include "accel/bvh.wgsl"

// Group 2: the light acceleration structure (`accel/gpu.rs`, `LightBvhBuffers`).
@group(2) @binding(0) var<storage, read> light_bvh_nodes: array<BvhNode>;
@group(2) @binding(1) var<storage, read> light_bvh_primitives: array<u32>;

fn shade_local_lights(s: ShadingInput) -> vec3<f32> {
    var radiance = vec3<f32>(0.0);
    if frame.light_count == 0u {
        return radiance;
    }
    var stack: array<u32, BVH_STACK_SIZE>;
    stack[0] = 0u;
    var top = 1u;
    while top > 0u {
        top -= 1u;
        let node = light_bvh_nodes[stack[top]];
        if !bvh_node_contains(node, s.position) {
            continue;
        }
        if (node.a & BVH_LEAF) != 0u {
            let first = node.a & ~BVH_LEAF;
            for (var k = first; k < first + node.b; k += 1u) {
                radiance += light_contribution(lights[light_bvh_primitives[k]], s);
            }
        } else {
            stack[top] = node.a;
            stack[top + 1u] = node.b;
            top += 2u;
        }
    }
    return radiance;
}
