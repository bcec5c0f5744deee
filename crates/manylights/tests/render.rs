//! GPU rendering tests (lavapipe in CI, ≤ 256×144): the demo renders lit, varied and deterministic
//! images that match the golden image; lights really light; the shading matches the analytic BRDF.

mod common;

use std::path::PathBuf;

use common::*;
use glam::Vec3;
use manylights::gpu::GpuContext;
use manylights::scene::{demo::demo_scene, Camera, Light, LightKind, Texture, TextureRef, Wrap};
use manylights::settings::LightMethod;

fn demo_frame() -> (manylights::renderer::Image<[u8; 4]>, manylights::renderer::Image<[f32; 4]>) {
    let scene = demo_scene();
    render(&scene, &scene.cameras[0])
}

#[test]
fn demo_is_lit_varied_and_deterministic() {
    let (ldr, hdr) = demo_frame();
    let (again, _) = demo_frame();
    assert_eq!(ldr.pixels, again.pixels, "two renders of the demo differ");

    let lum: Vec<f32> = ldr.pixels.iter().map(|p| luminance([p[0] as f32, p[1] as f32, p[2] as f32, 0.0]) / 255.0).collect();
    let mean = lum.iter().sum::<f32>() / lum.len() as f32;
    let variance = lum.iter().map(|l| (l - mean).powi(2)).sum::<f32>() / lum.len() as f32;
    assert!(mean > 0.15 && mean < 0.85, "demo mean luminance {mean} is too dark or too bright");
    assert!(variance.sqrt() > 0.08, "demo is nearly uniform (std dev {})", variance.sqrt());
    let distinct: std::collections::HashSet<[u8; 4]> = ldr.pixels.iter().copied().collect();
    assert!(distinct.len() > 2000, "only {} distinct colours", distinct.len());
    assert!(hdr.pixels.iter().all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)), "HDR has NaN, inf or negative values");
}

/// Mean absolute difference per channel (0–255) and the fraction of pixels differing by more than
/// `threshold` in any channel.
fn compare(a: &[[u8; 4]], b: &[[u8; 4]], threshold: u8) -> (f64, f64) {
    let mut sum = 0u64;
    let mut over = 0usize;
    for (p, q) in a.iter().zip(b) {
        let d: Vec<u8> = (0..3).map(|c| p[c].abs_diff(q[c])).collect();
        sum += d.iter().map(|&x| u64::from(x)).sum::<u64>();
        over += usize::from(d.iter().any(|&x| x > threshold));
    }
    (sum as f64 / (a.len() * 3) as f64, over as f64 / a.len() as f64)
}

#[test]
fn demo_matches_golden_image() {
    let golden_path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden/demo_256x144.png");
    let (ldr, _) = demo_frame();
    let actual = image::RgbaImage::from_raw(ldr.width, ldr.height, ldr.pixels.concat()).unwrap();
    if std::env::var_os("MANYLIGHTS_UPDATE_GOLDEN").is_some() {
        actual.save(&golden_path).unwrap();
        return;
    }
    let golden = image::open(&golden_path).expect("golden image (regenerate with MANYLIGHTS_UPDATE_GOLDEN=1)").to_rgba8();
    assert_eq!(golden.dimensions(), actual.dimensions());
    let to_pixels = |img: &image::RgbaImage| img.pixels().map(|p| p.0).collect::<Vec<_>>();
    let (mean, fraction_over) = compare(&to_pixels(&golden), &to_pixels(&actual), 16);
    // Tolerance: driver and LLVM versions may change rounding, never the picture.
    if mean > 1.0 || fraction_over > 0.005 {
        let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
        let diff = image::RgbaImage::from_fn(actual.width(), actual.height(), |x, y| {
            let (a, g) = (actual.get_pixel(x, y), golden.get_pixel(x, y));
            let d = (0..3).map(|c| a[c].abs_diff(g[c])).max().unwrap();
            image::Rgba([d.saturating_mul(8), d.saturating_mul(8), d.saturating_mul(8), 255])
        });
        actual.save(out.join("demo_actual.png")).unwrap();
        diff.save(out.join("demo_diff.png")).unwrap();
        panic!(
            "demo differs from the golden image: mean {mean:.3}/255, {:.3}% of pixels over 16/255; see {}",
            fraction_over * 100.0,
            out.join("demo_diff.png").display()
        );
    }
}

