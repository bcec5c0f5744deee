//! The post chain (`post/`), effect by effect, on emissive quads over a black sky (no sun, no ambient,
//! no lights: a surface's radiance is its emission) with the clamping tonemapper, so the 8-bit image
//! is the post-processed radiance, sRGB-encoded: vignetting follows the cos⁴ law; auto exposure maps
//! the measured luminance to middle grey, ignores the scene's scale, meters the surfaces in view
//! rather than the background and adapts at its rate; bloom
//! spreads a bright spot's light around it; depth of field blurs what is out of focus by its circle of
//! confusion and leaves what is in focus exact; motion blur smears along the camera's, animated
//! instances' and posed (morphed, skinned) meshes' motion and leaves still pixels exact.

mod common;

use common::*;
use glam::{Mat4, Quat, Vec3, Vec4};
use manylights::{
    renderer::{Image, FRAME_INTERVAL},
    scene::{
        animation::{Animation, Channel, Interpolation, Node, Property, Trs},
        deform::{Deformation, Deformer},
        pose::{MorphOffset, Pose, Skin, WeightKeys},
        Camera, Instance, Material, Scene,
    },
    settings::{AutoExposure, Bloom, DepthOfField, Exposure, MotionBlur, PostSettings},
    settings::{LightMethod, PipelineKind},
    settings::{RenderConfig, Tonemapper},
};

/// Metres per pixel at z = 0 seen from the test camera (4 m away, 60° vertical field of view, 144 rows).
const METRES_PER_PIXEL: f32 = 2.0 * 4.0 * 0.577_350_26 / HEIGHT as f32;

fn emissive(radiance: f32) -> Material {
    Material {
        base_color_factor: Vec4::new(0.0, 0.0, 0.0, 1.0),
        emissive_factor: Vec3::splat(radiance),
        metallic_factor: 0.0,
        ..Default::default()
    }
}

/// Emissive rectangles facing +Z, each (centre, half extent in x and y, radiance) with a mesh and
/// material of its own, and the test camera at z = 4 looking down −Z at the origin.
fn quads(rects: &[(Vec3, (f32, f32), f32)]) -> (Scene, Camera) {
    let mesh = |material| {
        let mut mesh = quad_mesh();
        mesh.primitives[0].material = material;
        mesh
    };
    let place = |&(centre, (hx, hy), _): &(Vec3, (f32, f32), f32)| {
        Mat4::from_scale_rotation_translation(Vec3::new(hx, hy, 1.0), Quat::IDENTITY, centre)
    };
    let scene = Scene {
        meshes: (0..rects.len()).map(mesh).collect(),
        materials: rects.iter().map(|r| emissive(r.2)).collect(),
        instances: rects.iter().enumerate().map(|(i, r)| Instance { mesh: i, world_from_local: place(r) }).collect(),
        ambient: Vec3::ZERO,
        ..Default::default()
    };
    let camera = Camera::look_at("front", Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 60f32.to_radians(), 0.1);
    (scene, camera)
}

fn post_config(post: PostSettings) -> RenderConfig {
    RenderConfig { tonemapper: Tonemapper::None, post, ..config(WIDTH, HEIGHT, LightMethod::Off) }
}

