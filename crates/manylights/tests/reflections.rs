//! Ray-traced reflections (`shading/reflections.wgsl`): a mirror floor shows a panel outside the view,
//! with the decal, the light and the particle light that reach the panel — through the acceleration structures (and brute
//! force) in every pipeline, exactly as the panel's own shading predicts — and shows that clustered
//! shading cannot light or decal such hit points: its lists cover the view frustum only.

mod common;

use common::*;
use glam::{Affine3A, Mat4, Quat, Vec3, Vec4};
use manylights::{
    renderer::Image,
    scene::ibl::BRDF_TABLE_SIZE,
    scene::ParticleSettings,
    scene::{Camera, Decal, Instance, Light, Material, Scene},
    settings::RaySettings,
    settings::RenderConfig,
    settings::{DecalMethod, LightMethod, ParticleMethod, PipelineKind},
};

const WIDTH: u32 = 96;
const HEIGHT: u32 = 54;
const AMBIENT: f32 = 0.2;
/// The panel: a quad facing +Z at z = PANEL_Z, x in [-4, 4], y in [3, 11] — above the view.
const PANEL_Z: f32 = -6.0;
/// The red decal's box on the panel: x in [-2, 2], y in [5, 9].
const DECAL_CENTRE: Vec3 = Vec3::new(0.0, 7.0, PANEL_Z);

/// A mirror floor (metallic, roughness 0, white: it reflects all it sees), the panel (white, fully
/// rough) and the camera looking down at the floor, which hides the panel from it. Ambient light only,
/// plus `lights` and `decals`.
fn mirror_scene(lights: Vec<Light>, decals: Vec<Decal>) -> (Scene, Camera) {
    let mirror = Material { base_color_factor: Vec4::ONE, metallic_factor: 1.0, roughness_factor: 0.0, ..Default::default() };
    let panel = Material { base_color_factor: Vec4::ONE, metallic_factor: 0.0, roughness_factor: 1.0, ..Default::default() };
    let red =
        Material { base_color_factor: Vec4::new(1.0, 0.0, 0.0, 1.0), metallic_factor: 0.0, roughness_factor: 1.0, ..Default::default() };
    let mut panel_mesh = quad_mesh();
    panel_mesh.primitives[0].material = 1;
    let scene = Scene {
        meshes: vec![quad_mesh(), panel_mesh],
        materials: vec![mirror, panel, red],
        instances: vec![
            Instance {
                mesh: 0,
                world_from_local: Mat4::from_scale_rotation_translation(
                    Vec3::new(10.0, 10.0, 1.0),
                    Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
                    Vec3::ZERO,
                ),
            },
            Instance {
                mesh: 1,
                world_from_local: Mat4::from_scale_rotation_translation(
                    Vec3::new(4.0, 4.0, 1.0),
                    Quat::IDENTITY,
                    Vec3::new(0.0, 7.0, PANEL_Z),
                ),
            },
        ],
        lights,
        decals,
        ambient: Vec3::splat(AMBIENT),
        ..Default::default()
    };
    (scene, Camera::look_at("down", Vec3::new(0.0, 2.0, 4.0), Vec3::ZERO, 40f32.to_radians(), 0.1))
}

fn red_decal() -> Decal {
    Decal {
        world_from_decal: Affine3A::from_scale_rotation_translation(Vec3::new(4.0, 4.0, 1.0), Quat::IDENTITY, DECAL_CENTRE),
        material: 2,
        layer: 0,
        weight: 1.0,
    }
}

/// Where the mirror sends a pixel's camera ray: the floor point it reflects at and the point of the
/// panel's plane it reaches, if any.
fn reflected_panel_point(camera: &Camera, x: f32, y: f32) -> Option<(Vec3, Vec3)> {
    let aspect = WIDTH as f32 / HEIGHT as f32;
    let tan_half = (20f32.to_radians()).tan();
    let view = Vec3::new((x / WIDTH as f32 * 2.0 - 1.0) * tan_half * aspect, (1.0 - y / HEIGHT as f32 * 2.0) * tan_half, -1.0);
    let dir = camera.world_from_view.transform_vector3(view).normalize();
    let eye = camera.position();
    let floor = eye + dir * (-eye.y / dir.y);
    let mirrored = Vec3::new(dir.x, -dir.y, dir.z);
    (mirrored.z < 0.0).then(|| (floor, floor + mirrored * ((PANEL_Z - floor.z) / mirrored.z)))
}

