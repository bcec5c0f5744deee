//! Debug views (`settings::DebugView`): the heat map of lights reaching each point equals the count a
//! CPU finds for the wall point a pixel shows, in every light method and pipeline; brute force's work
//! is every light at every point, the BVH's its own node count; the decals covering a point are
//! counted as the CPU counts them by every decal method.

mod common;

use common::*;
use glam::{Affine3A, Vec3, Vec4};
use manylights::{
    renderer::Image,
    scene::{Decal, GroupInstance, Groups, Material},
    settings::{heat_map, DebugView, RenderConfig},
    settings::{DecalMethod, LightMethod, PipelineKind},
};

const SIZE: (u32, u32) = (96, 54);

/// The wall point (z = 0) the centre of pixel (x, y) shows: the test camera is 4 m away with a 60°
/// vertical field of view.
fn wall_point(x: u32, y: u32) -> Vec3 {
    let tan = 30f32.to_radians().tan();
    let aspect = SIZE.0 as f32 / SIZE.1 as f32;
    let (nx, ny) = ((x as f32 + 0.5) / SIZE.0 as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / SIZE.1 as f32 * 2.0);
    Vec3::new(nx * tan * aspect * 4.0, ny * tan * 4.0, 0.0)
}

fn close(got: [f32; 4], expected: [f32; 3]) -> bool {
    (0..3).all(|c| (got[c] - expected[c]).abs() <= 1e-5)
}

fn debug_image(scene: &manylights::scene::Scene, camera: &manylights::scene::Camera, config: RenderConfig) -> Image<[f32; 4]> {
    render_with(scene, camera, config).1
}

#[test]
fn the_lights_reaching_each_point_are_counted_alike_by_every_method_and_pipeline_and_as_the_cpu_counts() {
    // Overlapping lights of different ranges in front of the wall: 0 to 4 reach a point.
    let lights = vec![
        point_light(Vec3::new(-1.0, 0.0, 0.5), 1.0, 2.0),
        point_light(Vec3::new(0.5, 0.3, 0.5), 1.0, 1.5),
        point_light(Vec3::new(0.0, -0.5, 1.0), 1.0, 2.5),
        point_light(Vec3::new(2.5, 1.0, 0.3), 1.0, 1.0),
    ];
    let (scene, camera) = wall_scene(lights.clone());
    let scale = DebugView::LightsReaching.scale();
    for pipeline in PipelineKind::ALL {
        for method in [LightMethod::Brute, LightMethod::Bvh, LightMethod::Clustered] {
            let what = format!("{} {}", pipeline.name(), method.name());
            let config = RenderConfig { pipeline, debug_view: DebugView::LightsReaching, ..config(SIZE.0, SIZE.1, method) };
            let image = debug_image(&scene, &camera, config);
            let mut checked = [0usize; 5];
            for y in 0..SIZE.1 {
                for x in 0..SIZE.0 {
                    let p = wall_point(x, y);
                    let distances: Vec<f32> = lights.iter().map(|l| (l.position - p).length() / l.range).collect();
                    // Points within 2 % of a range's edge may round either way.
                    if distances.iter().any(|d| (d - 1.0).abs() < 0.02) {
                        continue;
                    }
                    let count = distances.iter().filter(|&&d| d < 1.0).count();
                    let got = pixel(&image, x, y);
                    assert!(close(got, heat_map(count as u32, scale)), "{what}: pixel ({x}, {y}) shows {got:?}, {count} lights reach it");
                    checked[count] += 1;
                }
            }
            assert!(checked[..4].iter().all(|&n| n > 20), "{what}: too few pixels reached by 0 to 3 lights: {checked:?}");
        }
    }
    // The work: brute force tests all four lights everywhere; the BVH's query shows its own count
    // (nodes visited), not brute force's: walked where the lights are two groups, each point's
    // cell's list (0 to 4 lights, at least those reaching it) where one group is listed.
    let work = |scene: &manylights::scene::Scene, method| {
        debug_image(scene, &camera, RenderConfig { debug_view: DebugView::LightWork, ..config(SIZE.0, SIZE.1, method) })
    };
    let brute = work(&scene, LightMethod::Brute);
    let work_of = |n| heat_map(n, DebugView::LightWork.scale());
    assert!(brute.pixels.iter().all(|&p| close(p, work_of(4))), "brute force tests every light at every point");
    let mut grouped = scene.clone();
    let still = |group| GroupInstance { group, world_from_group: Affine3A::IDENTITY, spin: None };
    grouped.light_groups = Groups { sizes: vec![2, 2], instances: vec![still(0), still(1)] };
    let walked = work(&grouped, LightMethod::Bvh);
    assert!(walked.pixels.iter().all(|&p| p[..3] != [0.0; 3]), "the BVH's work is its nodes visited, at least a root");
    let brute_like = walked.pixels.iter().filter(|&&p| close(p, work_of(4))).count();
    assert!(brute_like < walked.pixels.len() / 2, "the BVH's work is brute force's at {brute_like} pixels");
    let listed = work(&scene, LightMethod::Bvh);
    let mut list_lengths = [0usize; 5];
    for y in 0..SIZE.1 {
        for x in 0..SIZE.0 {
            let p = wall_point(x, y);
            let reaching = lights.iter().filter(|l| (l.position - p).length() < 0.98 * l.range).count();
            let got = pixel(&listed, x, y);
            let length = (reaching..=4).find(|&n| close(got, work_of(n as u32)));
            assert!(length.is_some(), "pixel ({x}, {y}): its cell's list {got:?} is not 0 to 4 lights holding the {reaching} reaching it");
            list_lengths[length.unwrap()] += 1;
        }
    }
    assert!(list_lengths[4] < list_lengths.iter().sum::<usize>(), "every cell lists every light: {list_lengths:?}");
}

