// Decal enumeration through the decals' acceleration structure (Hansen & Peters 2021): the point
// query reaches the leaves whose box contains the shading point (walking as a subgroup, those of its
// neighbours too, `accel/volume_query.wgsl`); `decal_accumulate` applies the exact box test, so the
// result equals the brute-force loop's. A leaves module (`plan::query_walks`) hands a leaf's decals
// to the tests: each lane every decal (`decal_leaves_each.wgsl`), or, for dense decals walked as a
// subgroup, the lanes sharing the leaf out (`decal_leaves_shared_out.wgsl`).
#include "shading/decal_bindings.wgsl"
#include "shading/decals.wgsl"
#include "$DECAL_QUERY" with VOLUMES=decal
#include "$DECAL_LEAVES"

// The instance the query is in, and the surface in its group's space, set as the query enters it.
// Where a whole subgroup walks together, the surface is turned into the group's space for every decal
// instead: held through that walk it costs more than it saves (benchmarks/LOG.md, topics 2 and 4).
var<private> decal_instance: VolumeInstance;
var<private> decal_world: DecalSurface;
var<private> decal_surface: DecalSurface;

fn decal_query_entered(instance: VolumeInstance) {
    decal_instance = instance;
    if !decal_walk_shared() {
        decal_surface = decal_surface_in_group(decal_world, instance);
    }
    decal_leaves_entered(instance);
}

// Decal `index` of the current instance's group through the tests and the blend.
fn decal_apply(index: u32) {
    var surface = decal_surface;
    if decal_walk_shared() {
        surface = decal_surface_in_group(decal_world, decal_instance);
    }
    decal_accumulate(index, decal_instance, decal_query_point, surface);
}

fn apply_decals(s: ShadingInput, dp: PositionGradients) -> ShadingInput {
    decal_blend_begin();
    decal_world = decal_world_surface(s, dp);
    decal_leaves_begin();
    decal_query_begin(s.position, frame.decal_instance_count);
    for (var leaf = decal_query_next_leaf(); leaf.x != BVH_END; leaf = decal_query_next_leaf()) {
        decal_leaf(leaf);
    }
    return decal_blend_end(s);
}