/// The share of a uniform environment the panel (a fully rough dielectric) reflects specularly where
/// the mirror shows it at pixel (x, y): F0 × scale + bias from the split-sum table at the panel's n·v,
/// filtered as `shading/environment.wgsl` reads it.
fn panel_specular_albedo(camera: &Camera, x: u32, y: u32) -> f32 {
    let (floor, panel) = reflected_panel_point(camera, x as f32 + 0.5, y as f32 + 0.5).expect("the panel");
    let n_dot_v = (floor - panel).normalize().z;
    let (table, size) = (manylights::scene::ibl::brdf_table(), BRDF_TABLE_SIZE as usize);
    let column = n_dot_v.clamp(0.5 / size as f32, 1.0 - 0.5 / size as f32) * size as f32 - 0.5;
    let at = |i: usize| {
        let [scale, bias] = table[(size - 1) * size + i.min(size - 1)];
        0.04 * scale + bias
    };
    let (i, t) = (column.floor() as usize, column.fract());
    at(i) * (1.0 - t) + at(i + 1) * t
}

/// What the mirror shows at a pixel, if every corner of the pixel agrees.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Reflected {
    Decal,
    BarePanel,
    Elsewhere,
}

fn reflected(camera: &Camera, x: u32, y: u32) -> Option<Reflected> {
    let classify = |fx: f32, fy: f32| match reflected_panel_point(camera, fx, fy) {
        Some((_, q)) if (q.x.abs() <= 2.0) && (q.y - DECAL_CENTRE.y).abs() <= 2.0 => Reflected::Decal,
        Some((_, q)) if q.x.abs() <= 4.0 && (3.0..=11.0).contains(&q.y) => Reflected::BarePanel,
        _ => Reflected::Elsewhere,
    };
    let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)].map(|(dx, dy)| classify(x as f32 + dx, y as f32 + dy));
    corners.iter().all(|c| *c == corners[0]).then_some(corners[0])
}

fn render(scene: &Scene, camera: &Camera, pipeline: PipelineKind, lights: LightMethod, decals: DecalMethod) -> Image<[f32; 4]> {
    let rays = RaySettings { reflection_bounces: 1, ..Default::default() };
    render_with(scene, camera, RenderConfig { pipeline, decal_method: decals, rays, ..config(WIDTH, HEIGHT, lights) }).1
}

fn rgb(p: [f32; 4]) -> Vec3 {
    Vec3::new(p[0], p[1], p[2])
}

#[test]
fn a_mirror_shows_a_decal_outside_the_view_as_the_decal_colours_its_surface() {
    let (scene, camera) = mirror_scene(Vec::new(), vec![red_decal()]);
    // The mirror reflects all of the panel's radiance, which replaces its reflection of the uniform
    // environment; the panel's is its albedo plus its specular share, times the environment's radiance.
    let panel = |albedo: Vec3, x, y| (albedo + Vec3::splat(panel_specular_albedo(&camera, x, y))) * AMBIENT;
    for pipeline in PipelineKind::ALL {
        let name = pipeline.name();
        let bvh = render(&scene, &camera, pipeline, LightMethod::Off, DecalMethod::Bvh);
        let brute = render(&scene, &camera, pipeline, LightMethod::Off, DecalMethod::Brute);
        assert!(max_abs_difference(&bvh, &brute) < 1e-3, "{name}: bvh and brute-force decals differ in the reflection");
        let clustered = render(&scene, &camera, pipeline, LightMethod::Off, DecalMethod::Clustered);
        let (mut decal_pixels, mut bare_pixels) = (0, 0);
        for y in 0..HEIGHT {
            for x in 0..WIDTH {
                let (expect_decal, expect_bare) = (panel(Vec3::X, x, y), panel(Vec3::ONE, x, y));
                let (expected, clustered_expected) = match reflected(&camera, x, y) {
                    Some(Reflected::Decal) => {
                        decal_pixels += 1;
                        // The clustered lists hold no decal out there: the panel shows bare.
                        (expect_decal, expect_bare)
                    }
                    Some(Reflected::BarePanel) => {
                        bare_pixels += 1;
                        (expect_bare, expect_bare)
                    }
                    _ => continue,
                };
                let got = rgb(pixel(&bvh, x, y));
                assert!((got - expected).abs().max_element() < 1e-3, "{name}: pixel ({x}, {y}) reflects {got}, expected {expected}");
                let got = rgb(pixel(&clustered, x, y));
                assert!(
                    (got - clustered_expected).abs().max_element() < 1e-3,
                    "{name}: clustered pixel ({x}, {y}) reflects {got}, expected {clustered_expected}"
                );
            }
        }
        assert!(decal_pixels > 100 && bare_pixels > 100, "{name}: {decal_pixels} decal and {bare_pixels} bare panel pixels reflected");
    }
}

