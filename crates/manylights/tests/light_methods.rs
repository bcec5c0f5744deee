//! Every light enumeration method gives the brute-force image: linear HDR, max abs difference ≤ 1e-3.

mod common;

use std::path::PathBuf;

use common::*;
use glam::{Affine3A, Quat, Vec3};
use manylights::{
    scene::{self, demo::demo_scene, generators::ScatterLights, GroupInstance, Groups, Light, LightKind, Scene, Spin},
    settings::{BvhBuild, LightMethod, PipelineKind, RaySettings, RenderConfig},
};
use rand::{Rng, SeedableRng};

const TOLERANCE: f32 = 1e-3;

/// Every method that lights, whichever way it finds the lights (`off` is the unlit baseline).
fn lighting_methods() -> impl Iterator<Item = LightMethod> {
    LightMethod::ALL.into_iter().filter(|&m| m != LightMethod::Off)
}

fn assert_methods_agree(scene: &Scene, width: u32, height: u32) {
    assert_methods_agree_at(scene, width, height, 0.0);
}

/// Renders one frame at scene time `time` (where spinning groups are).
fn render_at(scene: &Scene, config: RenderConfig, time: f32) -> manylights::renderer::Image<[f32; 4]> {
    let mut r = renderer(scene, config);
    r.time = time;
    r.render(&scene.cameras[0]).expect("frame");
    r.read_hdr().expect("hdr")
}

fn assert_methods_agree_at(scene: &Scene, width: u32, height: u32, time: f32) {
    let brute = render_at(scene, config(width, height, LightMethod::Brute), time);
    let lit = brute.pixels.iter().filter(|p| p[0] + p[1] + p[2] > 0.0).count();
    assert!(lit > brute.pixels.len() / 2, "the reference image is mostly black");
    let gpu_built = RenderConfig { light_bvh_build: BvhBuild::GpuEveryFrame, ..config(width, height, LightMethod::Bvh) };
    let configs = lighting_methods().map(|method| config(width, height, method)).chain([gpu_built]);
    for config in configs {
        let image = render_at(scene, config.clone(), time);
        let difference = max_abs_difference(&brute, &image);
        assert!(
            difference <= TOLERANCE,
            "{} ({:?}): max abs difference {difference} from brute force",
            config.light_method.name(),
            config.light_bvh_build
        );
    }
}

fn with_scattered_lights(mut scene: Scene, count: usize, seed: u64) -> Scene {
    scene::generators::add_scattered_lights(&mut scene, &ScatterLights { count, seed, ..Default::default() }).unwrap();
    scene
}

/// Spot lights of every width, pointing every way, scattered through the demo room.
fn random_spots(count: usize, seed: u64) -> Vec<Light> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            let outer: f32 = rng.random_range(0.02..1.5);
            let direction = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..0.2), rng.random_range(-1.0..1.0)).normalize();
            Light {
                kind: LightKind::Spot { inner_cone_angle: outer * rng.random_range(0.0..0.9), outer_cone_angle: outer },
                position: Vec3::new(rng.random_range(-4.5..4.5), rng.random_range(0.2..4.5), rng.random_range(-4.5..4.5)),
                direction,
                color: Vec3::new(rng.random(), rng.random(), rng.random()),
                intensity: rng.random_range(1.0..8.0),
                range: rng.random_range(0.5..6.0),
                cast_shadows: false,
            }
        })
        .collect()
}

#[test]
fn demo_with_many_point_and_spot_lights() {
    let mut scene = with_scattered_lights(demo_scene(), 1500, 7);
    scene.lights.extend(random_spots(300, 11));
    assert_methods_agree(&scene, WIDTH, HEIGHT);
}

#[test]
fn dense_lights_walked_a_subgroup_at_a_time_match_brute_force() {
    // Large ranges in the demo room: dozens reach every point, past `DENSE_LIGHT_OVERLAP`, so bvh
    // lights get wide leaves that subgroups share out (built once or rebuilt every frame).
    let mut scene = demo_scene();
    scene::generators::add_scattered_lights(
        &mut scene,
        &ScatterLights { count: 600, seed: 5, range: Some((2.0, 3.0)), ..Default::default() },
    )
    .unwrap();
    let r = renderer(&scene, config(WIDTH, HEIGHT, LightMethod::Bvh));
    assert_eq!(r.shading_methods().dense_lights, r.shading_methods().subgroups, "the lights should count as dense");
    assert_methods_agree(&scene, WIDTH, HEIGHT);
}

#[test]
fn sponza_with_thousands_of_lights() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets/sponza/Sponza.gltf");
    let mut scene = with_scattered_lights(scene::load_path(&path).unwrap(), 4000, 3);
    scene.ambient = Vec3::splat(0.05);
    assert_methods_agree(&scene, 128, 72);
}

#[test]
fn no_lights() {
    let mut scene = demo_scene();
    scene.lights.clear();
    assert_methods_agree(&scene, 64, 36);
}

