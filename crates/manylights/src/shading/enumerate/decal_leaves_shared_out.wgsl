// A leaf's decals for `decals_bvh.wgsl`, shared out among the lanes of a subgroup walking together
// (dense decals, `plan::query_walks`), as the dense lights' leaves are (`lights_bvh.wgsl`): each
// lane tests one decal of the leaf against the box around all the lanes' points, then every lane
// takes the decals some lane kept, one after the other, through its own tests. A subgroup's width of
// box tests takes one round instead of one each in every lane, and each kept decal is read at one
// address by the whole subgroup, so these decals' groups have wide leaves (`Bvh::build_wide`). Where
// decals crowd (100k of about a metre over Sponza) this is faster than every lane testing every decal,
// more so with the wide leaves; where they crowd less it is slower (benchmarks/LOG.md, topic 2).

#include "shading/decal_box.wgsl"

// The lanes walking together (`VOLUMES_walk_lanes`), counted once: they all stay in the walk to its end.
var<private> decal_lanes: vec3<u32>;
// The box around the lanes' points in the space of the instance the query is in.
var<private> decal_walk_box: array<vec3<f32>, 2>;

fn decal_leaves_begin() {
    decal_lanes = decal_walk_lanes();
}

fn decal_leaves_entered(instance: VolumeInstance) {
    decal_walk_box = decal_walk_bounds(instance_point_to_group(instance, decal_query_world_point));
}

// Lanes past the leaf's end read its last decal and keep none. The lane's index of a kept decal comes
// by shuffle before any lane's own tests, while every lane is active (as in `lights_bvh.wgsl`).
fn decal_leaf(leaf: vec2<u32>) {
    for (var first = leaf.x; first < leaf.y; first += decal_lanes.y) {
        let k = first + decal_lanes.x;
        let rows = decals[min(k, leaf.y - 1u)].decal_from_group;
        let kept = decal_walk_ballot(k < leaf.y && decal_box_meets_box(rows, decal_walk_box[0], decal_walk_box[1]));
        for (var word = 0u; word < decal_lanes.z; word += 1u) {
            for (var bits = kept[word]; bits != 0u; bits &= bits - 1u) {
                decal_apply(decal_walk_lane_u32(k, word * 32u + firstTrailingBit(bits)));
            }
        }
    }
}
