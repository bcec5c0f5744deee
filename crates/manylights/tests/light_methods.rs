//! Every light enumeration method gives the brute-force image: linear HDR, max abs difference ≤ 1e-3.

mod common;

use std::path::PathBuf;

use common::*;
use glam::Vec3;
use manylights::{
    accel::BvhBuild,
    config::RenderConfig,
    pipelines::LightMethod,
    scene::{self, demo::demo_scene, generators::ScatterLights, Light, LightKind, Scene},
};
use rand::{Rng, SeedableRng};

const TOLERANCE: f32 = 1e-3;

fn assert_methods_agree(scene: &Scene, width: u32, height: u32) {
    let camera = &scene.cameras[0];
    let (_, brute) = render_with(scene, camera, config(width, height, LightMethod::Brute));
    let lit = brute.pixels.iter().filter(|p| p[0] + p[1] + p[2] > 0.0).count();
    assert!(lit > brute.pixels.len() / 2, "the reference image is mostly black");
    let gpu_built = RenderConfig { light_bvh_build: BvhBuild::GpuEveryFrame, ..config(width, height, LightMethod::Bvh) };
    let configs = LightMethod::ALL.iter().map(|&method| config(width, height, method)).chain([gpu_built]);
    for config in configs {
        let (_, image) = render_with(scene, camera, config.clone());
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
