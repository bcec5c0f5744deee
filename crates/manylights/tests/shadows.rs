//! Ray-traced sun shadows (`passes/ray_shadows.rs`, `shading/sun_shadow*.wgsl`): a box floating over a
//! floor casts exactly the shadow a CPU ray test predicts, in every pipeline, on opaque surfaces (the
//! traced mask) and on a transparent pane (its own rays); soft shadows follow the fraction of the
//! sun's disc each point sees.

mod common;

use common::*;
use glam::{Mat4, Quat, Vec3, Vec4};
use manylights::{
    renderer::Image,
    scene::{AlphaMode, Camera, Instance, Material, Mesh, Primitive, Projection, Scene, Sun, Vertex},
    settings::RenderConfig,
    settings::{LightMethod, PipelineKind},
    settings::{RaySettings, SunShadows},
};

const WIDTH: u32 = 128;
const HEIGHT: u32 = 72;
/// Half the height of the orthographic view, in metres.
const VIEW_HALF_HEIGHT: f32 = 6.0;
/// The box: [-2, 2] × [2, 4] × [-2, 2]. Its shadow falls on x in [-0.2, 5.6], z in [-1.4, 3.2].
const BOX_MIN: Vec3 = Vec3::new(-2.0, 2.0, -2.0);
const BOX_MAX: Vec3 = Vec3::new(2.0, 4.0, 2.0);
/// The transparent pane: 3 m square at this height, centred at (PANE_X, ·, 0), partly in the shadow.
const PANE_HEIGHT: f32 = 0.5;
const PANE_X: f32 = 5.0;

fn sun_direction() -> Vec3 {
    Vec3::new(0.9, -1.0, 0.3).normalize()
}

/// The cube [-1, 1]³ with outward faces.
fn cube_mesh() -> Mesh {
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = [0.0; 3];
            n[axis] = sign;
            let n = Vec3::from(n);
            let (mut u, mut v) = ([0.0; 3], [0.0; 3]);
            u[(axis + 1) % 3] = 1.0;
            v[(axis + 2) % 3] = 1.0;
            let (u, v) = (Vec3::from(u), Vec3::from(v));
            // Counter-clockwise seen from outside: u × v points along +axis, so flip for -axis.
            let (u, v) = if sign > 0.0 { (u, v) } else { (v, u) };
            let base = vertices.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let p = n + u * a + v * b;
                vertices.push(Vertex {
                    position: p.to_array(),
                    normal: n.to_array(),
                    tangent: u.extend(1.0).to_array(),
                    ..Default::default()
                });
            }
            indices.extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    Mesh { name: "cube".into(), primitives: vec![Primitive { vertices, indices, material: 0 }] }
}

/// A white floor (y = 0, 20 m square), the box floating over it, and a blended pane beside it,
/// under a sun; seen from straight above by an orthographic camera.
fn shadow_scene(sun_illuminance: f32) -> (Scene, Camera) {
    let white = Material { base_color_factor: Vec4::ONE, metallic_factor: 0.0, roughness_factor: 1.0, ..Default::default() };
    let glass = Material { base_color_factor: Vec4::new(0.2, 0.4, 1.0, 0.5), alpha_mode: AlphaMode::Blend, ..white.clone() };
    let mut pane = quad_mesh();
    pane.primitives[0].material = 1;
    let face_up = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    let scene = Scene {
        meshes: vec![quad_mesh(), cube_mesh(), pane],
        materials: vec![white, glass],
        instances: vec![
            Instance { mesh: 0, world_from_local: Mat4::from_scale_rotation_translation(Vec3::new(10.0, 10.0, 1.0), face_up, Vec3::ZERO) },
            Instance {
                mesh: 1,
                world_from_local: Mat4::from_scale_rotation_translation(
                    (BOX_MAX - BOX_MIN) * 0.5,
                    Quat::IDENTITY,
                    (BOX_MIN + BOX_MAX) * 0.5,
                ),
            },
            Instance {
                mesh: 2,
                world_from_local: Mat4::from_scale_rotation_translation(
                    Vec3::new(1.5, 1.5, 1.0),
                    face_up,
                    Vec3::new(PANE_X, PANE_HEIGHT, 0.0),
                ),
            },
        ],
        sun: Some(Sun { direction: sun_direction(), color: Vec3::ONE, illuminance: sun_illuminance }),
        ambient: Vec3::splat(0.05),
        ..Default::default()
    };
    let camera = Camera {
        name: "above".into(),
        world_from_view: Mat4::look_at_rh(Vec3::new(0.0, 10.0, 0.0), Vec3::ZERO, Vec3::NEG_Z).inverse(),
        projection: Projection::Orthographic { xmag: VIEW_HALF_HEIGHT, ymag: VIEW_HALF_HEIGHT, znear: 0.1, zfar: 20.0 },
    };
    (scene, camera)
}