#[test]
fn a_light_before_a_wall_brightens_it_and_removing_it_darkens_it() {
    let light = point_light(Vec3::new(1.0, 0.5, 1.0), 5.0, 4.0);
    let (scene_lit, camera) = wall_scene(vec![light]);
    let (scene_dark, _) = wall_scene(vec![]);
    let (_, lit) = render(&scene_lit, &camera);
    let (_, dark) = render(&scene_dark, &camera);

    let mean =
        |img: &manylights::renderer::Image<[f32; 4]>| img.pixels.iter().map(|&p| luminance(p)).sum::<f32>() / img.pixels.len() as f32;
    assert!(mean(&dark) < 1e-6, "with no light, no sun and no ambient the wall must be black, mean {}", mean(&dark));
    assert!(mean(&lit) > 0.01, "the light does not light the wall (mean {})", mean(&lit));

    // The brightest pixel is where the light is closest: its projection onto the wall.
    let (brightest, _) = lit.pixels.iter().enumerate().max_by(|a, b| luminance(*a.1).total_cmp(&luminance(*b.1))).unwrap();
    let (bx, by) = ((brightest as u32 % WIDTH) as f32, (brightest as u32 / WIDTH) as f32);
    let clip =
        camera.clip_from_view(WIDTH as f32 / HEIGHT as f32) * camera.world_from_view.inverse() * Vec3::new(1.0, 0.5, 0.0).extend(1.0);
    let expected = ((clip.x / clip.w * 0.5 + 0.5) * WIDTH as f32, (0.5 - clip.y / clip.w * 0.5) * HEIGHT as f32);
    assert!((bx - expected.0).abs() <= 2.0 && (by - expected.1).abs() <= 2.0, "brightest at ({bx}, {by}), expected near {expected:?}");

    // Beyond the range nothing is lit: the wall's far corner is black.
    assert_eq!(luminance(pixel(&lit, 0, HEIGHT - 1)), 0.0);
}

#[test]
fn spot_light_lights_only_inside_its_cone() {
    let spot = Light {
        kind: LightKind::Spot { inner_cone_angle: 10f32.to_radians(), outer_cone_angle: 20f32.to_radians() },
        position: Vec3::new(0.0, 0.0, 2.0),
        direction: Vec3::NEG_Z,
        color: Vec3::ONE,
        intensity: 10.0,
        range: 10.0,
        cast_shadows: false,
    };
    let (scene, camera) = wall_scene(vec![spot]);
    let (_, hdr) = render(&scene, &camera);
    // Centre of the image = the wall point on the spot's axis; the cone's edge on the wall lies at
    // 2 m · tan 20° ≈ 0.73 m, about 25 px from the centre at this field of view.
    let centre = luminance(pixel(&hdr, WIDTH / 2, HEIGHT / 2));
    let outside = luminance(pixel(&hdr, WIDTH / 2 + 40, HEIGHT / 2));
    assert!(centre > 0.05, "spot centre {centre}");
    assert_eq!(outside, 0.0, "outside the cone must be unlit");
}

