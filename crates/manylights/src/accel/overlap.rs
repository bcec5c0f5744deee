//! How many light or decal volumes reach a point of the scene's surfaces. The enumeration's cost
//! per pixel follows this number rather than the volume count (each reached volume is shaded or
//! sampled), so benchmarks state it beside their timings (`manylights info`).

use std::ops::Range;

use glam::Vec3;

use super::{decal_aabb, decal_contains, light_aabb, light_contains, Aabb, Bvh};
use crate::plan::{Measurements, SceneStatistics};
use crate::scene::{generators::surface_points, Groups, Scene};
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

/// Volumes [`centre_overlap`] samples, evenly spread over the groups.
pub const OVERLAP_SAMPLES: usize = 4096;

/// The mean number of boxes of its group holding a volume's box centre, over up to [`OVERLAP_SAMPLES`]
/// volumes of the groups that have a BVH (`builds`, one per range of `boxes`); 0 without any. A
/// decal's centre lies on the surface it is projected on, so this is how crowded the point queries'
/// leaves are where decals show.
pub fn centre_overlap(boxes: &[Aabb], ranges: &[Range<usize>], builds: &[Option<Bvh>]) -> f32 {
    let built: usize = ranges.iter().zip(builds).filter(|(_, b)| b.is_some()).map(|(r, _)| r.len()).sum();
    let step = built.div_ceil(OVERLAP_SAMPLES).max(1);
    // Every step-th volume counted over all the CPU-built groups together, so many small groups
    // take no more samples than one large one.
    let (mut seen, mut samples, mut holding) = (0usize, 0usize, 0usize);
    for (range, build) in ranges.iter().zip(builds) {
        let Some(bvh) = build else { continue };
        let group = &boxes[range.clone()];
        let first = (step - seen % step) % step;
        for b in group.iter().skip(first).step_by(step) {
            bvh.query_point(group, (b.min + b.max) * 0.5, |_| holding += 1);
            samples += 1;
        }
        seen += group.len();
    }
    if samples == 0 {
        0.0
    } else {
        holding as f32 / samples as f32
    }
}

/// Surface points and placed volumes [`sampled_overlap`] tests against each other, at most.
pub const SAMPLED_POINTS: usize = 1024;
pub const SAMPLED_VOLUMES: usize = 2048;

/// The mean number of placed volumes (each group's items through each of its instances, at time 0)
/// that `contains` accepts at a point of the surfaces, estimated from every k-th placed volume
/// against [`SAMPLED_POINTS`] surface points, k chosen so that at most [`SAMPLED_VOLUMES`] are
/// tested: an unbiased estimate whose cost does not grow with the scene. 0 for no points.
pub fn sampled_overlap<T>(
    items: &[T],
    groups: &Groups,
    points: &[Vec3],
    bounds: impl Fn(&T) -> Aabb,
    contains: impl Fn(&T, Vec3) -> bool,
) -> f32 {
    let (ranges, instances) = groups.resolve(items.len());
    let placed = groups.placed_count(items.len());
    if points.is_empty() || placed == 0 {
        return 0.0;
    }
    let step = placed.div_ceil(SAMPLED_VOLUMES).max(1);
    let (mut seen, mut sampled, mut hits) = (0usize, 0usize, 0usize);
    for instance in &instances {
        let range = ranges[instance.group].clone();
        let group_from_world = instance.world_from_group_at(0.0).inverse();
        let local: Vec<Vec3> = points.iter().map(|&p| group_from_world.transform_point3(p)).collect();
        let first = (step - seen % step) % step;
        for item in items[range.clone()].iter().skip(first).step_by(step) {
            let b = bounds(item);
            hits += local.iter().filter(|&&p| p.cmpge(b.min).all() && p.cmple(b.max).all() && contains(item, p)).count();
            sampled += 1;
        }
        seen += range.len();
    }
    if sampled == 0 {
        return 0.0;
    }
    (hits as f64 * placed as f64 / sampled as f64 / points.len() as f64) as f32
}