#[test]
fn a_mirror_shows_the_light_of_a_lamp_outside_the_view_which_clustered_lists_miss() {
    // Its whole range lies above the view, as the panel does.
    let lamp = point_light(Vec3::new(0.0, 8.0, PANEL_Z + 1.0), 10.0, 3.5);
    let (lit, camera) = mirror_scene(vec![lamp], Vec::new());
    let (dark, _) = mirror_scene(Vec::new(), Vec::new());
    let pipeline = PipelineKind::Visbuffer;
    let bvh = render(&lit, &camera, pipeline, LightMethod::Bvh, DecalMethod::Off);
    let brute = render(&lit, &camera, pipeline, LightMethod::Brute, DecalMethod::Off);
    let clustered = render(&lit, &camera, pipeline, LightMethod::Clustered, DecalMethod::Off);
    let unlit = render(&dark, &camera, pipeline, LightMethod::Off, DecalMethod::Off);
    assert!(max_abs_difference(&bvh, &brute) < 1e-3, "bvh and brute-force lights differ in the reflection");
    let mut lamp_lit = 0;
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            if reflected(&camera, x, y).is_none_or(|r| r == Reflected::Elsewhere) {
                continue;
            }
            let (through_bvh, without) = (rgb(pixel(&bvh, x, y)), rgb(pixel(&unlit, x, y)));
            if (through_bvh - without).min_element() > 0.05 {
                lamp_lit += 1;
            }
            // Clustered shading reflects the panel as if the lamp were not there.
            let through_clusters = rgb(pixel(&clustered, x, y));
            assert!(
                (through_clusters - without).abs().max_element() < 1e-3,
                "pixel ({x}, {y}): clustered {through_clusters}, unlit {without}"
            );
        }
    }
    assert!(lamp_lit > 100, "only {lamp_lit} reflected panel pixels show the lamp's light");
}

/// One particle light that stays where it is launched, 1 m in front of the panel (above the view).
fn particle_by_the_panel() -> ParticleSettings {
    ParticleSettings {
        count: 1,
        seed: 3,
        emitters: vec![(Vec3::new(0.5, 7.0, PANEL_Z + 1.0), 0.0)],
        gravity: 0.0,
        swirl: 0.0,
        radius: (3.0, 3.0),
        intensity: 2.0,
        ..ParticleSettings::default()
    }
}