/// The glTF BRDF and falloff, on the CPU, for a white Lambert-plus-GGX wall (roughness 1, metallic 0).
fn reference_radiance(light: &Light, point: Vec3, normal: Vec3, eye: Vec3) -> f32 {
    use std::f32::consts::PI;
    let to_light = light.position - point;
    let d2 = to_light.length_squared();
    let l = to_light.normalize();
    let v = (eye - point).normalize();
    let h = (l + v).normalize();
    let (n_l, n_v, n_h, v_h) = (normal.dot(l), normal.dot(v), normal.dot(h), v.dot(h));
    let ratio2 = d2 / (light.range * light.range);
    let window = (1.0 - ratio2 * ratio2).clamp(0.0, 1.0).powi(2);
    let alpha = 1.0f32; // roughness 1
    let d = alpha * alpha / (PI * ((n_h * n_h) * (alpha * alpha - 1.0) + 1.0).powi(2));
    let gv = n_l * (n_v * n_v * (1.0 - alpha * alpha) + alpha * alpha).sqrt();
    let gl = n_v * (n_l * n_l * (1.0 - alpha * alpha) + alpha * alpha).sqrt();
    let vis = 0.5 / (gv + gl);
    let fresnel = 0.04 + 0.96 * (1.0 - v_h).powi(5);
    let brdf = d * vis * fresnel + (1.0 - fresnel) / PI;
    light.intensity * window / d2 * brdf * n_l
}

#[test]
fn shading_matches_the_analytic_brdf_and_falloff() {
    let light = point_light(Vec3::new(0.3, -0.2, 1.5), 3.0, 5.0);
    let (scene, camera) = wall_scene(vec![light]);
    let (_, hdr) = render(&scene, &camera);
    for (x, y) in [(WIDTH / 2, HEIGHT / 2), (100, 40), (180, 100)] {
        // The point on the wall under the pixel centre.
        let ndc = glam::Vec2::new((x as f32 + 0.5) / WIDTH as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / HEIGHT as f32 * 2.0);
        let half_height = (30f32.to_radians()).tan() * 4.0;
        let point = Vec3::new(ndc.x * half_height * WIDTH as f32 / HEIGHT as f32, ndc.y * half_height, 0.0);
        let expected = reference_radiance(&light, point, Vec3::Z, camera.position());
        let actual = pixel(&hdr, x, y)[1];
        let error = (actual - expected).abs() / expected.max(1e-6);
        assert!(error < 0.01, "pixel ({x}, {y}): GPU {actual}, reference {expected}, relative error {error}");
    }
}

#[test]
fn mirrored_instances_are_drawn_and_lit_like_their_originals() {
    // A light on the mirror plane: the mirrored wall must look exactly like the original, not be
    // culled for its reversed winding, and not have its normal flipped.
    let light = point_light(Vec3::new(0.0, 0.4, 1.5), 4.0, 6.0);
    let (original, camera) = wall_scene(vec![light]);
    let mut mirrored = original.clone();
    mirrored.instances[0].world_from_local = glam::Mat4::from_scale(Vec3::new(-10.0, 10.0, 1.0));
    let (_, a) = render(&original, &camera);
    let (_, b) = render(&mirrored, &camera);
    assert!(luminance(pixel(&b, WIDTH / 2, HEIGHT / 2)) > 0.05, "the mirrored wall is missing or unlit");
    let max_difference = max_abs_difference(&a, &b);
    assert!(max_difference < 1e-3, "mirrored wall differs by {max_difference}");
}

/// An unlit quad whose emissive texture is a horizontal ramp, with u running 0..2 across it: the
/// second half shows what each wrap mode makes of u > 1.
fn wrap_probe(wrap: Wrap) -> (manylights::renderer::Image<[f32; 4]>, Camera) {
    let ramp: Vec<u8> = (0..8 * 8)
        .flat_map(|i| {
            let c = ((i % 8) * 32 + 16) as u8;
            [c, c, c, 255]
        })
        .collect();
    let (mut scene, camera) = wall_scene(vec![]);
    scene.textures = vec![Texture { name: "ramp".into(), width: 8, height: 8, rgba8: ramp }];
    scene.materials[0].base_color_factor = glam::Vec4::new(0.0, 0.0, 0.0, 1.0);
    scene.materials[0].emissive_factor = Vec3::ONE;
    scene.materials[0].emissive_texture = Some(TextureRef::new(0, wrap, Wrap::Repeat));
    for v in &mut scene.meshes[0].primitives[0].vertices {
        v.u *= 2.0;
    }
    scene.instances[0].world_from_local = glam::Mat4::from_scale(Vec3::new(2.0, 2.0, 1.0));
    let (_, hdr) = render(&scene, &camera);
    (hdr, camera)
}