/// The floor point under pixel coordinates (x, y) (continuous, y down).
fn floor_point(x: f32, y: f32) -> Vec3 {
    let aspect = WIDTH as f32 / HEIGHT as f32;
    Vec3::new((x / WIDTH as f32 * 2.0 - 1.0) * VIEW_HALF_HEIGHT * aspect, 0.0, (y / HEIGHT as f32 * 2.0 - 1.0) * VIEW_HALF_HEIGHT)
}

/// Whether the segment from `p` towards the sun along `to_sun` meets the box (slab test).
fn box_blocks(p: Vec3, to_sun: Vec3) -> bool {
    box_moved_blocks(p, to_sun, Vec3::ZERO)
}

/// As [`box_blocks`], with the box moved by `offset`.
fn box_moved_blocks(p: Vec3, to_sun: Vec3, offset: Vec3) -> bool {
    let inverse = to_sun.recip();
    let (t0, t1) = ((BOX_MIN + offset - p) * inverse, (BOX_MAX + offset - p) * inverse);
    let (near, far) = (t0.min(t1).max_element(), t0.max(t1).min_element());
    near.max(0.0) <= far
}

/// What a pixel shows, if it can be told without rounding: the box's top, or the floor (under the
/// pane or not), lit or shadowed, or — under the pane — a floor and a pane of which only one is
/// shadowed. Pixels whose corners disagree lie on an edge and are left out.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Seen {
    BoxTop,
    Surface { shadowed: bool },
    Mixed,
    Sky,
}

/// With the box moved by `offset` (its shadow moves along; the pane stays).
fn seen_with_box_at(x: u32, y: u32, offset: Vec3) -> Option<Seen> {
    let box_blocks = |p: Vec3, to_sun: Vec3| box_moved_blocks(p, to_sun, offset);
    let classify = |fx: f32, fy: f32| {
        let p = floor_point(fx, fy);
        if (p.x - offset.x).abs() <= BOX_MAX.x && (p.z - offset.z).abs() <= BOX_MAX.z {
            return Seen::BoxTop;
        }
        if p.x.abs() > 10.0 {
            return Seen::Sky;
        }
        let under_pane = (p.x - PANE_X).abs() <= 1.5 && p.z.abs() <= 1.5;
        let floor = box_blocks(p, -sun_direction());
        // Under the pane both the floor and the pane must agree, as both are blended into the pixel.
        let pane = under_pane && box_blocks(p + Vec3::Y * PANE_HEIGHT, -sun_direction());
        if under_pane && floor != pane {
            return Seen::Mixed;
        }
        Seen::Surface { shadowed: floor }
    };
    let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)].map(|(dx, dy)| classify(x as f32 + dx, y as f32 + dy));
    corners.iter().all(|c| *c == corners[0]).then_some(corners[0])
}

/// The sun's angular diameter for soft shadows: penumbrae of 4 to 9 pixels here.
const SOFT_SUN_DEGREES: f32 = 16.0;

fn settings(pipeline: PipelineKind, shadows: SunShadows) -> RenderConfig {
    let rays = RaySettings { sun_shadows: shadows, sun_angle_degrees: SOFT_SUN_DEGREES, shadow_rays: 32, ..Default::default() };
    RenderConfig { pipeline, rays, ..config(WIDTH, HEIGHT, LightMethod::Off) }
}

fn render(scene: &Scene, camera: &Camera, pipeline: PipelineKind, shadows: SunShadows) -> Image<[f32; 4]> {
    render_with(scene, camera, settings(pipeline, shadows)).1
}

/// Checks a shadowed frame pixel by pixel against the same frame without shadows (`lit`) and
/// without the sun (`dark`), for the box moved by `offset`; returns the shadowed and sunlit pixels
/// checked.
fn check_shadow(shadowed: &Image<[f32; 4]>, lit: &Image<[f32; 4]>, dark: &Image<[f32; 4]>, offset: Vec3, what: &str) -> (u32, u32) {
    let (mut in_shadow, mut in_sun) = (0, 0);
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let Some(seen) = seen_with_box_at(x, y, offset).filter(|s| ![Seen::Mixed, Seen::Sky].contains(s)) else { continue };
            let expected = if seen == (Seen::Surface { shadowed: true }) {
                in_shadow += 1;
                pixel(dark, x, y)
            } else {
                in_sun += 1;
                pixel(lit, x, y)
            };
            let got = pixel(shadowed, x, y);
            let error = (0..3).map(|c| (got[c] - expected[c]).abs()).fold(0.0, f32::max);
            assert!(error <= 1e-5, "{what}: pixel ({x}, {y}) shows {seen:?}: {got:?}, expected {expected:?}");
        }
    }
    (in_shadow, in_sun)
}