/// Large lights overlapping each other everywhere need more list entries than the clustered lists
/// start with: the renderer grows them and renders the frame again, so the image stays exact.
/// Lights around the eye — behind it, beside it, straddling the near plane — reach the visible
/// surfaces in front of it: the clustered lists bound them by the part beyond the near plane.
#[test]
fn lights_around_the_camera() {
    let mut scene = demo_scene();
    let eye = scene.cameras[0].position();
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    scene.lights = (0..300)
        .map(|_| {
            let offset = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let mut light = point_light(eye + offset, rng.random_range(0.05..0.2), rng.random_range(2.0..8.0));
            light.color = Vec3::new(rng.random_range(0.2..1.0), rng.random_range(0.2..1.0), rng.random_range(0.2..1.0));
            light
        })
        .collect();
    assert_methods_agree(&scene, 64, 36);
}

#[test]
fn clustered_lists_grow_to_what_the_view_needs() {
    let params = ScatterLights { count: 2000, seed: 3, range: Some((6.0, 12.0)), intensity: Some((0.01, 0.05)), ..Default::default() };
    let mut scene = demo_scene();
    scene::generators::add_scattered_lights(&mut scene, &params).unwrap();
    let mut clustered = renderer(&scene, config(128, 72, LightMethod::Clustered));
    let initial = clustered.cluster_capacities().0.expect("clustered lights have lists");
    clustered.render(&scene.cameras[0]).expect("frame");
    let grown = clustered.cluster_capacities().0.unwrap();
    assert!(grown > initial, "the lists did not grow ({initial} entries)");
    let brute = render_at(&scene, config(128, 72, LightMethod::Brute), 0.0);
    let difference = max_abs_difference(&brute, &clustered.read_hdr().unwrap());
    assert!(difference <= TOLERANCE, "clustered after growing: max abs difference {difference} from brute force");
}

#[test]
fn a_million_lights_fit_and_light_the_scene() {
    // 1M lights (64 MiB) and their BVH stay under lavapipe's 128 MiB storage bindings.
    let base = demo_scene();
    let mut scene = base.clone();
    let params = ScatterLights { count: 1 << 20, seed: 5, range: Some((0.05, 0.15)), intensity: Some((0.01, 0.02)), ..Default::default() };
    scene::generators::add_scattered_lights(&mut scene, &params).unwrap();
    let camera = &scene.cameras[0];
    let (_, without) = render_with(&base, camera, config(64, 36, LightMethod::Bvh));
    let (_, with) = render_with(&scene, camera, config(64, 36, LightMethod::Bvh));
    assert!(with.pixels.iter().all(|p| p.iter().all(|c| c.is_finite())));
    let added: f32 = with.pixels.iter().zip(&without.pixels).map(|(a, b)| luminance(*a) - luminance(*b)).sum();
    assert!(added > 0.0, "a million lights added no light");
}

/// The demo's lights split into groups: the first placed twice (once scaled, turned and shifted), the second
/// spinning, the third left alone.
fn grouped_demo() -> Scene {
    let mut scene = with_scattered_lights(demo_scene(), 1200, 17);
    scene.lights.extend(random_spots(300, 19));
    let still = |group, world_from_group| GroupInstance { group, world_from_group, spin: None };
    scene.light_groups = Groups {
        sizes: vec![507, 400, 600],
        instances: vec![
            still(0, Affine3A::IDENTITY),
            still(0, Affine3A::from_scale_rotation_translation(Vec3::splat(1.3), Quat::from_rotation_y(0.8), Vec3::new(0.5, 0.2, -0.3))),
            GroupInstance {
                spin: Some(Spin { pivot: Vec3::new(-0.5, 0.0, -1.0), radians_per_second: 1.3 }),
                ..still(1, Affine3A::IDENTITY)
            },
            still(2, Affine3A::IDENTITY),
        ],
    };
    scene
}

/// Sparse lights rebuilt every frame as one group placed once (here turned, and spinning) are read
/// from cell lists rebuilt on the GPU in place of their LBVH, and light every pipeline as brute force
/// does, reflections' hits too.
#[test]
fn sparse_lights_rebuilt_every_frame_are_read_from_cell_lists() {
    let mut scene = with_scattered_lights(demo_scene(), 1500, 23);
    scene.lights.extend(random_spots(200, 29));
    scene.light_groups = Groups {
        sizes: vec![scene.lights.len()],
        instances: vec![GroupInstance {
            group: 0,
            world_from_group: Affine3A::from_rotation_translation(Quat::from_rotation_y(0.4), Vec3::new(0.3, 0.0, -0.2)),
            spin: Some(Spin { pivot: Vec3::new(0.5, 0.0, 0.5), radians_per_second: 0.5 }),
        }],
    };
    for pipeline in PipelineKind::ALL {
        let reflections = RaySettings { reflection_bounces: u32::from(pipeline == PipelineKind::Visbuffer), ..Default::default() };
        let at = |method| RenderConfig { pipeline, rays: reflections, ..config(96, 54, method) };
        let brute = render_at(&scene, at(LightMethod::Brute), 0.6);
        let mut rebuilt = renderer(&scene, RenderConfig { light_bvh_build: BvhBuild::GpuEveryFrame, ..at(LightMethod::Bvh) });
        assert!(rebuilt.shading_methods().gpu_light_lists, "{}: the rebuilt lights are not listed", pipeline.name());
        rebuilt.time = 0.6;
        rebuilt.render(&scene.cameras[0]).expect("frame");
        let difference = max_abs_difference(&brute, &rebuilt.read_hdr().unwrap());
        assert!(difference <= TOLERANCE, "{}: max abs difference {difference} from brute force", pipeline.name());
    }
}

