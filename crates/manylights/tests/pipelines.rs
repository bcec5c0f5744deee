//! The pipelines share one shading core: within each pipeline the enumeration methods give the
//! brute-force image (linear HDR, max abs difference ≤ 1e-3), and the pipelines give the same image
//! up to their derivatives and G-buffer precision (`PIPELINE_*_TOLERANCE`).

mod common;

use common::*;
use manylights::{
    renderer::Image,
    scene::{demo::demo_scene, generators, generators::ScatterDecals, generators::ScatterLights, Scene},
    settings::RaySettings,
    settings::RenderConfig,
    settings::{DecalMethod, LightMethod, PipelineKind},
};

const TOLERANCE: f32 = 1e-3;

/// How far the other pipelines may stray from the visibility buffer, in linear HDR (per pixel, the
/// largest channel difference). Surfaces, lights and decals are the same; what differs: forward and
/// G-buffer fragments take texture gradients from 2×2 pixel quads where the compute resolve uses exact
/// neighbouring rays (a mip level can differ by a fraction, mostly at edges and on steep surfaces), and
/// the G-buffer stores albedo and roughness-metallic in 8 bits and normals in 2 × 16, and gives decals
/// gradients from the tangent plane. Measured on lavapipe (demo, 300 lights, 300 decals, 128×72,
/// radiance up to ≈ 4): forward mean 0.0006, 99.5th percentile 0.013; deferred mean 0.0016, 99.5th
/// percentile 0.019; the bounds leave about 2.5× room.
const PIPELINE_MEAN_TOLERANCE: f32 = 0.004;
const PIPELINE_P995_TOLERANCE: f32 = 0.05;

fn scene_with(lights: usize, decals: usize, seed: u64) -> Scene {
    let mut scene = demo_scene();
    generators::add_scattered_lights(&mut scene, &ScatterLights { count: lights, seed, ..Default::default() }).unwrap();
    generators::add_scattered_decals(&mut scene, &ScatterDecals { count: decals, seed, size: None }).unwrap();
    scene
}

fn render(scene: &Scene, config: RenderConfig) -> Image<[f32; 4]> {
    render_with(scene, &scene.cameras[0], config).1
}

/// On a device without subgroup operations, where every walk is per invocation.
fn render_without_subgroups(scene: &Scene, config: RenderConfig) -> Image<[f32; 4]> {
    let ctx = manylights::gpu::GpuContext::without(wgpu::Features::SUBGROUP).expect("a GPU adapter");
    render_on(ctx, scene, &scene.cameras[0], config).1
}

fn configured(pipeline: PipelineKind, lights: LightMethod, decals: DecalMethod, (width, height): (u32, u32)) -> RenderConfig {
    RenderConfig { pipeline, decal_method: decals, ..config(width, height, lights) }
}

/// Per-pixel differences (largest channel), sorted.
fn sorted_differences(a: &Image<[f32; 4]>, b: &Image<[f32; 4]>) -> Vec<f32> {
    let mut d: Vec<f32> = a.pixels.iter().zip(&b.pixels).map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, f32::max)).collect();
    d.sort_by(f32::total_cmp);
    d
}

/// Within `pipeline`, each pair of methods gives the brute-force image. Fragments walk the decals' BVH
/// a subgroup at a time where the device has subgroup operations (`passes::query_walks`), so the
/// forward pipeline also runs on a device without them.
fn assert_methods_equal_brute_force(pipeline: PipelineKind, methods: &[(LightMethod, DecalMethod)], seed: u64) {
    let size = (64, 36);
    let scene = scene_with(300, 300, seed);
    let brute = render(&scene, configured(pipeline, LightMethod::Brute, DecalMethod::Brute, size));
    let lit = brute.pixels.iter().filter(|p| p[0] + p[1] + p[2] > 0.0).count();
    assert!(lit > brute.pixels.len() / 2, "the reference image is mostly black");
    let ctx = manylights::gpu::GpuContext::new().expect("a GPU adapter");
    assert!(
        ctx.features.contains(wgpu::Features::SUBGROUP),
        "{} has no subgroup operations: the subgroup walks go untested",
        ctx.describe()
    );
    for &(lights, decals) in methods {
        let config = configured(pipeline, lights, decals, size);
        let mut images = vec![(render(&scene, config.clone()), "subgroups")];
        if pipeline == PipelineKind::Forward {
            images.push((render_without_subgroups(&scene, config), "no subgroups"));
        }
        for (image, device) in images {
            let difference = max_abs_difference(&brute, &image);
            assert!(
                difference <= TOLERANCE,
                "{}, lights {}, decals {}, {device}: max abs difference {difference}",
                pipeline.name(),
                lights.name(),
                decals.name()
            );
        }
    }
}

