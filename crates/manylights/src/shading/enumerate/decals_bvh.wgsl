// Decal enumeration through the decals' acceleration structure (Hansen & Peters 2021): the point
// query reaches the leaves whose box contains the shading point (walking as a subgroup, those of its
// neighbours too, `accel/volume_query.wgsl`); `decal_accumulate` applies the
// exact box test, so the result equals the brute-force loop's.
#include "shading/decal_bindings.wgsl"
#include "shading/decals.wgsl"
#include "$DECAL_QUERY" with VOLUMES=decal

// The instance the query is in, and the surface in its group's space, set as the query enters it.
// Where a whole subgroup walks together (fragments, `passes::query_walks`), the surface is turned into
// the group's space for every decal instead: held through that walk it cost more than it saved
// (BENCHMARKS.md, "Debug counters, decals in their group's space, …").
var<private> decal_instance: VolumeInstance;
var<private> decal_world: DecalSurface;
var<private> decal_surface: DecalSurface;

fn decal_query_entered(instance: VolumeInstance) {
    decal_instance = instance;
    if !decal_walk_shared() {
        decal_surface = decal_surface_in_group(decal_world, instance);
    }
}

fn apply_decals(s: ShadingInput, dp: PositionGradients) -> ShadingInput {
    decal_blend_begin();
    decal_world = decal_world_surface(s, dp);
    decal_query_begin(s.position, frame.decal_instance_count);
    for (var leaf = decal_query_next_leaf(); leaf.x != BVH_END; leaf = decal_query_next_leaf()) {
        for (var k = leaf.x; k < leaf.y; k += 1u) {
            var surface = decal_surface;
            if decal_walk_shared() {
                surface = decal_surface_in_group(decal_world, decal_instance);
            }
            decal_accumulate(k, decal_instance, decal_query_point, surface);
        }
    }
    return decal_blend_end(s);
}