#[test]
fn a_floating_box_shadows_exactly_the_floor_and_pane_points_whose_sun_ray_it_blocks() {
    let (scene, camera) = shadow_scene(3.0);
    let (sunless, _) = shadow_scene(0.0);
    for pipeline in PipelineKind::ALL {
        let name = pipeline.name();
        let lit = render(&scene, &camera, pipeline, SunShadows::Off);
        let dark = render(&sunless, &camera, pipeline, SunShadows::Off);
        let shadowed = render(&scene, &camera, pipeline, SunShadows::Hard);
        let (in_shadow, in_sun) = check_shadow(&shadowed, &lit, &dark, Vec3::ZERO, name);
        // The shadow falls in view, beside plenty of sunlit floor.
        assert!(in_shadow > 150 && in_sun > 3000, "{name}: {in_shadow} shadowed and {in_sun} sunlit pixels");
    }
}

/// The fraction of the sun's disc (angular radius `radius`) a floor point sees past the box, by
/// integrating over the disc on a fine polar grid.
fn visible_fraction(p: Vec3, radius: f32) -> f32 {
    let axis = -sun_direction();
    let u = axis.cross(Vec3::X).normalize();
    let v = axis.cross(u);
    let (rings, sectors) = (24, 48);
    let mut visible = 0.0;
    let mut total = 0.0;
    for ring in 0..rings {
        // Rings of equal solid angle, like the shader's samples.
        let cos_theta = 1.0 - (ring as f32 + 0.5) / rings as f32 * (1.0 - radius.cos());
        let sin_theta = (1.0 - cos_theta * cos_theta).sqrt();
        for sector in 0..sectors {
            let phi = (sector as f32 + 0.5) / sectors as f32 * std::f32::consts::TAU;
            let dir = axis * cos_theta + (u * phi.cos() + v * phi.sin()) * sin_theta;
            total += 1.0;
            if !box_blocks(p, dir) {
                visible += 1.0;
            }
        }
    }
    visible / total
}

#[test]
fn soft_shadows_follow_the_fraction_of_the_sun_each_point_sees() {
    let (scene, camera) = shadow_scene(3.0);
    let (sunless, _) = shadow_scene(0.0);
    let pipeline = PipelineKind::Visbuffer;
    let lit = render(&scene, &camera, pipeline, SunShadows::Off);
    let dark = render(&sunless, &camera, pipeline, SunShadows::Off);
    let soft = render(&scene, &camera, pipeline, SunShadows::Soft);
    let radius = (SOFT_SUN_DEGREES * 0.5).to_radians();
    // What a pixel should show: the fraction averaged over its area (4 × 4 points).
    let pixel_fraction = |x: f32, y: f32| {
        let points = (0..16).map(|k| floor_point(x + (k % 4) as f32 * 0.25 + 0.125, y + (k / 4) as f32 * 0.25 + 0.125));
        points.map(|p| visible_fraction(p, radius)).sum::<f32>() / 16.0
    };
    let (mut penumbra, mut error_sum, mut umbra, mut full_sun) = (0, 0.0, 0, 0);
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let p = floor_point(x as f32 + 0.5, y as f32 + 0.5);
            let near_pane = (p.x - PANE_X).abs() <= 2.0 && p.z.abs() <= 2.0;
            if (p.x.abs() <= BOX_MAX.x + 0.2 && p.z.abs() <= BOX_MAX.z + 0.2) || near_pane || p.x.abs() > 9.5 {
                continue;
            }
            let expected = pixel_fraction(x as f32, y as f32);
            let sun = luminance(pixel(&lit, x, y)) - luminance(pixel(&dark, x, y));
            let measured = (luminance(pixel(&soft, x, y)) - luminance(pixel(&dark, x, y))) / sun;
            // Points that see all or none of the sun, with every neighbour the filter reaches alike
            // (its 7×7 window, 3 pixels either way), keep that exactly.
            let window = (-3..=3).flat_map(|dy| (-3..=3).map(move |dx| (dx, dy)));
            let neighbours: Vec<f32> = window
                .map(|(dx, dy)| visible_fraction(floor_point(x as f32 + 0.5 + dx as f32, y as f32 + 0.5 + dy as f32), radius))
                .collect();
            if neighbours.iter().all(|&f| f == 0.0) {
                umbra += 1;
                assert!(measured.abs() < 1e-4, "umbra pixel ({x}, {y}) sees {measured} of the sun");
            } else if neighbours.iter().all(|&f| f == 1.0) {
                full_sun += 1;
                assert!((measured - 1.0).abs() < 1e-4, "sunlit pixel ({x}, {y}) sees {measured} of the sun");
            } else if expected > 0.0 && expected < 1.0 {
                penumbra += 1;
                error_sum += (measured - expected).abs();
            }
        }
    }
    let mean_error = error_sum / penumbra as f32;
    assert!(
        umbra > 20 && full_sun > 2000 && penumbra > 100,
        "{umbra} umbra, {full_sun} sunlit, {penumbra} penumbra pixels, error {mean_error}"
    );
    // 32 rays per pixel and the filter: the penumbra within 0.05 of the exact fraction on average.
    assert!(mean_error < 0.05, "penumbra pixels are off the sun's visible fraction by {mean_error} on average");
}

