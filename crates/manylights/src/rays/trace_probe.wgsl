// Test probe of the ray traversal: for each ray, the closest hit (`trace_closest`) or, flagged, whether
// anything is hit before t_max (`trace_any_hit`), through the functions the passes use. Rays are (origin, t_max) and
// (direction, any-hit flag); results are (t, triangle, instance, b1) and b2.
#include "shading/scene_bindings.wgsl"
#include "rays/trace.wgsl"

@group(1) @binding(0) var<storage, read> probe_rays: array<vec4<f32>>;
@group(1) @binding(1) var<storage, read_write> probe_hits: array<vec4<f32>>;

@compute @workgroup_size(64)
fn trace_probe(@builtin(global_invocation_id) id: vec3<u32>) {
    let count = arrayLength(&probe_rays) / 2u;
    if id.x >= count {
        return;
    }
    let origin = probe_rays[2u * id.x];
    let dir = probe_rays[2u * id.x + 1u];
    var hit: RayHit;
    if dir.w != 0.0 {
        hit = trace_any_hit(origin.xyz, dir.xyz, origin.w);
    } else {
        hit = trace_closest(origin.xyz, dir.xyz, origin.w);
    }
    probe_hits[2u * id.x] = vec4<f32>(hit.t, bitcast<f32>(hit.triangle), bitcast<f32>(hit.instance), hit.b1);
    probe_hits[2u * id.x + 1u] = vec4<f32>(hit.b2, 0.0, 0.0, 0.0);
}
