//! The light tree: what `restir` needs to draw its candidates through a group's BVH instead of
//! enumerating the lights that reach a point (Conty Estevez & Kulla 2018; `shading/light_tree.wgsl`).
//! Every node of a light group gets, beside its box (the union of its lights' volumes), the box
//! around its lights' positions, their total power and their largest range; a descent picks a child
//! in proportion to an importance estimated from them, so each light's probability is the product of
//! the choices on its path, exact and known. CPU-built groups get theirs here
//! ([`light_tree_nodes`]); groups rebuilt on the GPU, the particles' too, from their LBVH build
//! (`lbvh.wgsl`, `LIGHT_TREE`).

use glam::Vec3;

use super::bvh::{Bvh, END};
use crate::gpu::scene::GpuLight;

/// A BVH node's emitters, at the node's index in the light structure. Keep in sync with
/// `LightTreeNode` in `accel/bvh_types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LightTreeNode {
    /// The box around the positions of the node's lights (group space).
    pub min: [f32; 3],
    /// Their total power: the luminance of each one's radiant intensity, summed.
    pub power: f32,
    pub max: [f32; 3],
    /// The largest of their ranges.
    pub range: f32,
}

impl LightTreeNode {
    /// One light's emitter: its position as a point box, its power and its range. A GPU build over
    /// lights takes one per box (`GpuLbvh::set_emitters`; particles write theirs, `particles/lights.wgsl`).
    pub fn of_light(light: &GpuLight) -> Self {
        Self { min: light.position, power: light_power(light), max: light.position, range: light.range }
    }
}

/// A light's power as the tree weighs it: the luminance of its colour × intensity.
pub fn light_power(light: &GpuLight) -> f32 {
    Vec3::from(light.radiant).dot(Vec3::new(0.2126, 0.7152, 0.0722)).max(0.0)
}

/// The emitters of each node of `bvh`, a group's BVH whose leaves name `lights` by primitive index.
/// The nodes are in depth-first order (children after their parent), so one pass from the last
/// node back sums each subtree.
pub fn light_tree_nodes(bvh: &Bvh, lights: &[GpuLight]) -> Vec<LightTreeNode> {
    let mut tree = vec![LightTreeNode::default(); bvh.nodes.len()];
    for index in (0..bvh.nodes.len()).rev() {
        let node = bvh.nodes[index];
        tree[index] = if node.is_leaf() {
            bvh.primitive_indices[node.leaf_range()].iter().fold(EMPTY, |t, &i| union(t, LightTreeNode::of_light(&lights[i as usize])))
        } else {
            let first = node.entry as usize;
            let second = bvh.nodes[first].skip;
            debug_assert!(first > index && second != END);
            union(tree[first], tree[second as usize])
        };
    }
    tree
}

/// No emitters: the identity of [`union`].
pub const EMPTY: LightTreeNode = LightTreeNode { min: [f32::INFINITY; 3], power: 0.0, max: [f32::NEG_INFINITY; 3], range: 0.0 };

/// The emitters of two nodes together.
pub fn union(a: LightTreeNode, b: LightTreeNode) -> LightTreeNode {
    LightTreeNode {
        min: Vec3::from(a.min).min(Vec3::from(b.min)).into(),
        power: a.power + b.power,
        max: Vec3::from(a.max).max(Vec3::from(b.max)).into(),
        range: a.range.max(b.range),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::light_aabb;
    use crate::scene::{Light, LightKind};

    #[test]
    fn each_node_bounds_its_lights_and_sums_their_power() {
        let lights: Vec<Light> = (0..300)
            .map(|i| {
                let t = i as f32;
                Light {
                    kind: LightKind::Point,
                    position: Vec3::new((t * 0.37).sin() * 10.0, (t * 0.11).cos() * 4.0, t * 0.05),
                    direction: Vec3::NEG_Z,
                    color: Vec3::new(1.0, 0.5 + 0.5 * (t * 0.3).sin(), 0.2),
                    intensity: 1.0 + (i % 7) as f32,
                    range: 0.5 + (i % 5) as f32,
                    cast_shadows: false,
                }
            })
            .collect();
        let records: Vec<GpuLight> = lights.iter().map(GpuLight::from).collect();
        let boxes: Vec<_> = lights.iter().map(light_aabb).collect();
        for bvh in [Bvh::build(&boxes).unwrap(), Bvh::build_wide(&boxes).unwrap()] {
            let tree = light_tree_nodes(&bvh, &records);
            let total: f32 = records.iter().map(light_power).sum();
            assert!((tree[0].power - total).abs() <= 1e-4 * total, "root {} against {total}", tree[0].power);
            // Every node against its lights, gathered by walking its subtree.
            for (index, node) in bvh.nodes.iter().enumerate() {
                let end = if node.skip == END { bvh.nodes.len() } else { node.skip as usize };
                let lights_below: Vec<usize> = (index..end)
                    .filter(|&n| bvh.nodes[n].is_leaf())
                    .flat_map(|n| bvh.primitive_indices[bvh.nodes[n].leaf_range()].iter().map(|&i| i as usize))
                    .collect();
                let power: f32 = lights_below.iter().map(|&i| light_power(&records[i])).sum();
                assert!((tree[index].power - power).abs() <= 1e-4 * power.max(1.0), "node {index}");
                for &i in &lights_below {
                    let p = Vec3::from(records[i].position);
                    assert!(p.cmpge(Vec3::from(tree[index].min)).all() && p.cmple(Vec3::from(tree[index].max)).all(), "node {index}");
                }
                let bounds = lights_below.iter().fold(EMPTY, |t, &i| {
                    let p = Vec3::from(records[i].position);
                    union(t, LightTreeNode { min: p.into(), power: 0.0, max: p.into(), range: records[i].range })
                });
                assert_eq!(
                    (tree[index].min, tree[index].max, tree[index].range),
                    (bounds.min, bounds.max, bounds.range),
                    "node {index} is tight"
                );
            }
        }
    }
}