/// The box of [`shadow_scene`] flying along x at 60 m/s (one metre, six pixels, a frame), by a glTF
/// style node animation.
fn moving_box(scene: &mut Scene) {
    let centre = (BOX_MIN + BOX_MAX) * 0.5;
    fly(scene, 1, centre - Vec3::X * 3.0, centre + Vec3::X * 3.0);
}

/// Where the flying box is at `time`, as an offset from its rest place.
fn box_offset(time: f32) -> Vec3 {
    Vec3::X * (-3.0 + 60.0 * time)
}

#[test]
fn every_frame_traces_the_top_level_of_its_own_time_while_the_occluder_moves() {
    let (mut scene, camera) = shadow_scene(3.0);
    let (mut sunless, _) = shadow_scene(0.0);
    moving_box(&mut scene);
    moving_box(&mut sunless);
    let pipeline = PipelineKind::Visbuffer;
    let [mut lit, mut dark, mut shadowed] = [
        renderer(&scene, settings(pipeline, SunShadows::Off)),
        renderer(&sunless, settings(pipeline, SunShadows::Off)),
        renderer(&scene, settings(pipeline, SunShadows::Hard)),
    ];
    let mut shadow_columns = Vec::new();
    for frame in 0..5 {
        let time = shadowed.time;
        let images = [&mut lit, &mut dark, &mut shadowed].map(|r| {
            r.render(&camera).unwrap();
            r.read_hdr().unwrap()
        });
        let what = format!("frame {frame} at {time} s");
        // The box's draw (the scene's second) is ordered front to back by where it is now.
        let command = shadowed.scene.draw_commands.iter().find(|c| c.draw_index == 1).unwrap();
        let centre = (BOX_MIN + BOX_MAX) * 0.5 + box_offset(time);
        assert!(command.center.distance(centre) < 1e-4, "{what}: the box's draw is at {}, the box at {centre}", command.center);
        let (in_shadow, in_sun) = check_shadow(&images[2], &images[0], &images[1], box_offset(time), &what);
        assert!(in_shadow > 100 && in_sun > 3000, "{what}: {in_shadow} shadowed and {in_sun} sunlit pixels");
        // Where the shadow is, on average: it must travel with the box.
        let columns: Vec<u32> = (0..HEIGHT)
            .flat_map(|y| (0..WIDTH).map(move |x| (x, y)))
            .filter(|&(x, y)| seen_with_box_at(x, y, box_offset(time)) == Some(Seen::Surface { shadowed: true }))
            .map(|(x, _)| x)
            .collect();
        shadow_columns.push(columns.iter().sum::<u32>() as f32 / columns.len() as f32);
    }
    assert!(shadow_columns.windows(2).all(|w| w[1] > w[0] + 4.0), "the shadow does not follow the box: {shadow_columns:?}");
    // Frames submitted back to back, each placing the box and tracing it before the next: the last
    // frame equals the one rendered alone at its time.
    let mut batch = renderer(&scene, settings(pipeline, SunShadows::Hard));
    batch.render_frames(&camera, 5).unwrap();
    let mut single = renderer(&scene, settings(pipeline, SunShadows::Hard));
    single.time = 4.0 * manylights::renderer::FRAME_INTERVAL;
    single.render(&camera).unwrap();
    assert_eq!(batch.read_hdr().unwrap().pixels, single.read_hdr().unwrap().pixels);
}