#[test]
fn instanced_and_moving_light_groups() {
    // At time 0.6 the spinning group has turned 0.78 rad: the top level is rebuilt for it.
    assert_methods_agree_at(&grouped_demo(), 128, 72, 0.6);
}

#[test]
fn an_instanced_group_lights_like_its_lights_copied_into_the_world() {
    let grouped = grouped_demo();
    let (ranges, instances) = grouped.light_groups.resolve(grouped.lights.len());
    let mut expanded = grouped.clone();
    expanded.light_groups = Groups::default();
    expanded.lights = instances
        .iter()
        .flat_map(|instance| {
            let t = instance.world_from_group_at(0.6);
            let scale = t.matrix3.x_axis.length();
            grouped.lights[ranges[instance.group].clone()].iter().map(move |l| Light {
                position: t.transform_point3(l.position),
                direction: t.transform_vector3(l.direction) / scale,
                range: l.range * scale,
                ..*l
            })
        })
        .collect();
    let expected = render_at(&expanded, config(128, 72, LightMethod::Brute), 0.0);
    for method in lighting_methods() {
        let image = render_at(&grouped, config(128, 72, method), 0.6);
        let difference = max_abs_difference(&expected, &image);
        assert!(difference <= TOLERANCE, "{}: max abs difference {difference} from the expanded lights", method.name());
    }
}

/// 70,000 lights that all reach every pixel of a wall: a loop over more than 65,535 of them, which an
/// old lavapipe (Mesa before its loop limiter went) would end early. Brute force and the clustered
/// lists (70,000 long in every froxel) must equal the BVH's walk, and the last lights must count:
/// they are the bright ones. Where the driver does limit loops, brute force and clustered shading are
/// refused instead, with the limit named.
#[test]
fn seventy_thousand_lights_on_one_point_are_all_shaded() {
    const COUNT: usize = 70_000;
    const DIM: usize = 65_535;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(70);
    let lights: Vec<Light> = (0..COUNT)
        .map(|i| {
            let position = Vec3::new(rng.random_range(-3.0..3.0), rng.random_range(-2.0..2.0), rng.random_range(1.0..3.0));
            point_light(position, if i < DIM { 1e-4 } else { 1e-2 }, 30.0)
        })
        .collect();
    let (scene, camera) = wall_scene(lights);
    let (width, height) = (16, 9);
    let ctx = manylights::gpu::GpuContext::new().expect("a GPU adapter");
    let render = |scene: &Scene, method: LightMethod| {
        manylights::renderer::Renderer::new(ctx.clone(), scene, config(width, height, method)).and_then(|mut r| {
            r.render(&camera)?;
            r.read_hdr()
        })
    };
    if let Some(limit) = ctx.loop_limit {
        for method in [LightMethod::Brute, LightMethod::Clustered] {
            let refused = render(&scene, method).err().map(|e| e.to_string()).unwrap_or_default();
            assert!(refused.contains(&format!("after {limit} iterations")), "{}: {refused}", method.name());
        }
        return;
    }
    let bvh = render(&scene, LightMethod::Bvh).expect("bvh");
    for method in [LightMethod::Brute, LightMethod::Clustered] {
        let image = render(&scene, method).expect("frame");
        let difference = bvh.pixels.iter().zip(&image.pixels).map(|(a, b)| (a[0] - b[0]).abs() / a[0].max(1e-6)).fold(0.0, f32::max);
        assert!(difference <= 1e-3, "{}: relative difference {difference} from bvh", method.name());
    }
    // The bright lights past the 65,535th carry most of the light: without them the wall is far darker.
    let first = Scene { lights: scene.lights[..DIM].to_vec(), ..scene.clone() };
    let dim = render(&first, LightMethod::Brute).expect("frame");
    let centre = |image: &manylights::renderer::Image<[f32; 4]>| pixel(image, width / 2, height / 2)[0];
    assert!(centre(&bvh) > 2.0 * centre(&dim), "all lights {} against the first {DIM} alone {}", centre(&bvh), centre(&dim));
}