fn srgb_encode(linear: f32) -> f32 {
    if linear <= 0.0031308 {
        linear * 12.92
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

fn srgb_decode(encoded: u8) -> f32 {
    let c = encoded as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The 8-bit value the tonemap stores for a linear value in [0, 1].
fn ldr_of(linear: f32) -> f32 {
    (srgb_encode(linear.clamp(0.0, 1.0)) * 255.0).round()
}

fn red(image: &Image<[u8; 4]>, x: u32, y: u32) -> u8 {
    pixel(image, x, y)[0]
}

fn render_ldr(scene: &Scene, camera: &Camera, post: PostSettings) -> Image<[u8; 4]> {
    render_with(scene, camera, post_config(post)).0
}

/// The whole view filled by one emissive wall of `radiance`.
fn uniform_wall(radiance: f32) -> (Scene, Camera) {
    quads(&[(Vec3::ZERO, (10.0, 10.0), radiance)])
}

#[test]
fn vignetting_follows_the_cos4_law_off_the_axis() {
    let (scene, camera) = uniform_wall(0.5);
    for strength in [1.0, 0.5] {
        let image = render_ldr(&scene, &camera, PostSettings { vignette: strength, ..still_post() });
        let tan = (30f32).to_radians().tan();
        let aspect = WIDTH as f32 / HEIGHT as f32;
        for (x, y) in [(128, 72), (0, 0), (255, 143), (40, 100), (200, 20)] {
            let ndc = Vec3::new(
                ((x as f32 + 0.5) / WIDTH as f32 * 2.0 - 1.0) * tan * aspect,
                (1.0 - (y as f32 + 0.5) / HEIGHT as f32 * 2.0) * tan,
                1.0,
            );
            let cos_theta = 1.0 / ndc.length();
            let expected = ldr_of(0.5 * (1.0 + strength * (cos_theta.powi(4) - 1.0)));
            let got = red(&image, x, y) as f32;
            assert!((got - expected).abs() <= 1.0, "strength {strength}, pixel ({x}, {y}): {got}, expected {expected}");
        }
        // The corners lose most: cos⁴ of about 40° off the axis.
        assert!(red(&image, 0, 0) < red(&image, 128, 72));
    }
}

/// log2 of auto exposure for a uniform image of luminance `l`: middle grey over the centre of the
/// quarter-stop histogram bin `l` falls in (`exposure.wgsl`).
fn auto_exposure_log2(l: f32, compensation: f32) -> f32 {
    let bin = ((l.log2() + 16.0) * 4.0).floor();
    (0.18f32).log2() + compensation - (-16.0 + (bin + 0.5) / 4.0)
}

#[test]
fn auto_exposure_maps_the_image_to_middle_grey_whatever_its_scale_and_adapts_at_its_rate() {
    // 1 % above powers of two, so the luminance sits inside its bin whatever the rounding.
    let (dim, bright) = (1.01 * 2f32.powi(-4), 1.01 * 2f32.powi(-2));
    let auto =
        |compensation_ev| PostSettings { exposure: Exposure::Auto(AutoExposure { compensation_ev, ..Default::default() }), ..still_post() };
    let (dim_wall, camera) = uniform_wall(dim);
    let (bright_wall, _) = uniform_wall(bright);
    let dim_image = render_ldr(&dim_wall, &camera, auto(0.0));
    let bright_image = render_ldr(&bright_wall, &camera, auto(0.0));
    // Four times the light is eight bins up: the same exposed image.
    assert_eq!(dim_image.pixels, bright_image.pixels, "auto exposure must not depend on the scene's scale");
    let expected = ldr_of(dim * auto_exposure_log2(dim, 0.0).exp2());
    assert!((red(&dim_image, 100, 50) as f32 - expected).abs() <= 1.0, "{} vs {expected}", red(&dim_image, 100, 50));
    // One stop of compensation doubles it.
    let brighter = render_ldr(&dim_wall, &camera, auto(1.0));
    let expected = ldr_of(dim * auto_exposure_log2(dim, 1.0).exp2());
    assert!((red(&brighter, 100, 50) as f32 - expected).abs() <= 1.0, "{} vs {expected}", red(&brighter, 100, 50));

    // Adaptation: the dim wall ahead, the bright one behind the camera; the first frame takes the
    // dim wall's exposure at once, the next, turned to the bright wall, moves 1 − e^(−Δt·speed) of the
    // way in stops.
    let speed = 10.0;
    let (mut scene, ahead) = quads(&[(Vec3::ZERO, (10.0, 10.0), dim), (Vec3::new(0.0, 0.0, 8.0), (10.0, 10.0), bright)]);
    scene.instances[1].world_from_local = Mat4::from_scale_rotation_translation(
        Vec3::new(10.0, 10.0, 1.0),
        Quat::from_rotation_y(std::f32::consts::PI),
        Vec3::new(0.0, 0.0, 8.0),
    );
    let behind = Camera::look_at("back", Vec3::new(0.0, 0.0, 4.0), Vec3::new(0.0, 0.0, 8.0), 60f32.to_radians(), 0.1);
    let settings =
        PostSettings { exposure: Exposure::Auto(AutoExposure { compensation_ev: 0.0, adaptation_speed: speed }), ..still_post() };
    let mut renderer = renderer(&scene, post_config(settings));
    renderer.render(&ahead).unwrap();
    let first = renderer.read_ldr().unwrap();
    assert!((red(&first, 100, 50) as f32 - ldr_of(dim * auto_exposure_log2(dim, 0.0).exp2())).abs() <= 1.0);
    renderer.render(&behind).unwrap();
    let second = renderer.read_ldr().unwrap();
    let rate = 1.0 - (-FRAME_INTERVAL * speed).exp();
    let (from, to) = (auto_exposure_log2(dim, 0.0), auto_exposure_log2(bright, 0.0));
    let expected = ldr_of(bright * (from + (to - from) * rate).exp2());
    assert!((red(&second, 100, 50) as f32 - expected).abs() <= 1.0, "adapting: {} vs {expected}", red(&second, 100, 50));
    let settled = ldr_of(bright * to.exp2());
    assert!(red(&second, 100, 50) as f32 > settled + 10.0, "the exposure must not jump to the bright wall's at once");
}

/// The surfaces in view are metered, not the background around them (here the void of a uniform
/// ambient, 16 times darker than the quad): a model on an empty background is exposed for the model.
/// With no surface in view, the background is.
#[test]
fn auto_exposure_meters_the_surfaces_in_view_and_the_background_only_without_them() {
    let (dim, bright) = (1.01 * 2f32.powi(-8), 1.01 * 2f32.powi(-4));
    let (mut scene, camera) = quads(&[(Vec3::ZERO, (0.5, 0.5), bright)]);
    scene.ambient = Vec3::splat(dim);
    let auto = PostSettings { exposure: Exposure::Auto(AutoExposure::default()), ..still_post() };
    let image = render_ldr(&scene, &camera, auto);
    let (centre, corner) = (red(&image, WIDTH / 2, HEIGHT / 2), red(&image, 2, 2));
    let expected = ldr_of(bright * auto_exposure_log2(bright, 0.0).exp2());
    assert!((centre as f32 - expected).abs() <= 1.0, "the quad: {centre} vs {expected}");
    assert!(corner < 40, "the background stays darker than the quad: {corner}");

    let away = Camera::look_at("away", Vec3::new(0.0, 0.0, 4.0), Vec3::new(0.0, 0.0, 8.0), 60f32.to_radians(), 0.1);
    let background = red(&render_ldr(&scene, &away, auto), WIDTH / 2, HEIGHT / 2);
    let expected = ldr_of(dim * auto_exposure_log2(dim, 0.0).exp2());
    assert!((background as f32 - expected).abs() <= 1.0, "the background alone: {background} vs {expected}");
}

#[test]
fn bloom_spreads_a_bright_spot_over_its_surroundings_falling_off_with_distance() {
    // An 8×8-pixel spot of radiance 1 at the image's centre, on the black sky.
    let half = 4.0 * METRES_PER_PIXEL;
    let (scene, camera) = quads(&[(Vec3::ZERO, (half, half), 1.0)]);
    let off = render_ldr(&scene, &camera, still_post());
    let bloom = |intensity| render_ldr(&scene, &camera, PostSettings { bloom: Some(Bloom { intensity }), ..still_post() });
    let (full, half_bloom) = (bloom(1.0), bloom(0.5));
    // Without bloom the sky beside the spot is black; with it, lit, less and less farther out, and
    // alike on every side.
    let ring = |image: &Image<[u8; 4]>, d: u32| {
        let samples = [(132 + d, 72), (123 - d, 72), (128, 76 + d), (127, 67 - d)];
        samples.map(|(x, y)| srgb_decode(red(image, x, y)))
    };
    let mut previous = f32::INFINITY;
    for d in [2, 6, 12, 24] {
        assert!(ring(&off, d).iter().all(|&v| v == 0.0), "{d} px out, without bloom: {:?}", ring(&off, d));
        let lit = ring(&full, d);
        let mean = lit.iter().sum::<f32>() / 4.0;
        assert!(mean > 0.0 && mean < previous, "{d} px out: {lit:?} after {previous}");
        assert!(lit.iter().all(|&v| (v - mean).abs() <= 0.25 * mean + 2e-3), "{d} px out, not alike on every side: {lit:?}");
        previous = mean;
    }
    // The blend is linear in the intensity: half of it halves the way from the image to the bloom.
    for (x, y) in [(120, 72), (128, 60), (128, 72), (100, 72)] {
        let expected = 0.5 * (srgb_decode(red(&off, x, y)) + srgb_decode(red(&full, x, y)));
        let got = srgb_decode(red(&half_bloom, x, y));
        assert!((got - expected).abs() <= 0.01 * expected.max(0.2), "pixel ({x}, {y}): {got} vs {expected}");
    }
}

/// The circle of confusion's radius in pixels of a point `distance` m along the view axis, for the
/// test camera at f-number `n` focused at `focus` (`post::PostUniforms`).
fn coc_radius(distance: f32, focus: f32, n: f32) -> f32 {
    let focal_length = manylights::post::SENSOR_HEIGHT * 0.5 / 30f32.to_radians().tan();
    let per_dioptre = focal_length * focal_length / n / manylights::post::SENSOR_HEIGHT * HEIGHT as f32;
    0.5 * per_dioptre * (1.0 / focus - 1.0 / distance).abs() * focus / (focus - focal_length)
}

#[test]
fn depth_of_field_blurs_by_the_circle_of_confusion_and_keeps_what_is_in_focus_exact() {
    // A vertical bar four pixels wide, 4 m from the camera, on the black sky.
    let bar = |x: f32| (Vec3::new(x, 0.0, 0.0), (2.0 * METRES_PER_PIXEL, 10.0), 1.0);
    let (scene, camera) = quads(&[bar(0.0)]);
    let sharp = render_ldr(&scene, &camera, still_post());
    let dof = |focus, f_number| PostSettings {
        depth_of_field: Some(DepthOfField { focus_distance: focus, f_number, max_radius: 16.0 }),
        ..still_post()
    };
    // Focused on the bar (explicitly, or on what the centre shows): exactly the sharp image.
    assert_eq!(render_ldr(&scene, &camera, dof(Some(4.0), 0.1)).pixels, sharp.pixels);
    assert_eq!(render_ldr(&scene, &camera, dof(None, 0.1)).pixels, sharp.pixels);
    // Focused at 1 m: the bar spreads over its circle of confusion (about 10 px), no farther.
    let radius = coc_radius(4.0, 1.0, 0.1);
    assert!((8.0..12.0).contains(&radius), "{radius}");
    let blurred = render_ldr(&scene, &camera, dof(Some(1.0), 0.1));
    let y = 72;
    for x in 0..WIDTH {
        // Distance from the bar's nearest column (it covers columns 126 to 129).
        let d = if x < 126 { 126 - x } else { x.saturating_sub(129) } as f32;
        let v = red(&blurred, x, y);
        if d >= 1.0 && d <= radius - 1.5 {
            assert!(v > 0, "column {x}, {d} px beside the bar, within its circle of confusion {radius}, is dark");
        }
        if d >= radius + 1.5 {
            assert_eq!(v, 0, "column {x}, {d} px beside the bar, beyond its circle of confusion {radius}, is lit");
        }
    }
    assert!(red(&blurred, 128, y) < red(&sharp, 128, y), "the blurred bar must be dimmer than the sharp one");

    // A sharp bar in front of a blurred wall 8 m away: the wall's blur does not spill over the bar,
    // and the uniform wall stays uniform.
    let (scene, camera) = quads(&[bar(0.0), (Vec3::new(0.0, 0.0, -4.0), (20.0, 20.0), 0.25)]);
    let image = render_ldr(&scene, &camera, dof(Some(4.0), 0.1));
    for x in 126..=129 {
        assert_eq!(red(&image, x, y), 255, "the bar in focus, column {x}");
    }
    let wall = ldr_of(0.25) as u8;
    for x in [10, 60, 110, 150, 200, 250] {
        assert_eq!(red(&image, x, y), wall, "the wall, column {x}");
    }
}

/// Columns of row `y` that are lit.
fn lit_columns(image: &Image<[u8; 4]>, y: u32) -> Vec<u32> {
    (0..WIDTH).filter(|&x| red(image, x, y) > 0).collect()
}

#[test]
fn motion_blur_smears_along_the_cameras_motion_and_leaves_a_still_image_exact() {
    // A 12×12-pixel square at the centre.
    let half = 6.0 * METRES_PER_PIXEL;
    let (scene, camera) = quads(&[(Vec3::ZERO, (half, half), 1.0)]);
    let blur = PostSettings { motion_blur: Some(MotionBlur { shutter: 1.0, samples: 32, max_length: 32.0 }), ..still_post() };
    let still = render_ldr(&scene, &camera, still_post());
    assert_eq!(render_ldr(&scene, &camera, blur).pixels, still.pixels, "nothing moved: nothing may blur");

    // The camera slides 10 pixels' worth to the left between two frames: the square moves 10 px to
    // the right on screen, and with a full-frame shutter smears 5 px to each side of where it is,
    // along x only.
    let shift = 10.0 * METRES_PER_PIXEL;
    let moved = Camera::look_at("moved", Vec3::new(-shift, 0.0, 4.0), Vec3::new(-shift, 0.0, 0.0), 60f32.to_radians(), 0.1);
    let mut blurred = renderer(&scene, post_config(blur));
    blurred.render(&camera).unwrap();
    blurred.render(&moved).unwrap();
    let image = blurred.read_ldr().unwrap();
    let sharp = render_ldr(&scene, &moved, still_post());
    let (sharp_columns, blurred_columns) = (lit_columns(&sharp, 72), lit_columns(&image, 72));
    let (first, last) = (sharp_columns[0], *sharp_columns.last().unwrap());
    assert_eq!(last - first + 1, 12, "{sharp_columns:?}");
    assert!(
        blurred_columns[0] + 4 <= first && blurred_columns[0] + 6 >= first,
        "the smear must reach about 5 px before the square: {blurred_columns:?} vs {first}..={last}"
    );
    let blurred_last = *blurred_columns.last().unwrap();
    assert!(blurred_last >= last + 4 && blurred_last <= last + 6, "and about 5 px after it: {blurred_columns:?} vs {first}..={last}");
    // Rows just above and below the square stay dark: the motion is horizontal.
    for y in [65, 79] {
        assert!(lit_columns(&sharp, y).is_empty());
        assert!(lit_columns(&image, y).is_empty(), "row {y} is lit: {:?}", lit_columns(&image, y));
    }
}

#[test]
fn motion_blur_smears_animated_instances_by_their_own_motion_and_not_still_ones_beside_them() {
    // Two 12×12-pixel squares 40 px apart; the left one flies along +x at 10 px a frame (glTF-style
    // node animation), the right one stands still.
    let half = 6.0 * METRES_PER_PIXEL;
    let left = Vec3::new(-20.0 * METRES_PER_PIXEL, 0.0, 0.0);
    let right = Vec3::new(20.0 * METRES_PER_PIXEL, 0.0, 0.0);
    let (mut scene, camera) = quads(&[(left, (half, half), 1.0), (right, (half, half), 0.5)]);
    let speed = 10.0 * METRES_PER_PIXEL / FRAME_INTERVAL;
    scene.animation = Some(Animation {
        name: "fly".into(),
        nodes: vec![Node::from_trs(None, Trs { translation: left, rotation: Quat::IDENTITY, scale: Vec3::new(half, half, 1.0) })],
        channels: vec![Channel {
            node: 0,
            property: Property::Translation,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![(left - Vec3::X * speed * 0.5).extend(0.0), (left + Vec3::X * speed * 0.5).extend(0.0)],
        }],
        instances: vec![(0, 0)],
        duration: 1.0,
    });
    // At 0.5 s the flying square is back at its rest place, moving right.
    let at = |post| {
        let mut r = renderer(&scene, post_config(post));
        r.time = 0.5;
        r.render(&camera).unwrap();
        r.read_ldr().unwrap()
    };
    let sharp = at(still_post());
    let blurred = at(PostSettings { motion_blur: Some(MotionBlur { shutter: 1.0, samples: 32, max_length: 32.0 }), ..still_post() });
    let y = 72;
    let flying: Vec<u32> = lit_columns(&sharp, y).into_iter().filter(|&x| x < 128).collect();
    let (first, last) = (flying[0], *flying.last().unwrap());
    assert_eq!(last - first + 1, 12, "{flying:?}");
    let smeared: Vec<u32> = lit_columns(&blurred, y).into_iter().filter(|&x| x < 128).collect();
    assert!(
        smeared[0] + 4 <= first && *smeared.last().unwrap() >= last + 4,
        "the flying square must smear about 5 px each way: {smeared:?} vs {first}..={last}"
    );
    // The still square and everything right of the middle is exactly as without motion blur.
    for x in 128..WIDTH {
        for y in 60..85 {
            assert_eq!(pixel(&blurred, x, y), pixel(&sharp, x, y), "the still square's side at ({x}, {y})");
        }
    }
    for y in [65, 79] {
        assert!(lit_columns(&blurred, y).is_empty(), "row {y} is lit: the motion is horizontal");
    }
}

#[test]
fn motion_blur_smears_morphed_and_skinned_meshes_by_their_previous_pose() {
    // Two 12×12-pixel squares 40 px apart, each flying along +x at 10 px a frame: the left one by a
    // morph target moving every vertex, the right one by the joint it is skinned to. At 0.5 s both
    // are at their rest place.
    let half = 6.0 * METRES_PER_PIXEL;
    let left = Vec3::new(-20.0 * METRES_PER_PIXEL, 0.0, 0.0);
    let right = Vec3::new(20.0 * METRES_PER_PIXEL, 0.0, 0.0);
    let (mut scene, camera) = quads(&[(left, (half, half), 1.0), (right, (half, half), 1.0)]);
    let speed = 10.0 * METRES_PER_PIXEL / FRAME_INTERVAL;
    // The morph target moves a vertex by `speed` metres at weight 1, in the quad's space (scaled by
    // `half`); the weight runs from −0.5 to 0.5 over a second.
    let slide = MorphOffset { position: Vec3::X * speed / half, ..Default::default() };
    let morphed = Pose {
        targets: vec![vec![slide; 4]],
        rest_weights: vec![0.0],
        weight_keys: Some(WeightKeys { interpolation: Interpolation::Linear, times: vec![0.0, 1.0], values: vec![-0.5, 0.5] }),
        skin: None,
    };
    // The right square is placed by its joint (a skinned mesh's node transform is not used).
    scene.instances[1].world_from_local = Mat4::IDENTITY;
    let skinned = Pose {
        targets: Vec::new(),
        rest_weights: Vec::new(),
        weight_keys: None,
        skin: Some(Skin {
            joints: vec![0],
            inverse_bind: vec![Mat4::IDENTITY],
            sets: 1,
            joint_indices: vec![[0; 4]; 4],
            weights: vec![[1.0, 0.0, 0.0, 0.0]; 4],
        }),
    };
    scene.deformers = vec![
        Deformer { mesh: 0, deformation: Deformation::Pose(Box::new(morphed)) },
        Deformer { mesh: 1, deformation: Deformation::Pose(Box::new(skinned)) },
    ];
    scene.animation = Some(Animation {
        name: "joint".into(),
        nodes: vec![Node::from_trs(None, Trs { translation: right, rotation: Quat::IDENTITY, scale: Vec3::new(half, half, 1.0) })],
        channels: vec![Channel {
            node: 0,
            property: Property::Translation,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![(right - Vec3::X * speed * 0.5).extend(0.0), (right + Vec3::X * speed * 0.5).extend(0.0)],
        }],
        instances: Vec::new(),
        duration: 1.0,
    });
    let at = |post| {
        let mut r = renderer(&scene, post_config(post));
        r.time = 0.5;
        r.render(&camera).unwrap();
        r.read_ldr().unwrap()
    };
    let sharp = at(still_post());
    let blurred = at(PostSettings { motion_blur: Some(MotionBlur { shutter: 1.0, samples: 32, max_length: 32.0 }), ..still_post() });
    let y = 72;
    for (name, side) in [("morphed", 0..128), ("skinned", 128..WIDTH)] {
        let square: Vec<u32> = lit_columns(&sharp, y).into_iter().filter(|x| side.contains(x)).collect();
        let (first, last) = (square[0], *square.last().unwrap());
        assert_eq!(last - first + 1, 12, "{name}: {square:?}");
        let smeared: Vec<u32> = lit_columns(&blurred, y).into_iter().filter(|x| side.contains(x)).collect();
        assert!(
            smeared[0] + 4 <= first && smeared[0] + 6 >= first && *smeared.last().unwrap() >= last + 4,
            "the {name} square must smear about 5 px each way: {smeared:?} vs {first}..={last}"
        );
    }
}

#[test]
fn every_post_effect_runs_in_every_pipeline() {
    let (scene, camera) = quads(&[(Vec3::ZERO, (0.5, 0.5), 1.0), (Vec3::new(0.0, 0.0, -4.0), (20.0, 20.0), 0.1)]);
    let all = PostSettings {
        exposure: Exposure::Auto(AutoExposure::default()),
        bloom: Some(Bloom::default()),
        depth_of_field: Some(DepthOfField { f_number: 0.5, ..Default::default() }),
        motion_blur: Some(MotionBlur::default()),
        vignette: 0.5,
    };
    let reference = render_with(&scene, &camera, RenderConfig { pipeline: PipelineKind::Visbuffer, ..post_config(all) }).0;
    for pipeline in [PipelineKind::Deferred, PipelineKind::Forward] {
        let image = render_with(&scene, &camera, RenderConfig { pipeline, ..post_config(all) }).0;
        let worst = image.pixels.iter().zip(&reference.pixels).map(|(a, b)| (a[0] as i32 - b[0] as i32).abs()).max().unwrap();
        assert!(worst <= 2, "{}: off the visibility buffer's image by {worst}", pipeline.name());
    }
}

#[test]
fn bad_post_settings_are_refused_with_the_flag_to_fix() {
    let (scene, camera) = uniform_wall(1.0);
    let cases: [(PostSettings, &str); 6] = [
        (PostSettings { vignette: 2.0, ..still_post() }, "--vignette"),
        (PostSettings { bloom: Some(Bloom { intensity: f32::NAN }), ..still_post() }, "--bloom-intensity"),
        (
            PostSettings { depth_of_field: Some(DepthOfField { focus_distance: Some(-1.0), ..Default::default() }), ..still_post() },
            "--focus-distance",
        ),
        (PostSettings { depth_of_field: Some(DepthOfField { f_number: 0.0, ..Default::default() }), ..still_post() }, "--f-number"),
        (PostSettings { motion_blur: Some(MotionBlur { samples: 0, ..Default::default() }), ..still_post() }, "--motion-blur-samples"),
        (
            PostSettings {
                exposure: Exposure::Auto(AutoExposure { compensation_ev: f32::INFINITY, ..Default::default() }),
                ..still_post()
            },
            "--exposure-compensation",
        ),
    ];
    for (settings, flag) in cases {
        let ctx = manylights::gpu::GpuContext::new().unwrap();
        let error = match manylights::renderer::Renderer::new(ctx, &scene, post_config(settings)) {
            Ok(_) => panic!("{settings:?} was accepted"),
            Err(e) => e.to_string(),
        };
        assert!(error.contains(flag), "{error}");
    }
    // Depth of field needs a lens: an orthographic camera is refused when the frame is rendered.
    let ortho =
        Camera { projection: manylights::scene::Projection::Orthographic { xmag: 2.0, ymag: 2.0, znear: 0.1, zfar: 10.0 }, ..camera };
    let mut r = renderer(&scene, post_config(PostSettings { depth_of_field: Some(DepthOfField::default()), ..still_post() }));
    let error = r.render(&ortho).unwrap_err().to_string();
    assert!(error.contains("perspective"), "{error}");
}
