// Decal enumeration through the decals' acceleration structure (Hansen & Peters 2021): the point
// query reaches the leaves whose box contains the shading point; `decal_accumulate` applies the
// exact box test, so the result equals the brute-force loop's.
#include "shading/decal_bindings.wgsl"
#include "shading/decals.wgsl"
#include "$DECAL_QUERY" with VOLUMES=decal

// The instance the query is in: its decals are tested and applied through it.
var<private> decal_instance: VolumeInstance;

fn decal_query_entered(instance: VolumeInstance) {
    decal_instance = instance;
}

fn apply_decals(s: ShadingInput, dp: PositionGradients) -> ShadingInput {
    decal_blend_begin();
    decal_query_begin(s.position, frame.decal_instance_count);
    for (var leaf = decal_query_next_leaf(); leaf.x != BVH_END; leaf = decal_query_next_leaf()) {
        for (var k = leaf.x; k < leaf.y; k += 1u) {
            decal_accumulate(decals[k], decal_instance, decal_query_point, s, dp);
        }
    }
    return decal_blend_end(s);
}