/// Radiance at the wall point where u (0..2 over x in -2..2) takes the given value.
fn at_u(image: &manylights::renderer::Image<[f32; 4]>, camera: &Camera, u: f32) -> f32 {
    let world = Vec3::new((u - 1.0) * 2.0, 0.0, 0.0);
    let clip = camera.clip_from_view(WIDTH as f32 / HEIGHT as f32) * camera.world_from_view.inverse() * world.extend(1.0);
    let x = ((clip.x / clip.w * 0.5 + 0.5) * WIDTH as f32) as u32;
    pixel(image, x, HEIGHT / 2)[0]
}

#[test]
fn texture_wrap_modes_follow_gltf() {
    let close = |a: f32, b: f32| (a - b).abs() < 0.03;
    let (repeat, camera) = wrap_probe(Wrap::Repeat);
    let (low, high) = (at_u(&repeat, &camera, 0.375), at_u(&repeat, &camera, 0.625));
    assert!(high - low > 0.1, "the ramp must rise along u: {low} → {high}");
    assert!(close(at_u(&repeat, &camera, 1.375), low), "repeat: u 1.375 must look like 0.375");

    let (mirrored, _) = wrap_probe(Wrap::MirroredRepeat);
    assert!(close(at_u(&mirrored, &camera, 1.375), high), "mirrored repeat: u 1.375 must look like 0.625");

    let (clamped, _) = wrap_probe(Wrap::ClampToEdge);
    let edge = at_u(&clamped, &camera, 0.97);
    assert!(edge > high, "the last texel is the brightest");
    for u in [1.375, 1.625, 1.9] {
        assert!(close(at_u(&clamped, &camera, u), edge), "clamp to edge: u {u} must show the edge texel");
    }
}

#[test]
fn a_scene_far_from_the_origin_renders_like_one_at_the_origin() {
    // Pixel rays are rebuilt relative to the camera, so moving scene and camera 5 km away must not
    // change the image beyond f32 rounding of the positions themselves.
    let shift = Vec3::new(5000.0, 0.0, -5000.0);
    let light = point_light(Vec3::new(0.5, 0.3, 1.2), 4.0, 5.0);
    let (near, camera) = wall_scene(vec![light]);
    let mut far = near.clone();
    far.instances[0].world_from_local = glam::Mat4::from_translation(shift) * far.instances[0].world_from_local;
    far.lights[0].position += shift;
    let mut far_camera = camera.clone();
    far_camera.world_from_view = glam::Mat4::from_translation(shift) * far_camera.world_from_view;
    let (_, a) = render(&near, &camera);
    let (_, b) = render(&far, &far_camera);
    let total: f32 = a.pixels.iter().map(|&p| luminance(p)).sum();
    let difference: f32 = a.pixels.iter().zip(&b.pixels).map(|(&p, &q)| (luminance(p) - luminance(q)).abs()).sum();
    assert!(difference / total < 0.01, "relative difference {}", difference / total);
}

#[test]
fn raster_without_primitive_index_draws_the_same_image() {
    // The demo, and draws of every kind (blended ones link their layers through the same raster).
    let demo = demo_scene();
    let every_kind = draws_of_every_kind();
    for (scene, camera) in [(&demo, &demo.cameras[0]), (&every_kind.0, &every_kind.1)] {
        let frame = |ctx: GpuContext| {
            let mut r = manylights::renderer::Renderer::new(ctx, scene, config(WIDTH, HEIGHT, LightMethod::Brute)).expect("renderer");
            r.render(camera).expect("frame");
            r.read_hdr().expect("hdr")
        };
        let indexed = GpuContext::new().expect("a GPU adapter");
        assert!(
            indexed.features.contains(wgpu::Features::PRIMITIVE_INDEX),
            "this test compares the indexed raster with the pulled one, and needs an adapter with primitive_index (lavapipe has it)"
        );
        let pulled = GpuContext::without(wgpu::Features::PRIMITIVE_INDEX).expect("a GPU adapter");
        assert!(!pulled.features.contains(wgpu::Features::PRIMITIVE_INDEX));
        let (a, b) = (frame(indexed), frame(pulled));
        assert_eq!(max_abs_difference(&a, &b), 0.0, "indexed and pulled rasters draw different images");
    }
}

