//! How many light or decal volumes reach a point of the scene's surfaces. The enumeration's cost
//! per pixel follows this number rather than the volume count (each reached volume is shaded or
//! sampled), so benchmarks state it beside their timings (`manylights info`).

use glam::Vec3;

use super::{decal_aabb, decal_contains, light_aabb, light_contains, Aabb, Bvh};
use crate::scene::{Groups, Scene};
use crate::Result;

/// Volumes reaching each of a set of points, after the exact test (sphere or cone, decal box).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overlap {
    /// Mean over all points.
    pub mean: f64,
    /// Fraction of the points reached by at least one volume.
    pub covered: f64,
    pub max: usize,
}

/// Lights whose volume reaches each point (world space), in their groups' placements at time 0.
pub fn light_overlap(scene: &Scene, points: &[Vec3]) -> Result<Overlap> {
    let boxes: Vec<Aabb> = scene.lights.iter().map(light_aabb).collect();
    overlap(&boxes, &scene.light_groups, points, |i, p| light_contains(&scene.lights[i], p))
}

/// Decals whose box holds each point (world space), in their groups' placements at time 0.
pub fn decal_overlap(scene: &Scene, points: &[Vec3]) -> Result<Overlap> {
    let boxes: Vec<Aabb> = scene.decals.iter().map(decal_aabb).collect();
    overlap(&boxes, &scene.decal_groups, points, |i, p| decal_contains(&scene.decals[i], p))
}

/// Counts, per point, the items whose box holds it and that `contains` accepts; each group is
/// queried in its own space through each of its instances, as the GPU does.
fn overlap(boxes: &[Aabb], groups: &Groups, points: &[Vec3], contains: impl Fn(usize, Vec3) -> bool) -> Result<Overlap> {
    let (ranges, instances) = groups.resolve(boxes.len());
    let bvhs = ranges.iter().map(|r| Bvh::build(&boxes[r.clone()])).collect::<Result<Vec<_>>>()?;
    let group_from_world: Vec<_> = instances.iter().map(|i| i.world_from_group_at(0.0).inverse()).collect();
    let counts: Vec<usize> = points
        .iter()
        .map(|&p| {
            let mut count = 0;
            for (instance, to_group) in instances.iter().zip(&group_from_world) {
                let range = &ranges[instance.group];
                let local = to_group.transform_point3(p);
                bvhs[instance.group].query_point(&boxes[range.clone()], local, |i| {
                    count += usize::from(contains(range.start + i as usize, local));
                });
            }
            count
        })
        .collect();
    let n = counts.len().max(1) as f64;
    Ok(Overlap {
        mean: counts.iter().sum::<usize>() as f64 / n,
        covered: counts.iter().filter(|&&c| c > 0).count() as f64 / n,
        max: counts.iter().copied().max().unwrap_or(0),
    })
}

#[cfg(test)]
mod tests {
    use glam::Affine3A;

    use super::*;
    use crate::scene::{Decal, GroupInstance};

    fn decal_at(x: f32, edge: f32) -> Decal {
        Decal {
            world_from_decal: Affine3A::from_scale_rotation_translation(Vec3::splat(edge), glam::Quat::IDENTITY, Vec3::new(x, 0.0, 0.0)),
            material: 0,
            layer: 0,
            weight: 1.0,
        }
    }

    #[test]
    fn counts_boxes_holding_each_point_through_instances() {
        // Unit boxes on x ∈ [-0.5, 0.5] and [0, 1]: x = 0.25 is in both, 0.75 in the second, 5.75 in none.
        let mut scene = Scene { decals: vec![decal_at(0.0, 1.0), decal_at(0.5, 1.0)], ..Default::default() };
        let points = [Vec3::new(0.25, 0.0, 0.0), Vec3::new(0.75, 0.0, 0.0), Vec3::new(5.75, 0.0, 0.0)];
        let o = decal_overlap(&scene, &points).unwrap();
        assert_eq!((o.max, o.mean, o.covered), (2, 1.0, 2.0 / 3.0));
        // The group instanced again 5 m along x: the second decal's copy holds the far point.
        let moved = Affine3A::from_translation(Vec3::new(5.0, 0.0, 0.0));
        scene.decal_groups = Groups {
            sizes: vec![2],
            instances: vec![
                GroupInstance { group: 0, world_from_group: Affine3A::IDENTITY, spin: None },
                GroupInstance { group: 0, world_from_group: moved, spin: None },
            ],
        };
        let o = decal_overlap(&scene, &points).unwrap();
        assert_eq!((o.max, o.mean, o.covered), (2, 4.0 / 3.0, 1.0));
    }
}
