// Test probe of the light tree's draws (`light_tree.wgsl`): invocation i draws from the root of light
// instance 0 at `probe.point` facing `probe.normal` (group space), with a random sequence of its own,
// and writes whether it reached a leaf, the draw's probability and the leaf's first item, which the
// tests compare with a CPU oracle and the histogram of many draws.
#include "shading/light_tree.wgsl"

struct LightTreeProbe {
    point: vec4<f32>,
    normal: vec4<f32>,
}

@group(1) @binding(0) var<storage, read> probe: LightTreeProbe;
@group(1) @binding(1) var<storage, read_write> draws: array<vec4<u32>>;

@compute @workgroup_size(64)
fn light_tree_probe(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&draws) {
        return;
    }
    random_state = random_hash(id.x + 1u);
    let draw = light_tree_draw_leaf(light_instances[0].blas_root & ~ENTRY_GRID_FLAG, probe.point.xyz, probe.normal.xyz, false);
    draws[id.x] = vec4<u32>(0u, u32(draw.drawn), bitcast<u32>(draw.probability), draw.entry & BVH_LEAF_FIRST_MASK);
}