/// Draws of every kind a raster pass orders: opaque, alpha-masked, double-sided, mirrored, blended
/// and moving (with motion blur, whose velocity pass draws the moving ones again).
fn draws_of_every_kind() -> (manylights::scene::Scene, Camera) {
    use glam::{Mat4, Quat, Vec4};
    use manylights::scene::{AlphaMode, Instance, Material};
    let (mut scene, camera) = wall_scene(vec![point_light(Vec3::new(0.5, 0.5, 2.0), 3.0, 6.0)]);
    scene.ambient = Vec3::splat(0.2);
    let material = |color: Vec4, alpha_mode: AlphaMode, double_sided: bool| Material {
        base_color_factor: color,
        alpha_mode,
        double_sided,
        base_color_texture: Some(TextureRef::new(0, Wrap::Repeat, Wrap::Repeat)),
        ..Default::default()
    };
    scene.textures = vec![Texture {
        name: "checker".into(),
        width: 2,
        height: 2,
        rgba8: vec![255, 255, 255, 255, 90, 90, 90, 40, 90, 90, 90, 40, 255, 255, 255, 255],
    }];
    scene.materials.extend([
        material(Vec4::new(0.9, 0.3, 0.2, 1.0), AlphaMode::Mask { cutoff: 0.5 }, false),
        material(Vec4::new(0.2, 0.8, 0.3, 1.0), AlphaMode::Opaque, true),
        material(Vec4::new(0.3, 0.4, 1.0, 0.5), AlphaMode::Blend, false),
    ]);
    for (material, (x, y), z, mirrored) in
        [(1, (-1.2, 0.6), 0.5, false), (2, (1.2, 0.6), 0.5, true), (3, (0.0, -0.7), 1.0, false), (0, (0.0, 0.7), 0.8, false)]
    {
        let mut quad = quad_mesh();
        quad.primitives[0].material = material;
        scene.meshes.push(quad);
        let scale = Vec3::new(if mirrored { -0.5 } else { 0.5 }, 0.5, 1.0);
        let world_from_local = Mat4::from_scale_rotation_translation(scale, Quat::from_rotation_y(0.3), Vec3::new(x, y, z));
        scene.instances.push(Instance { mesh: scene.meshes.len() - 1, world_from_local });
    }
    let last = scene.instances.len() - 1;
    fly(&mut scene, last, Vec3::new(-0.3, 0.7, 0.8), Vec3::new(0.3, 0.7, 0.8));
    (scene, camera)
}

#[test]
fn indirect_draws_and_a_call_per_draw_draw_the_same_image_in_every_pipeline() {
    let (scene, camera) = draws_of_every_kind();
    let indirect = GpuContext::new().expect("a GPU adapter");
    assert!(
        indirect.features.contains(wgpu::Features::INDIRECT_FIRST_INSTANCE),
        "this test compares indirect draws with direct ones, and needs an adapter with indirect_first_instance (lavapipe has it)"
    );
    let direct = GpuContext::without(wgpu::Features::INDIRECT_FIRST_INSTANCE).expect("a GPU adapter");
    assert!(!direct.features.contains(wgpu::Features::INDIRECT_FIRST_INSTANCE));
    let blur = manylights::settings::MotionBlur { shutter: 1.0, samples: 8, max_length: 16.0 };
    for pipeline in manylights::settings::PipelineKind::ALL {
        let config = manylights::settings::RenderConfig {
            pipeline,
            post: manylights::settings::PostSettings { motion_blur: Some(blur), ..still_post() },
            ..config(WIDTH, HEIGHT, LightMethod::Brute)
        };
        // The displayed image: motion blur is part of the post chain.
        let frame = |ctx: &GpuContext, scene: &manylights::scene::Scene, config: &manylights::settings::RenderConfig| {
            let mut r = manylights::renderer::Renderer::new(ctx.clone(), scene, config.clone()).expect("renderer");
            r.time = 0.05;
            r.render(&camera).expect("frame");
            r.read_ldr().expect("ldr")
        };
        let name = pipeline.name();
        let image = frame(&indirect, &scene, &config);
        assert!(image.pixels == frame(&direct, &scene, &config).pixels, "{name}: indirect and direct draws differ");
        let differing =
            |other: manylights::renderer::Image<[u8; 4]>| image.pixels.iter().zip(&other.pixels).filter(|(p, q)| p != q).count();
        let wall_only = manylights::scene::Scene { instances: scene.instances[..1].to_vec(), animation: None, ..scene.clone() };
        let quads = differing(frame(&indirect, &wall_only, &config));
        assert!(quads > 2000, "{name}: the quads before the wall changed only {quads} pixels");
        let still = manylights::settings::RenderConfig { post: still_post(), ..config.clone() };
        let smeared = differing(frame(&indirect, &scene, &still));
        assert!(smeared > 100, "{name}: motion blur changed only {smeared} pixels: the moving draws were not drawn again");
    }
}