/// A crowd of particle lights reflected exactly: reflection rays' hit points are shaded inside per-lane
/// control flow (lanes whose rays miss have left), where the subgroup walk shares each leaf's lights
/// out among the lanes still bouncing; the mirror shows the crowd as their point lights through
/// brute force show it, in every pipeline.
#[test]
fn a_mirror_shows_a_crowd_of_particle_lights_as_their_point_lights() {
    let settings = ParticleSettings {
        count: 2000,
        seed: 11,
        emitters: vec![(Vec3::new(0.5, 7.0, PANEL_Z + 1.0), 1.5)],
        radius: (0.5, 1.5),
        intensity: 0.05,
        ..ParticleSettings::default()
    };
    let lights: Vec<Light> = (0..settings.count)
        .map(|i| {
            let p = settings.particle_at(i, 0.0);
            Light { color: p.color, intensity: 1.0, ..point_light(p.position, 1.0, p.radius) }
        })
        .collect();
    let (mut scene, camera) = mirror_scene(Vec::new(), Vec::new());
    scene.particles = Some(settings);
    let (lamp_scene, _) = mirror_scene(lights, Vec::new());
    let (unlit_scene, _) = mirror_scene(Vec::new(), Vec::new());
    for pipeline in PipelineKind::ALL {
        let reflect = |scene: &Scene, lights, particles| {
            let rays = RaySettings { reflection_bounces: 1, ..Default::default() };
            let config = RenderConfig {
                decal_method: DecalMethod::Off,
                particle_method: particles,
                pipeline,
                rays,
                ..config(WIDTH, HEIGHT, lights)
            };
            render_with(scene, &camera, config).1
        };
        let exact = reflect(&scene, LightMethod::Bvh, ParticleMethod::Bvh);
        let lamps = reflect(&lamp_scene, LightMethod::Brute, ParticleMethod::Off);
        let unlit = reflect(&unlit_scene, LightMethod::Off, ParticleMethod::Off);
        let mut reflected_light = 0.0;
        for y in 0..HEIGHT {
            for x in 0..WIDTH {
                if reflected(&camera, x, y).is_some_and(|r| r != Reflected::Elsewhere) {
                    reflected_light += luminance(pixel(&lamps, x, y)) - luminance(pixel(&unlit, x, y));
                }
            }
        }
        assert!(reflected_light > 1.0, "{}: the crowd barely lights the reflected panel: {reflected_light}", pipeline.name());
        let difference = max_abs_difference(&exact, &lamps);
        assert!(difference < 1e-3, "{}: the exact crowd differs from its point lights by {difference}", pipeline.name());
    }
}

/// Particle lights reach reflections' hit points too: exactly, as point lights in the lights' BVH
/// (equal to the same point light), and through the 3D-texture grid, close to it.
#[test]
fn a_mirror_shows_particle_lights_outside_the_view() {
    let settings = particle_by_the_panel();
    let particle = settings.particle_at(0, 0.0);
    let as_light = Light { color: particle.color, intensity: 1.0, ..point_light(particle.position, 1.0, particle.radius) };
    let (mut scene, camera) = mirror_scene(Vec::new(), Vec::new());
    scene.particles = Some(settings);
    let (lamp_scene, _) = mirror_scene(vec![as_light], Vec::new());
    let (unlit_scene, _) = mirror_scene(Vec::new(), Vec::new());
    let reflect = |scene: &Scene, lights, particles, voxel| {
        let rays = RaySettings { reflection_bounces: 1, ..Default::default() };
        let config = RenderConfig {
            decal_method: DecalMethod::Off,
            particle_method: particles,
            particle_voxel_size: voxel,
            rays,
            ..config(WIDTH, HEIGHT, lights)
        };
        render_with(scene, &camera, config).1
    };
    let exact = reflect(&scene, LightMethod::Bvh, ParticleMethod::Bvh, 1.0);
    let lamp = reflect(&lamp_scene, LightMethod::Brute, ParticleMethod::Off, 1.0);
    let grid = reflect(&scene, LightMethod::Off, ParticleMethod::Grid, 0.25);
    let unlit = reflect(&unlit_scene, LightMethod::Off, ParticleMethod::Off, 1.0);
    assert!(max_abs_difference(&exact, &lamp) < 1e-3, "the exact particle differs from its point light in the reflection");
    // Over the reflected panel, the grid's light (0.25 m voxels) is the point light's within 10 %.
    let (mut exact_light, mut grid_light) = (0.0, 0.0);
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            if reflected(&camera, x, y).is_some_and(|r| r != Reflected::Elsewhere) {
                exact_light += luminance(pixel(&lamp, x, y)) - luminance(pixel(&unlit, x, y));
                grid_light += luminance(pixel(&grid, x, y)) - luminance(pixel(&unlit, x, y));
            }
        }
    }
    assert!(exact_light > 1.0, "the particle's light barely reaches the reflected panel: {exact_light}");
    let ratio = grid_light / exact_light;
    assert!((ratio - 1.0).abs() < 0.1, "the grid reflects {ratio} times the particle's exact light");
}