const ACCELERATED: [(LightMethod, DecalMethod); 3] =
    [(LightMethod::Bvh, DecalMethod::Bvh), (LightMethod::Clustered, DecalMethod::Clustered), (LightMethod::Bvh, DecalMethod::Clustered)];

#[test]
fn visbuffer_methods_equal_brute_force() {
    assert_methods_equal_brute_force(PipelineKind::Visbuffer, &ACCELERATED, 6);
}

#[test]
fn deferred_methods_equal_brute_force() {
    assert_methods_equal_brute_force(PipelineKind::Deferred, &ACCELERATED, 5);
}

#[test]
fn forward_methods_equal_brute_force() {
    assert_methods_equal_brute_force(PipelineKind::Forward, &ACCELERATED, 3);
}

/// Deferred decals blend in draw order and in the G-buffer's precision, where the shading core blends
/// weighted-OIT sums in f32 (`passes/deferred_decals.wgsl` lists the differences). Where decals do not
/// overlap, only precision remains: measured on lavapipe (demo, 150 decals of one layer, 128×72) mean
/// 0.00013, 99.5th percentile 0.0046 against the decals' own effect of mean 0.0082; the bounds leave
/// about 3× room, and the decals' effect must be over 10× the difference.
const DEFERRED_DECALS_MEAN_TOLERANCE: f32 = 0.0004;
const DEFERRED_DECALS_P995_TOLERANCE: f32 = 0.015;

/// Shaders with decals or reflections are compiled to SPIR-V by manylights on Vulkan, without
/// zeroing the decal layers' sums or the closest-hit stack (`gpu/spirv.rs`); wgpu compiles them
/// elsewhere. Both give the same image in every pipeline, with every decal method, and with
/// reflections of every surface.
#[test]
fn images_from_our_spirv_equal_images_from_wgpus() {
    let size = (64, 36);
    let scene = scene_with(50, 400, 5);
    let ctx = manylights::gpu::GpuContext::new().expect("a GPU adapter");
    assert!(
        ctx.features.contains(wgpu::Features::PASSTHROUGH_SHADERS),
        "{} takes no passthrough shaders: our SPIR-V goes untested",
        ctx.describe()
    );
    let reflecting = |config: RenderConfig| RenderConfig {
        rays: RaySettings { reflection_bounces: 2, reflection_roughness: 1.0, ..Default::default() },
        ..config
    };
    // (configuration, one without the effect under test, which must look different)
    let mut cases = Vec::new();
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        for decals in [DecalMethod::Bvh, DecalMethod::Clustered, DecalMethod::Brute] {
            let config = configured(pipeline, LightMethod::Bvh, decals, size);
            cases.push((config.clone(), RenderConfig { decal_method: DecalMethod::Off, ..config.clone() }));
            if decals == DecalMethod::Bvh {
                cases.push((reflecting(config.clone()), config));
            }
        }
    }
    let config = configured(PipelineKind::Deferred, LightMethod::Bvh, DecalMethod::DeferredDecals, size);
    cases.push((config.clone(), RenderConfig { decal_method: DecalMethod::Off, ..config }));
    for (config, without) in cases {
        let label =
            format!("{:?} with {:?} decals, {} reflection bounces", config.pipeline, config.decal_method, config.rays.reflection_bounces);
        let ours = render(&scene, config.clone());
        let wgpus = manylights::gpu::GpuContext::without(wgpu::Features::PASSTHROUGH_SHADERS).unwrap();
        let wgpus = render_on(wgpus, &scene, &scene.cameras[0], config).1;
        assert!(max_abs_difference(&ours, &render(&scene, without)) > 0.01, "{label}: the effect is not in view");
        assert_eq!(max_abs_difference(&ours, &wgpus), 0.0, "{label}: our SPIR-V and wgpu's differ");
    }
}