/// The statistics the frame plan reads (`plan::FramePlan::resolve`), measuring only what
/// `measurements` asks.
pub fn scene_statistics(scene: &Scene, measurements: Measurements) -> Result<SceneStatistics> {
    let (ranges, instances) = scene.decal_groups.resolve(scene.decals.len());
    let (light_ranges, light_instances) = scene.light_groups.resolve(scene.lights.len());
    let decal_centre_overlap = if measurements.decal_centre_overlap {
        let boxes: Vec<Aabb> = scene.decals.iter().map(decal_aabb).collect();
        let builds =
            ranges.iter().map(|r| (!r.is_empty()).then(|| Bvh::build(&boxes[r.clone()])).transpose()).collect::<Result<Vec<_>>>()?;
        Some(centre_overlap(&boxes, &ranges, &builds))
    } else {
        None
    };
    let placed_lights = scene.light_groups.placed_count(scene.lights.len());
    let placed_decals = scene.decal_groups.placed_count(scene.decals.len());
    let points =
        if measurements.light_overlap || measurements.decal_overlap { surface_points(scene, SAMPLED_POINTS, 1) } else { Vec::new() };
    let light_overlap =
        measurements.light_overlap.then(|| sampled_overlap(&scene.lights, &scene.light_groups, &points, light_aabb, light_contains));
    let decal_overlap =
        measurements.decal_overlap.then(|| sampled_overlap(&scene.decals, &scene.decal_groups, &points, decal_aabb, decal_contains));
    Ok(SceneStatistics {
        particles: scene.particles.as_ref().map_or(0, |p| p.count),
        placed_lights,
        placed_decals,
        light_overlap,
        decal_overlap,
        placed_light_groups: light_instances.iter().filter(|i| !light_ranges[i.group].is_empty()).count(),
        placed_decal_groups: instances.iter().filter(|i| !ranges[i.group].is_empty()).count(),
        decal_centre_overlap,
        animated_instances: scene.animation.as_ref().is_some_and(|a| !a.instances.is_empty()) || !scene.deformers.is_empty(),
        material_extensions: scene
            .materials
            .iter()
            .any(|m| m.unlit || m.clearcoat.is_some() || m.transmission.is_some() || m.specular != crate::scene::Specular::default()),
        vertex_colors: scene
            .meshes
            .iter()
            .flat_map(|m| &m.primitives)
            .any(|p| p.vertices.iter().any(|v| v.color != crate::scene::Vertex::WHITE)),
        occlusion_textures: scene.materials.iter().any(|m| m.occlusion_texture.is_some()),
        second_uv_set: scene.materials.iter().flat_map(|m| m.textures()).any(|(t, _)| t.tex_coord == 1),
        // Only drawn materials: the transparent pass copies the opaque image for them every frame.
        transmission: scene
            .instances
            .iter()
            .flat_map(|i| &scene.meshes[i.mesh].primitives)
            .any(|p| scene.materials[p.material].transmission.is_some()),
        sheen: scene.materials.iter().any(|m| m.sheen.is_some()),
    })
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

    #[test]
    fn sampled_overlap_is_exact_for_few_volumes_and_close_for_many() {
        let mut scene = crate::scene::demo::demo_scene();
        let points = surface_points(&scene, SAMPLED_POINTS, 1);
        let overlap_of = |scene: &Scene| {
            let exact = light_overlap(scene, &points).unwrap().mean as f32;
            (sampled_overlap(&scene.lights, &scene.light_groups, &points, light_aabb, light_contains), exact)
        };
        // Up to SAMPLED_VOLUMES placed volumes, every one is tested: the mean itself.
        let (sampled, exact) = overlap_of(&scene);
        assert!(scene.lights.len() <= SAMPLED_VOLUMES && exact > 0.0);
        assert!((sampled - exact).abs() <= 1e-4 * exact, "{sampled} against {exact}");
        // Beyond, every k-th: an estimate of the same mean, here within 10 %.
        let params = crate::scene::generators::ScatterLights { count: 20 * SAMPLED_VOLUMES, range: Some((0.5, 1.5)), ..Default::default() };
        crate::scene::generators::add_scattered_lights(&mut scene, &params).unwrap();
        let (sampled, exact) = overlap_of(&scene);
        assert!(exact > 5.0 && (sampled - exact).abs() <= 0.1 * exact, "{sampled} against {exact}");
    }

    #[test]
    fn centre_overlap_counts_the_boxes_holding_each_centre_in_its_group() {
        let at = |x: f32| Aabb::new(glam::Vec3::new(x, 0.0, 0.0), glam::Vec3::new(x + 1.0, 1.0, 1.0));
        // Ten stacked boxes, a lone one, and ten more stacked in a group built on the GPU.
        let boxes: Vec<Aabb> = std::iter::repeat_n(at(0.0), 10).chain([at(5.0)]).chain(std::iter::repeat_n(at(0.0), 10)).collect();
        let ranges = [0..10, 10..11, 11..21];
        let built = |range: &Range<usize>| Some(Bvh::build(&boxes[range.clone()]).unwrap());
        let builds = [built(&ranges[0]), built(&ranges[1]), None];
        assert_eq!(centre_overlap(&boxes, &ranges, &builds), (10.0 * 10.0 + 1.0) / 11.0);
        assert_eq!(centre_overlap(&boxes, &ranges[1..2], &builds[1..2]), 1.0);
        assert_eq!(centre_overlap(&boxes, &ranges[2..], &builds[2..]), 0.0);
        // More one-box groups than samples: every group sampled holds its own box alone.
        let many: Vec<Aabb> = (0..3 * OVERLAP_SAMPLES).map(|i| at(2.0 * i as f32)).collect();
        let ranges: Vec<Range<usize>> = (0..many.len()).map(|i| i..i + 1).collect();
        let builds: Vec<Option<Bvh>> = ranges.iter().map(|r| Some(Bvh::build(&many[r.clone()]).unwrap())).collect();
        assert_eq!(centre_overlap(&many, &ranges, &builds), 1.0);
    }
}