#[test]
fn a_blended_instance_that_animation_turns_mirrored_is_drawn() {
    // A single-sided blended pane whose animation scales it through −1 along x: mirrored at the time
    // rendered, a raster state it did not have at load.
    use glam::{Mat4, Quat, Vec4};
    use manylights::scene::animation::{Animation, Channel, Interpolation, Node, Property, Trs};
    use manylights::scene::{AlphaMode, Instance, Material};
    let (mut scene, camera) = wall_scene(Vec::new());
    scene.ambient = Vec3::splat(0.5);
    scene.materials.push(Material { base_color_factor: Vec4::new(0.1, 0.3, 1.0, 0.6), alpha_mode: AlphaMode::Blend, ..Default::default() });
    let mut pane = quad_mesh();
    pane.primitives[0].material = 1;
    scene.meshes.push(pane);
    let place = Vec3::new(0.0, 0.0, 1.0);
    scene.instances.push(Instance { mesh: 1, world_from_local: Mat4::from_translation(place) });
    scene.animation = Some(Animation {
        name: "turn".into(),
        nodes: vec![Node::from_trs(None, Trs { translation: place, rotation: Quat::IDENTITY, scale: Vec3::ONE })],
        channels: vec![Channel {
            node: 0,
            property: Property::Scale,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![Vec4::new(1.0, 1.0, 1.0, 0.0), Vec4::new(-1.0, 1.0, 1.0, 0.0)],
        }],
        instances: vec![(1, 0)],
        duration: 1.0,
    });
    let mut r =
        manylights::renderer::Renderer::new(GpuContext::new().expect("a GPU adapter"), &scene, config(WIDTH, HEIGHT, LightMethod::Brute))
            .expect("renderer");
    r.time = 0.9;
    r.render(&camera).expect("frame");
    let centre = pixel(&r.read_hdr().expect("hdr"), WIDTH / 2, HEIGHT / 2);
    assert!(centre[2] > 1.25 * centre[0], "the mirrored pane does not tint the wall: {centre:?}");
}

