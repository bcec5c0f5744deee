//! The environment (`scene::sky`, `scene::environment`, `shading/environment.wgsl`): a scene with no
//! lights of its own is lit by the daylight sky and its sun, seen in the background, and one with a
//! sun alone by the sky of that sun, in its units; `Sky::Off` leaves
//! it dark; an HDR image lights it instead; the sky's sun casts traced shadows; traced reflections
//! of the sky replace the prefiltered environment rather than adding to it.

mod common;

use std::path::PathBuf;

use common::*;
use glam::{Mat4, Quat, Vec3, Vec4};
use manylights::{
    files::LoadBudget,
    renderer::Image,
    scene::{self, sky::light_with_sky, Camera, Environment, Instance, Material, Scene, Sun},
    settings::{LightMethod, RaySettings, RenderConfig, Sky, SunShadows},
};

/// The glTF box (a red unit cube at the origin, no lights) on a white floor 20 m square.
fn box_on_floor() -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets/box/Box.glb");
    let mut scene = scene::load_path(&path).unwrap();
    let floor = Material { base_color_factor: Vec4::ONE, metallic_factor: 0.0, roughness_factor: 1.0, ..Default::default() };
    let mut floor_mesh = quad_mesh();
    floor_mesh.primitives[0].material = scene.materials.len();
    scene.materials.push(floor);
    scene.meshes.push(floor_mesh);
    let face_up = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    let world_from_local = Mat4::from_scale_rotation_translation(Vec3::new(10.0, 10.0, 1.0), face_up, Vec3::new(0.0, -0.5, 0.0));
    scene.instances.push(Instance { mesh: scene.meshes.len() - 1, world_from_local });
    scene
}

fn mean_luminance(image: &Image<[f32; 4]>) -> f32 {
    image.pixels.iter().map(|p| luminance(*p)).sum::<f32>() / image.pixels.len() as f32
}

fn render_sky(scene: &Scene, camera: &Camera, rays: RaySettings) -> Image<[f32; 4]> {
    render_with(scene, camera, RenderConfig { rays, ..config(WIDTH, HEIGHT, LightMethod::Brute) }).1
}

/// The default sky's sun, as `settings::environment` places it.
fn towards_sun() -> Vec3 {
    let mut scene = box_on_floor();
    light_with_sky(&mut scene, Sky::Auto);
    -scene.sun.expect("the sky's sun").direction
}

#[test]
fn a_scene_without_lights_is_lit_by_the_sky_by_default_and_dark_without_it() {
    let camera = Camera::look_at("box", Vec3::new(2.5, 1.5, 2.5), Vec3::new(0.0, 0.2, 0.0), 50f32.to_radians(), 0.05);
    let mut lit = box_on_floor();
    assert_eq!(lit.authored_lights, 0);
    light_with_sky(&mut lit, Sky::Auto);
    assert!(lit.environment.is_some() && lit.sun.is_some());
    let (ldr, hdr) = render_with(&lit, &camera, config(WIDTH, HEIGHT, LightMethod::Brute));
    let ldr_mean = ldr.pixels.iter().map(|p| luminance(p.map(|c| c as f32 / 255.0))).sum::<f32>() / ldr.pixels.len() as f32;
    assert!((0.2..0.8).contains(&ldr_mean), "the sky-lit image's mean is {ldr_mean} of white");

    let mut dark = box_on_floor();
    light_with_sky(&mut dark, Sky::Off);
    assert!(dark.environment.is_none() && dark.sun.is_none());
    let dark_hdr = render_with(&dark, &camera, config(WIDTH, HEIGHT, LightMethod::Brute)).1;
    let (lit_mean, dark_mean) = (mean_luminance(&hdr), mean_luminance(&dark_hdr));
    assert!(dark_mean < 0.04 && lit_mean > 10.0 * dark_mean, "sky {lit_mean}, off {dark_mean}");
}

/// A sun alone, as glTF files exported with one have, gets the sky that sun implies in its units: a
/// sun 1,024 times the project's (in lux, say) lights the scene and fills the background 1,024 times
/// brighter, so the auto-exposed image is the same.
#[test]
fn a_scene_with_only_a_sun_gets_the_sky_it_implies_in_its_units() {
    let camera = Camera::look_at("box", Vec3::new(2.5, 1.5, 2.5), Vec3::new(0.0, 0.2, 0.0), 50f32.to_radians(), 0.05);
    let render = |illuminance| {
        let mut scene = box_on_floor();
        // Behind the camera: its disc, far brighter than half floats hold at 1,024 times, out of view.
        let direction = Vec3::new(-0.5, -0.7, -0.5).normalize();
        scene.sun = Some(Sun { direction, color: Vec3::new(1.0, 0.9, 0.8), illuminance });
        light_with_sky(&mut scene, Sky::Auto);
        assert!(scene.environment.is_some(), "the sky");
        render_with(&scene, &camera, config(WIDTH, HEIGHT, LightMethod::Brute)).1
    };
    let (project, lux) = (render(2.0), render(2048.0));
    let sky = pixel(&project, WIDTH / 2, 2);
    assert!(sky[2] > sky[0] && sky[2] > 0.01, "a blue sky at the top: {sky:?}");
    for (a, b) in project.pixels.iter().zip(&lux.pixels) {
        for c in 0..3 {
            assert!((b[c] - 1024.0 * a[c]).abs() <= 4e-3 * b[c] + 1e-3, "{a:?} × 1024 against {b:?}");
        }
    }
}