#[test]
fn the_decals_covering_each_point_are_counted_alike_by_every_decal_method() {
    let (mut scene, camera) = ambient_wall();
    scene.materials.push(Material { base_color_factor: Vec4::new(1.0, 0.0, 0.0, 1.0), metallic_factor: 0.0, ..Default::default() });
    let material = scene.materials.len() - 1;
    // Two 2 m decals overlapping over 1 m, and a third inside both.
    let at = |x: f32, size: f32| Decal {
        world_from_decal: Affine3A::from_scale_rotation_translation(
            Vec3::new(size, size, 0.5),
            glam::Quat::IDENTITY,
            Vec3::new(x, 0.0, 0.0),
        ),
        material,
        layer: 0,
        weight: 1.0,
    };
    scene.decals = vec![at(-0.5, 2.0), at(0.5, 2.0), at(0.0, 0.5)];
    let scale = DebugView::DecalsCovering.scale();
    for method in [DecalMethod::Brute, DecalMethod::Bvh, DecalMethod::Clustered] {
        let config =
            RenderConfig { decal_method: method, debug_view: DebugView::DecalsCovering, ..config(SIZE.0, SIZE.1, LightMethod::Off) };
        let image = debug_image(&scene, &camera, config);
        let mut seen = [0usize; 4];
        for y in 0..SIZE.1 {
            for x in 0..SIZE.0 {
                let p = wall_point(x, y);
                let inside = |d: &Decal| {
                    let q = d.world_from_decal.inverse().transform_point3(p);
                    q.x.abs() < 0.5 && q.y.abs() < 0.5
                };
                let near_edge = scene.decals.iter().any(|d| {
                    let q = d.world_from_decal.inverse().transform_point3(p);
                    (q.x.abs().max(q.y.abs()) - 0.5).abs() <= 0.02
                });
                if near_edge {
                    continue;
                }
                let count = scene.decals.iter().filter(|d| inside(d)).count();
                let got = pixel(&image, x, y);
                assert!(
                    close(got, heat_map(count as u32, scale)),
                    "{}: pixel ({x}, {y}) shows {got:?}, {count} decals cover it",
                    method.name()
                );
                seen[count] += 1;
            }
        }
        assert!(seen.iter().all(|&n| n > 10), "{}: {seen:?}", method.name());
    }
}

#[test]
fn a_slice_through_the_particle_grid_shows_where_it_is_crossed_and_the_dimmed_scene_elsewhere() {
    let mut scene = manylights::scene::demo::demo_scene();
    let particles = manylights::scene::generators::ScatterParticles::new(4000, 1, 8);
    manylights::scene::generators::add_particles(&mut scene, &particles).unwrap();
    let camera = scene.cameras[0].clone();
    let render = |debug_view, debug_slice_height| {
        let config = RenderConfig { debug_view, debug_slice_height, ..config(SIZE.0, SIZE.1, LightMethod::Brute) };
        debug_image(&scene, &camera, config)
    };
    let shaded = render(DebugView::Off, None);
    // A plane far above everything: no ray crosses it before its surface, so every surface is shown
    // at a tenth of its radiance (the sky is not shaded).
    let above = render(DebugView::ParticleGridSlice, Some(1000.0));
    let near = |a: f32, b: f32| (a - b).abs() <= 1e-6 * b.abs().max(1.0);
    let (mut dimmed, mut sky) = (0, 0);
    for (a, s) in above.pixels.iter().zip(&shaded.pixels) {
        if (0..3).all(|c| near(a[c], 0.1 * s[c])) {
            dimmed += 1;
        } else {
            assert!((0..3).all(|c| a[c] == s[c]), "a pixel neither dimmed nor sky: {a:?} from {s:?}");
            sky += 1;
        }
    }
    assert!(dimmed > sky * 2, "{dimmed} dimmed surface pixels, {sky} sky pixels");
    // Half a metre above the floor, through the particles: the grid shows where rays cross it.
    let through = render(DebugView::ParticleGridSlice, Some(0.5));
    let sliced = through.pixels.iter().zip(&above.pixels).filter(|(t, a)| (0..3).any(|c| (t[c] - a[c]).abs() > 1e-3)).count();
    assert!(sliced * 10 > through.pixels.len(), "only {sliced} pixels show the slice");
}
