// Decal enumeration through clustered shading: the decals listed for the shading point's froxel
// (`accel/cluster_grid.wgsl`), built this frame on the GPU; `decal_accumulate` applies the exact box
// test, so the result equals the brute-force loop's inside the view frustum.
#include "shading/decal_bindings.wgsl"
#include "shading/decals.wgsl"
#include "accel/cluster_grid.wgsl"

fn apply_decals(s: ShadingInput, dp: PositionGradients) -> ShadingInput {
    decal_blend_begin();
    var instance: VolumeInstance;
    var local = s.position;
    var surface: DecalSurface;
    var entered = 0xffffffffu;
    let range = decal_cluster_ranges[cluster_of(s.position)];
    for (var i = range.x; i < range.x + range.y; i += 1u) {
        let entry = decal_cluster_entries[i];
        if entry.x != entered {
            entered = entry.x;
            instance = decal_instances[entry.x];
            local = instance_point_to_group(instance, s.position);
            surface = decal_surface_in_group(decal_world_surface(s, dp), instance);
        }
        decal_accumulate(entry.y, instance, local, surface);
    }
    return decal_blend_end(s);
}