/// The wall of `common::wall_scene` lit by a lamp at (2, 0, 3) that casts shadows (if `casts`), with an
/// opaque 1 m square at z = 1.5 centred before the wall: its shadow covers x in [-3, -1], y in
/// [-1, 1] of the wall.
fn lamp_and_blocker(casts: bool) -> (Scene, Camera) {
    let lamp = manylights::scene::Light { cast_shadows: casts, ..point_light(Vec3::new(2.0, 0.0, 3.0), 10.0, 10.0) };
    let (mut scene, camera) = wall_scene(vec![lamp]);
    scene.meshes.push(quad_mesh());
    scene.instances.push(Instance {
        mesh: 1,
        world_from_local: Mat4::from_scale_rotation_translation(Vec3::new(0.5, 0.5, 1.0), Quat::IDENTITY, Vec3::new(0.0, 0.0, 1.5)),
    });
    (scene, camera)
}

/// What the wall's pixel (x, y) of a `width`×`height` image shows, if its corners agree: `Some(true)`
/// in the blocker's shadow, `Some(false)` lit; `None` on an edge or where the blocker hides the wall.
fn wall_in_lamp_shadow(x: u32, y: u32, (width, height): (u32, u32)) -> Option<bool> {
    let tan = 30f32.to_radians().tan();
    let aspect = width as f32 / height as f32;
    let classify = |fx: f32, fy: f32| {
        let (nx, ny) = (fx / width as f32 * 2.0 - 1.0, 1.0 - fy / height as f32 * 2.0);
        let wall = Vec3::new(nx * tan * aspect * 4.0, ny * tan * 4.0, 0.0);
        // The blocker, seen from the camera at z = 4, hides the wall within 0.8 m of its centre.
        if wall.x.abs() <= 0.8 + 1e-3 && wall.y.abs() <= 0.8 + 1e-3 {
            return None;
        }
        Some((-3.0..=-1.0).contains(&wall.x) && (-1.0..=1.0).contains(&wall.y))
    };
    let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].map(|(dx, dy)| classify(x as f32 + dx, y as f32 + dy));
    corners.iter().all(|c| *c == corners[0]).then_some(corners[0]).flatten()
}

#[test]
fn lamps_that_cast_shadows_are_blocked_exactly_where_the_segment_to_them_is_in_every_method_and_pipeline() {
    let size = (96, 54);
    let config = |pipeline, lights, light_shadow_rays| RenderConfig {
        pipeline,
        rays: RaySettings { light_shadow_rays, ..Default::default() },
        ..common::config(size.0, size.1, lights)
    };
    let (scene, camera) = lamp_and_blocker(true);
    for pipeline in PipelineKind::ALL {
        let unshadowed = render_with(&scene, &camera, config(pipeline, LightMethod::Brute, 0)).1;
        for method in [LightMethod::Brute, LightMethod::Bvh, LightMethod::Clustered] {
            let what = format!("{} {}", pipeline.name(), method.name());
            let shadowed = render_with(&scene, &camera, config(pipeline, method, 1)).1;
            let (mut dark, mut lit) = (0, 0);
            for y in 0..size.1 {
                for x in 0..size.0 {
                    let Some(in_shadow) = wall_in_lamp_shadow(x, y, size) else { continue };
                    let got = pixel(&shadowed, x, y);
                    // No ambient: in the shadow the wall is black.
                    let expected = if in_shadow { [0.0; 4] } else { pixel(&unshadowed, x, y) };
                    let error = (0..3).map(|c| (got[c] - expected[c]).abs()).fold(0.0, f32::max);
                    assert!(error <= 1e-4, "{what}: pixel ({x}, {y}) in shadow {in_shadow}: {got:?}, expected {expected:?}");
                    if in_shadow {
                        dark += 1;
                    } else {
                        lit += 1;
                    }
                }
            }
            assert!(dark > 200 && lit > 2000, "{what}: {dark} shadowed and {lit} lit pixels");
        }
    }
    // A lamp that does not cast shadows, or a budget of none, lights the wall through the blocker.
    let (unflagged, _) = lamp_and_blocker(false);
    let reference = render_with(&scene, &camera, config(PipelineKind::Visbuffer, LightMethod::Bvh, 0)).1;
    let through = render_with(&unflagged, &camera, config(PipelineKind::Visbuffer, LightMethod::Bvh, 4)).1;
    assert_eq!(reference.pixels, through.pixels);
}