#[test]
fn draws_partly_in_view_are_drawn_and_the_view_leaves_out_only_unseen_ones() {
    // Quads on a grid wider and taller than the view, some straddling each of its edges, and more
    // beside and behind the eye: a draw each, or all in one draw, which no view leaves out. The
    // images must be equal in every pipeline.
    use glam::{Mat4, Vec4};
    use manylights::scene::{Instance, Material, Mesh, Primitive, Scene};
    let mut places: Vec<Vec3> = Vec::new();
    // At 3 m the view reaches ±3.08 m across and ±1.73 m up: the outer columns (±3.2 m) and rows
    // (±1.6 m) of 0.6 m quads straddle its edges.
    for i in -8..=8 {
        for j in -5..=5 {
            places.push(Vec3::new(i as f32 * 0.8, j as f32 * 0.8, -3.0));
        }
    }
    places.extend([Vec3::new(0.0, 0.0, 3.0), Vec3::new(10.0, 0.0, -1.0), Vec3::new(-10.0, 2.0, -1.0), Vec3::new(0.0, 9.0, -2.0)]);
    let placed = |p: Vec3| Mat4::from_translation(p) * Mat4::from_scale(Vec3::splat(0.3));
    let material = Material { base_color_factor: Vec4::new(0.8, 0.5, 0.3, 1.0), ..Default::default() };
    let base = Scene {
        materials: vec![material],
        ambient: Vec3::splat(0.4),
        lights: vec![point_light(Vec3::new(0.5, 0.5, -1.0), 3.0, 8.0)],
        ..Default::default()
    };
    let apart = Scene {
        meshes: vec![quad_mesh()],
        instances: places.iter().map(|&p| Instance { mesh: 0, world_from_local: placed(p) }).collect(),
        ..base.clone()
    };
    let quad = quad_mesh().primitives.remove(0);
    let mut together = Primitive { vertices: Vec::new(), indices: Vec::new(), material: 0 };
    for &p in &places {
        let first = together.vertices.len() as u32;
        together.vertices.extend(
            quad.vertices
                .iter()
                .map(|v| manylights::scene::Vertex { position: placed(p).transform_point3(Vec3::from(v.position)).to_array(), ..*v }),
        );
        together.indices.extend(quad.indices.iter().map(|i| first + i));
    }
    let together = Scene {
        meshes: vec![Mesh { name: "together".into(), primitives: vec![together] }],
        instances: vec![Instance { mesh: 0, world_from_local: Mat4::IDENTITY }],
        ..base
    };
    let camera = Camera::look_at("ahead", Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 60f32.to_radians(), 0.1);
    for pipeline in manylights::settings::PipelineKind::ALL {
        let config = manylights::settings::RenderConfig { pipeline, ..config(WIDTH, HEIGHT, LightMethod::Brute) };
        let mut renderer =
            manylights::renderer::Renderer::new(GpuContext::new().expect("a GPU adapter"), &apart, config.clone()).expect("renderer");
        renderer.render(&camera).expect("frame");
        let a = renderer.read_hdr().expect("hdr");
        let drawn = renderer.scene.drawn_count();
        // 9 columns × 5 rows reach into the view; the rest lie outside it.
        assert!((40..=50).contains(&drawn), "{}: {drawn} of {} draws drawn", pipeline.name(), places.len());
        let b = render_with(&together, &camera, config).1;
        assert_eq!(max_abs_difference(&a, &b), 0.0, "{}: a draw each differs from one draw", pipeline.name());
        // The grid's gaps show the background: the view holds both.
        let quad = luminance(pixel(&a, WIDTH / 2, HEIGHT / 2));
        let gaps = a.pixels.iter().filter(|p| (luminance(**p) - quad).abs() > 0.1 * quad).count();
        assert!(gaps > a.pixels.len() / 20 && gaps < a.pixels.len() * 3 / 4, "{}: {gaps} pixels unlike a quad's", pipeline.name());
    }
    // An instance flying in from outside the view is drawn where it arrives: its bounds move too.
    let mut flying = apart.clone();
    flying.materials.push(Material { base_color_factor: Vec4::new(0.0, 1.0, 0.0, 1.0), unlit: true, ..Default::default() });
    let mut green = quad_mesh();
    green.primitives[0].material = 1;
    flying.meshes.push(green);
    flying.instances.push(Instance { mesh: 1, world_from_local: placed(Vec3::new(10.0, 0.0, -2.0)) });
    // At 0.095 s of 0.1 it is 0.025 m right of the view's centre.
    fly(&mut flying, places.len(), Vec3::new(10.0, 0.0, -2.0), Vec3::new(-0.5, 0.0, -2.0));
    let mut renderer =
        manylights::renderer::Renderer::new(GpuContext::new().expect("a GPU adapter"), &flying, config(WIDTH, HEIGHT, LightMethod::Brute))
            .expect("renderer");
    renderer.time = 0.095;
    renderer.render(&camera).expect("frame");
    let centre = pixel(&renderer.read_hdr().expect("hdr"), WIDTH / 2, HEIGHT / 2);
    assert!(centre[1] > 0.9 && centre[0] < 0.1, "the quad that flew into the view is not drawn: {centre:?}");
}