#[test]
fn deferred_decals_match_the_shading_cores_decals_where_both_apply() {
    let size = (128, 72);
    let mut scene = scene_with(40, 150, 9);
    for decal in &mut scene.decals {
        decal.layer = 0;
    }
    let config = |decals| configured(PipelineKind::Deferred, LightMethod::Brute, decals, size);
    let bvh = render(&scene, config(DecalMethod::Bvh));
    let deferred = render(&scene, config(DecalMethod::DeferredDecals));
    let bare = render(&scene, config(DecalMethod::Off));
    let mean = |d: &[f32]| d.iter().sum::<f32>() / d.len() as f32;
    let effect = mean(&sorted_differences(&bvh, &bare));
    let d = sorted_differences(&bvh, &deferred);
    let p995 = d[d.len() * 995 / 1000];
    eprintln!("deferred decals vs bvh decals: mean {}, 99.5th percentile {p995}; decals' effect: mean {effect}", mean(&d));
    assert!(effect > 10.0 * mean(&d), "the decals barely change the image (mean {effect})");
    assert!(mean(&d) <= DEFERRED_DECALS_MEAN_TOLERANCE, "mean difference {}", mean(&d));
    assert!(p995 <= DEFERRED_DECALS_P995_TOLERANCE, "99.5th percentile difference {p995}");
}

/// A decal box around the eye has no front face in view: deferred decals draw it inside out, and it
/// still reaches the surface it projects onto.
#[test]
fn deferred_decals_reach_surfaces_from_boxes_around_the_eye() {
    let (mut scene, camera) = ambient_wall();
    scene.materials.push(manylights::scene::Material {
        base_color_factor: glam::Vec4::new(0.9, 0.1, 0.1, 1.0),
        metallic_factor: 0.0,
        ..Default::default()
    });
    // From z = −0.5, behind the wall, to z = 4.5, behind the camera at z = 4.
    let box_around_eye = glam::Affine3A::from_scale_rotation_translation(
        glam::Vec3::new(3.0, 3.0, 5.0),
        glam::Quat::IDENTITY,
        glam::Vec3::new(0.0, 0.0, 2.0),
    );
    scene.decals.push(manylights::scene::Decal { world_from_decal: box_around_eye, material: 1, layer: 0, weight: 1.0 });
    let config = |decals| configured(PipelineKind::Deferred, LightMethod::Off, decals, (64, 36));
    let (_, bvh) = render_with(&scene, &camera, config(DecalMethod::Bvh));
    let (_, deferred) = render_with(&scene, &camera, config(DecalMethod::DeferredDecals));
    let centre = |image: &Image<[f32; 4]>| pixel(image, 32, 18);
    assert!(centre(&bvh)[0] > 0.8 && centre(&bvh)[1] < 0.15, "the decal does not cover the wall: {:?}", centre(&bvh));
    let difference = max_abs_difference(&bvh, &deferred);
    assert!(difference <= 0.01, "deferred decals from a box around the eye: max abs difference {difference} from bvh decals");
}

#[test]
fn deferred_decals_outside_the_deferred_pipeline_are_an_error() {
    let scene = scene_with(0, 10, 1);
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Forward] {
        let ctx = manylights::gpu::GpuContext::new().expect("a GPU adapter");
        let config = configured(pipeline, LightMethod::Brute, DecalMethod::DeferredDecals, (32, 18));
        let error = manylights::renderer::Renderer::new(ctx, &scene, config).err().expect("an invalid combination");
        let message = error.to_string();
        assert!(message.contains("--pipeline deferred") && message.contains(pipeline.name()), "{message}");
    }
}

