// A leaf's decals for `decals_bvh.wgsl`, each through the lane's own tests: walking alone, the leaves
// whose box holds the lane's point; walking as a subgroup, every leaf any lane reaches.

fn decal_leaves_begin() {}

fn decal_leaves_entered(instance: VolumeInstance) {}

fn decal_leaf(leaf: vec2<u32>) {
    for (var k = leaf.x; k < leaf.y; k += 1u) {
        decal_apply(k);
    }
}
