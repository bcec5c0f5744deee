//! Every scene of the shared assets with the default settings, as a new user renders it: alone and
//! with scattered lights, decals or particles, the picture is exposed (auto exposure), `auto` picks a
//! method that is not brute force where there are many volumes, and its image is brute force's.

mod common;

use std::path::PathBuf;

use common::*;
use manylights::{
    plan::BRUTE_FORCE_MAX,
    renderer::Image,
    scene::{
        self,
        generators::{self, ScatterDecals, ScatterLights, ScatterParticles},
        Camera, Scene,
    },
    settings::{DecalMethod, LightMethod, RenderConfig},
};

const SIZE: (u32, u32) = (96, 54);
/// Scattered lights and decals: enough that a loop over all of them is the slow choice.
const VOLUMES: usize = 2000;

fn assets() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets")
}

/// The defaults, small: only the size and the texture budget differ from `RenderConfig::default()`.
fn defaults() -> RenderConfig {
    RenderConfig { width: SIZE.0, height: SIZE.1, max_texture_size: 256, anisotropy: 1, ..RenderConfig::default() }
}

fn camera(scene: &Scene) -> Camera {
    scene.cameras.first().cloned().unwrap_or_else(|| Camera::framing(&scene.bounds()))
}

/// The sRGB-encoded image's mean luma, and the fractions of its pixels clipped to white and black.
fn exposure_of(image: &Image<[u8; 4]>) -> (f32, f32, f32) {
    let n = image.pixels.len() as f32;
    let luma = |p: &[u8; 4]| (0.2126 * f32::from(p[0]) + 0.7152 * f32::from(p[1]) + 0.0722 * f32::from(p[2])) / 255.0;
    let mean = image.pixels.iter().map(luma).sum::<f32>() / n;
    let clipped = image.pixels.iter().filter(|p| p[..3].iter().all(|&c| c >= 254)).count() as f32 / n;
    let black = image.pixels.iter().filter(|p| p[..3].iter().all(|&c| c <= 2)).count() as f32 / n;
    (mean, clipped, black)
}

#[test]
fn every_shared_scene_renders_exposed_with_no_flags_and_auto_matches_brute_force() {
    let files = [
        "box/Box.gltf",
        "box_textured/BoxTextured.glb",
        "duck/Duck.glb",
        "damaged_helmet/DamagedHelmet.glb",
        "gas_station/GasStation.gltf",
        "sponza/Sponza.gltf",
    ];
    for file in files {
        let base = scene::load_path(&assets().join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        let mut lights = base.clone();
        generators::add_scattered_lights(&mut lights, &ScatterLights { count: VOLUMES, ..Default::default() }).unwrap();
        let mut decals = base.clone();
        generators::add_scattered_decals(&mut decals, &ScatterDecals { count: VOLUMES, ..Default::default() }).unwrap();
        let mut particles = base.clone();
        generators::add_particles(&mut particles, &ScatterParticles::new(4096, 1, 16)).unwrap();
        for (variant, scene) in [("alone", &base), ("lights", &lights), ("decals", &decals), ("particles", &particles)] {
            let camera = camera(scene);
            let mut r = renderer(scene, defaults());
            r.render(&camera).expect("frame");
            let (mean, clipped, black) = exposure_of(&r.read_ldr().expect("ldr"));
            let what = format!("{file} {variant}");
            assert!((0.12..=0.75).contains(&mean), "{what}: mean luma {mean:.3} is badly exposed");
            assert!(clipped <= 0.05, "{what}: {:.1} % of the pixels clipped to white", clipped * 100.0);
            assert!(black <= 0.35, "{what}: {:.1} % of the pixels black", black * 100.0);
            let chosen = r.methods_chosen();
            if scene.lights.len() > BRUTE_FORCE_MAX {
                assert_ne!(chosen.lights.method, LightMethod::Brute, "{what}: {}", chosen.lights);
            }
            if scene.decals.len() > BRUTE_FORCE_MAX {
                assert_ne!(chosen.decals.method, DecalMethod::Brute, "{what}: {}", chosen.decals);
            }
            if variant == "lights" || variant == "decals" {
                let auto = r.read_hdr().expect("hdr");
                let brute = RenderConfig { light_method: LightMethod::Brute, decal_method: DecalMethod::Brute, ..defaults() };
                let mut reference = renderer(scene, brute);
                reference.render(&camera).expect("frame");
                let reference = reference.read_hdr().expect("hdr");
                let peak = reference.pixels.iter().map(|&p| luminance(p)).fold(0.0, f32::max).max(1.0);
                let difference = max_abs_difference(&auto, &reference);
                assert!(difference <= 1e-3 * peak, "{what}: auto ({chosen:?}) differs from brute force by {difference} (peak {peak})");
            }
        }
    }
}