#[test]
fn the_background_is_a_blue_sky_brighter_towards_the_sun_with_its_disc() {
    let mut scene = box_on_floor();
    light_with_sky(&mut scene, Sky::Auto);
    let to_sun = towards_sun();
    let eye = Vec3::new(0.0, 1.0, 8.0);
    let look = |dir: Vec3| Camera::look_at("sky", eye, eye + dir, 60f32.to_radians(), 0.05);
    let towards = render_sky(&scene, &look(to_sun), RaySettings::default());
    let away = render_sky(&scene, &look(Vec3::new(-to_sun.x, to_sun.y, -to_sun.z)), RaySettings::default());
    // Both views look 10° and more above the horizon: only sky.
    let (towards_mean, away_mean) = (mean_luminance(&towards), mean_luminance(&away));
    assert!(towards_mean > 2.0 * away_mean, "towards the sun {towards_mean}, away {away_mean}");
    // The sun's disc, half a degree wide: a narrow view puts pixels inside it.
    let telephoto = Camera::look_at("sun", eye, eye + to_sun, 5f32.to_radians(), 0.05);
    let sun = render_sky(&scene, &telephoto, RaySettings::default());
    let brightest = sun.pixels.iter().map(|p| luminance(*p)).fold(0.0, f32::max);
    assert!(brightest > 1000.0, "the sun's disc: {brightest}");
    let top = pixel(&away, WIDTH / 2, 0);
    assert!(top[2] > top[1] && top[1] > top[0], "the sky away from the sun is blue: {top:?}");
}

#[test]
fn an_environment_image_lights_the_scene_and_fills_the_background() {
    let dir = std::env::temp_dir().join(format!("manylights_environment_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Red above the horizon, dim blue below.
    let path = dir.join("red_sky.hdr");
    let pixels: Vec<image::Rgb<f32>> =
        (0..128).map(|i| if i < 64 { image::Rgb([2.0, 0.0, 0.0]) } else { image::Rgb([0.0, 0.0, 0.2]) }).collect();
    image::codecs::hdr::HdrEncoder::new(std::fs::File::create(&path).unwrap()).encode(&pixels, 16, 8).unwrap();
    let mut scene = box_on_floor();
    scene.environment = Some(Environment::load(&path, &LoadBudget::new()).unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
    light_with_sky(&mut scene, Sky::Auto);
    assert!(scene.sun.is_none(), "an environment image brings no sun");

    let camera = Camera::look_at("floor", Vec3::new(0.0, 3.0, 6.0), Vec3::new(0.0, 1.0, 0.0), 60f32.to_radians(), 0.05);
    let image = render_sky(&scene, &camera, RaySettings::default());
    let sky = pixel(&image, WIDTH / 2, 2);
    assert!((sky[0] - 2.0).abs() < 0.05 && sky[2] < 0.01, "the background shows the image: {sky:?}");
    // The white floor in front of the box, lit from above by the red half: irradiance / π = 2.
    let floor = pixel(&image, WIDTH / 2, HEIGHT - 4);
    assert!((floor[0] - 2.0).abs() < 0.15 && floor[2] < 0.1, "the floor is lit red: {floor:?}");
}

#[test]
fn the_skys_sun_casts_traced_shadows() {
    let mut scene = box_on_floor();
    // The box floats a metre over the floor, so its shadow lies beside it.
    scene.instances[0].world_from_local = Mat4::from_translation(Vec3::new(0.0, 1.0, 0.0)) * scene.instances[0].world_from_local;
    light_with_sky(&mut scene, Sky::Auto);
    let camera = Camera::look_at("above", Vec3::new(0.0, 9.0, 0.5), Vec3::ZERO, 60f32.to_radians(), 0.05);
    let unshadowed = render_sky(&scene, &camera, RaySettings::default());
    let shadowed = render_sky(&scene, &camera, RaySettings { sun_shadows: SunShadows::Hard, ..RaySettings::default() });
    let darkened = unshadowed.pixels.iter().zip(&shadowed.pixels).filter(|(u, s)| luminance(**s) < 0.5 * luminance(**u)).count();
    let fraction = darkened as f32 / unshadowed.pixels.len() as f32;
    assert!((0.005..0.1).contains(&fraction), "{fraction} of the image in the box's shadow");
}

#[test]
fn traced_reflections_of_the_sky_replace_its_prefiltered_reflection() {
    // A glossy metal floor seen with the sun behind the camera: it reflects only the sky, which the
    // prefiltered environment and the traced rays both show.
    let metal = Material { base_color_factor: Vec4::ONE, metallic_factor: 1.0, roughness_factor: 0.1, ..Default::default() };
    let face_up = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    let mut scene = Scene {
        meshes: vec![quad_mesh()],
        materials: vec![metal],
        instances: vec![Instance {
            mesh: 0,
            world_from_local: Mat4::from_scale_rotation_translation(Vec3::splat(50.0), face_up, Vec3::ZERO),
        }],
        ..Default::default()
    };
    light_with_sky(&mut scene, Sky::Auto);
    let to_sun = towards_sun();
    let eye = Vec3::new(0.0, 2.0, 0.0);
    let camera = Camera::look_at("floor", eye, eye + Vec3::new(-to_sun.x, -0.6, -to_sun.z), 50f32.to_radians(), 0.05);
    let prefiltered = render_sky(&scene, &camera, RaySettings::default());
    let traced = render_sky(&scene, &camera, RaySettings { reflection_bounces: 1, ..RaySettings::default() });
    let (prefiltered_mean, traced_mean) = (mean_luminance(&prefiltered), mean_luminance(&traced));
    assert!(prefiltered_mean > 0.05, "the floor reflects the sky: {prefiltered_mean}");
    assert!((traced_mean / prefiltered_mean - 1.0).abs() < 0.1, "traced {traced_mean}, prefiltered {prefiltered_mean}");
}