#[test]
fn sky_pixels_do_not_show_triangles_of_earlier_frames() {
    // Ids are not cleared between frames: a pixel that turns to sky must be shaded as sky, not as
    // the triangle an earlier frame left there.
    let scene = demo_scene();
    let ground = &scene.cameras[0];
    let eye = ground.world_from_view.transform_point3(Vec3::ZERO);
    let sky = Camera::look_at("sky", eye, eye + Vec3::new(0.3, 1.0, 0.2), 1.0, 0.1);
    let mut r = renderer(&scene, config(WIDTH, HEIGHT, LightMethod::Brute));
    r.render(ground).expect("frame");
    r.render(&sky).expect("frame");
    let after_ground = r.read_hdr().expect("hdr");
    let (_, fresh) = render(&scene, &sky);
    // Shading by stale ids instead of depth fails here by 4.0 (checked when this test was written).
    assert_eq!(max_abs_difference(&after_ground, &fresh), 0.0);
}

/// `KHR_texture_transform` moves a texture as the extension says: a wall whose texture's coordinates
/// go through an offset, a rotation and a scale shows what a wall whose vertices carry the transformed
/// coordinates shows, in every pipeline, and not what the untransformed texture shows.
#[test]
fn texture_transforms_move_the_texture_as_transformed_coordinates_do() {
    use glam::{Affine2, Mat2, Vec2};
    use manylights::settings::{PipelineKind, RenderConfig};
    let checker: Vec<u8> = (0..8 * 8u32)
        .flat_map(|i| {
            let (x, y) = (i % 8, i / 8);
            [(x * 32 + 16) as u8, (y * 32 + 16) as u8, if (x + y) % 2 == 0 { 255 } else { 0 }, 255]
        })
        .collect();
    let (sin, cos) = 0.5f32.sin_cos();
    let linear = Mat2::from_cols(Vec2::new(cos, sin), Vec2::new(-sin, cos)) * Mat2::from_diagonal(Vec2::new(4.0, 2.5));
    let transform = Affine2::from_mat2_translation(linear, Vec2::new(0.1, 0.3));
    let wall = |uv_transform: Affine2, coordinates: Affine2| {
        let (mut scene, camera) = wall_scene(vec![]);
        scene.textures = vec![Texture { name: "checker".into(), width: 8, height: 8, rgba8: checker.clone() }];
        scene.materials[0].base_color_factor = glam::Vec4::new(0.0, 0.0, 0.0, 1.0);
        scene.materials[0].emissive_factor = Vec3::ONE;
        scene.materials[0].emissive_texture = Some(TextureRef { uv_transform, ..TextureRef::new(0, Wrap::Repeat, Wrap::Repeat) });
        for v in &mut scene.meshes[0].primitives[0].vertices {
            let uv = coordinates.transform_point2(Vec2::new(v.u, v.v));
            (v.u, v.v) = (uv.x, uv.y);
        }
        (scene, camera)
    };
    let (transformed, camera) = wall(transform, Affine2::IDENTITY);
    let (twin, _) = wall(Affine2::IDENTITY, transform);
    let (plain, _) = wall(Affine2::IDENTITY, Affine2::IDENTITY);
    for pipeline in PipelineKind::ALL {
        let frame = |scene| render_with(scene, &camera, RenderConfig { pipeline, ..config(WIDTH, HEIGHT, LightMethod::Off) }).1;
        let (got, expected) = (frame(&transformed), frame(&twin));
        let difference = max_abs_difference(&got, &expected);
        assert!(difference < 2e-3, "{}: {difference} from the wall with transformed coordinates", pipeline.name());
        assert!(max_abs_difference(&got, &frame(&plain)) > 0.5, "{}: the transform changed nothing", pipeline.name());
    }
}