/// `off` is the baseline of the method comparison: the image of the scene without local lights, or
/// without decals.
#[test]
fn off_renders_the_scene_without_lights_or_decals() {
    let size = (64, 36);
    let scene = scene_with(300, 300, 8);
    for pipeline in PipelineKind::ALL {
        let mut unlit = scene.clone();
        unlit.lights.clear();
        let mut undecaled = scene.clone();
        undecaled.decals.clear();
        for (without, lights, decals) in
            [(&unlit, LightMethod::Off, DecalMethod::Brute), (&undecaled, LightMethod::Brute, DecalMethod::Off)]
        {
            let expected = render(without, configured(pipeline, LightMethod::Brute, DecalMethod::Brute, size));
            let image = render(&scene, configured(pipeline, lights, decals, size));
            let difference = max_abs_difference(&expected, &image);
            assert!(difference <= TOLERANCE, "{}, lights {}, decals {}: {difference}", pipeline.name(), lights.name(), decals.name());
            let full = render(&scene, configured(pipeline, LightMethod::Brute, DecalMethod::Brute, size));
            assert!(
                max_abs_difference(&full, &image) > 0.05,
                "turning {} off changed nothing",
                if lights == LightMethod::Off { "lights" } else { "decals" }
            );
        }
    }
}

#[test]
fn pipelines_agree_with_the_visibility_buffer() {
    let size = (128, 72);
    let scene = scene_with(300, 300, 4);
    let visbuffer = render(&scene, configured(PipelineKind::Visbuffer, LightMethod::Brute, DecalMethod::Brute, size));
    // Not trivially equal because both are blank: the image has structure.
    let bright = visbuffer.pixels.iter().filter(|p| luminance(**p) > 0.05).count();
    assert!(bright > visbuffer.pixels.len() / 2, "the image is mostly dark");
    for pipeline in [PipelineKind::Forward, PipelineKind::Deferred] {
        let image = render(&scene, configured(pipeline, LightMethod::Brute, DecalMethod::Brute, size));
        let d = sorted_differences(&visbuffer, &image);
        let mean = d.iter().sum::<f32>() / d.len() as f32;
        let p995 = d[d.len() * 995 / 1000];
        eprintln!("{} vs visibility buffer: mean {mean}, 99.5th percentile {p995}, max {}", pipeline.name(), d[d.len() - 1]);
        assert!(mean <= PIPELINE_MEAN_TOLERANCE, "{}: mean difference {mean}", pipeline.name());
        assert!(p995 <= PIPELINE_P995_TOLERANCE, "{}: 99.5th percentile difference {p995}", pipeline.name());
    }
}

/// The daylight sky lights every pipeline alike: its image-based lighting, its sun's traced shadows
/// and traced reflections of it.
#[test]
fn pipelines_agree_under_the_daylight_sky() {
    let size = (128, 72);
    let mut scene = demo_scene();
    manylights::scene::sky::light_with_sky(&mut scene, manylights::settings::Sky::Daylight);
    let rays = RaySettings { sun_shadows: manylights::settings::SunShadows::Hard, reflection_bounces: 1, ..RaySettings::default() };
    let render_in = |pipeline| render(&scene, RenderConfig { rays, ..configured(pipeline, LightMethod::Brute, DecalMethod::Brute, size) });
    let visbuffer = render_in(PipelineKind::Visbuffer);
    for pipeline in [PipelineKind::Forward, PipelineKind::Deferred] {
        let d = sorted_differences(&visbuffer, &render_in(pipeline));
        let mean = d.iter().sum::<f32>() / d.len() as f32;
        let p995 = d[d.len() * 995 / 1000];
        eprintln!("{} vs visibility buffer under the sky: mean {mean}, 99.5th percentile {p995}", pipeline.name());
        assert!(mean <= PIPELINE_MEAN_TOLERANCE, "{}: mean difference {mean}", pipeline.name());
        assert!(p995 <= PIPELINE_P995_TOLERANCE, "{}: 99.5th percentile difference {p995}", pipeline.name());
    }
}
