//! The hardware ray backend (`--ray-backend hardware`: wgpu's ray queries) gives the software BVHs'
//! image and the brute-force one for lights and decals (acceleration structures of boxes,
//! `accel/hardware.rs`; linear HDR, max abs difference ≤ 1e-3) in every pipeline, built once or every
//! frame, grouped and spinning, at reflection hits and with no volumes at all; and the software
//! hierarchy's image for rays against the scene's triangles (`rays/hardware.rs`): sun shadows hard and
//! soft, shadowed lamps, reflections and restir's rays, through alpha-masked holes, past moving
//! instances and deforming meshes. `auto` takes ray queries where the GPU runs them and the software
//! BVHs where a CPU emulates them (lavapipe) or none exist.
//!
//! Mesa 25's lavapipe has ray queries (`scripts/ensure-vulkan.sh` installs it); on an adapter without
//! them the tests that need them fail with that said, rather than pass without testing anything.

mod common;

use common::*;
use manylights::{
    gpu::GpuContext,
    plan::{Capabilities, RayQueries, RayTracer},
    renderer::{Image, Renderer},
    scene::{
        deform::{Deformer, Wave},
        demo::demo_scene,
        generators::{self, ScatterDecals, ScatterLights},
        AlphaMode, ParticleSettings, Scene, Vertex,
    },
    settings::{
        BvhBuild, DecalMethod, DirectLighting, LightMethod, ParticleMethod, PipelineKind, RayBackend, RaySettings, RenderConfig, SunShadows,
    },
    Error,
};

const TOLERANCE: f32 = 1e-3;

fn ray_queries() -> GpuContext {
    let ctx = GpuContext::new().expect("a GPU adapter");
    assert!(ctx.has_ray_queries(), "{} has no ray queries: install Mesa 25's lavapipe (scripts/ensure-vulkan.sh)", ctx.describe());
    ctx
}

fn with_decals_and_lights(mut scene: Scene, decals: usize, lights: usize, seed: u64) -> Scene {
    generators::add_scattered_decals(&mut scene, &ScatterDecals { count: decals, seed, size: None }).unwrap();
    generators::add_scattered_lights(&mut scene, &ScatterLights { count: lights, seed: seed + 1, ..Default::default() }).unwrap();
    scene
}

/// Lights and decals found the same way (`method`: brute force or bvh), built as `build` says,
/// traced by `backend`.
fn backend_config(pipeline: PipelineKind, bvh: bool, build: BvhBuild, backend: RayBackend) -> RenderConfig {
    let (lights, decals) = if bvh { (LightMethod::Bvh, DecalMethod::Bvh) } else { (LightMethod::Brute, DecalMethod::Brute) };
    RenderConfig {
        pipeline,
        decal_method: decals,
        light_bvh_build: build,
        decal_bvh_build: build,
        rays: RaySettings { backend, ..config(96, 54, lights).rays },
        ..config(96, 54, lights)
    }
}

fn render_at(ctx: &GpuContext, scene: &Scene, config: RenderConfig, time: f32) -> (Image<[f32; 4]>, RayTracer) {
    let mut r = Renderer::new(ctx.clone(), scene, config).expect("renderer");
    r.time = time;
    r.render(&scene.cameras[0]).expect("frame");
    (r.read_hdr().expect("hdr"), r.ray_tracer())
}

/// In every pipeline: brute force, the software BVHs and the hardware back end, each built once and
/// every frame, give the same image at `time`.
fn assert_backends_agree(scene: &Scene, time: f32) {
    let ctx = ray_queries();
    for pipeline in PipelineKind::ALL {
        let (brute, _) = render_at(&ctx, scene, backend_config(pipeline, false, BvhBuild::CpuOnce, RayBackend::Software), time);
        assert!(brute.pixels.iter().filter(|p| luminance(**p) > 0.0).count() > brute.pixels.len() / 2, "the reference is mostly black");
        for build in [BvhBuild::CpuOnce, BvhBuild::GpuEveryFrame] {
            let mut images = Vec::new();
            for backend in [RayBackend::Software, RayBackend::Hardware] {
                let (image, tracer) = render_at(&ctx, scene, backend_config(pipeline, true, build, backend), time);
                assert_eq!(tracer.name(), backend.name(), "{backend} was asked for");
                let difference = max_abs_difference(&brute, &image);
                assert!(
                    difference <= TOLERANCE,
                    "{} {build:?} {backend}: max abs difference {difference} from brute force",
                    pipeline.name()
                );
                images.push(image);
            }
            let difference = max_abs_difference(&images[0], &images[1]);
            assert!(difference <= TOLERANCE, "{} {build:?}: hardware differs from software by {difference}", pipeline.name());
        }
    }
}

#[test]
fn hardware_lights_and_decals_give_the_software_and_brute_force_image_in_every_pipeline() {
    let scene = with_decals_and_lights(demo_scene(), 600, 400, 31);
    assert_backends_agree(&scene, 0.0);
}

/// Groups placed by spinning instances: the top level is rebuilt for the time, and the query enters
/// each instance's space.
#[test]
fn hardware_queries_follow_spinning_groups() {
    let mut scene = with_decals_and_lights(demo_scene(), 600, 400, 9);
    generators::group_for_animation(&mut scene, 6, 2).unwrap();
    assert_backends_agree(&scene, 0.7);
    // Frames rendered back to back rebuild the top level as the instances move.
    let ctx = ray_queries();
    let config = backend_config(PipelineKind::Visbuffer, true, BvhBuild::CpuOnce, RayBackend::Hardware);
    let mut r = Renderer::new(ctx.clone(), &scene, config).unwrap();
    r.render_frames(&scene.cameras[0], 12).unwrap();
    let time = 11.0 * manylights::renderer::FRAME_INTERVAL;
    let (expected, _) =
        render_at(&ctx, &scene, backend_config(PipelineKind::Visbuffer, false, BvhBuild::CpuOnce, RayBackend::Software), time);
    let difference = max_abs_difference(&expected, &r.read_hdr().unwrap());
    assert!(difference <= TOLERANCE, "frame 12 differs by {difference} from brute force at its time");
}

/// Particles as exact lights: their boxes, written every frame, are packed and their bottom level
/// rebuilt; frames rendered back to back, the particles moving, give the software BVH's image.
#[test]
fn hardware_queries_find_moving_particle_lights() {
    let mut scene = demo_scene();
    scene.particles = Some(ParticleSettings {
        count: 3000,
        seed: 3,
        emitters: vec![(glam::Vec3::new(0.0, 0.1, 0.0), 3.0), (glam::Vec3::new(2.0, 0.1, -2.0), 2.0)],
        ..ParticleSettings::default()
    });
    let ctx = ray_queries();
    let [software, hardware] = [RayBackend::Software, RayBackend::Hardware].map(|backend| {
        let config = backend_config(PipelineKind::Visbuffer, true, BvhBuild::CpuOnce, backend);
        let mut r = Renderer::new(ctx.clone(), &scene, RenderConfig { particle_method: ParticleMethod::Bvh, ..config }).unwrap();
        assert_eq!(r.shading_methods().hardware_lights, backend == RayBackend::Hardware);
        r.render_frames(&scene.cameras[0], 3).unwrap();
        r.read_hdr().unwrap()
    });
    let difference = max_abs_difference(&software, &hardware);
    assert!(difference <= TOLERANCE, "particle lights: hardware differs from software by {difference}");
}

/// Reflection hits are shaded by the same core, which queries lights and decals through the
/// hardware back end there too.
#[test]
fn reflection_hits_query_through_the_hardware_backend() {
    let mut scene = with_decals_and_lights(demo_scene(), 300, 300, 5);
    for material in &mut scene.materials {
        material.roughness_factor = material.roughness_factor.min(0.15);
    }
    let ctx = ray_queries();
    let reflecting = |bvh, backend| {
        let config = backend_config(PipelineKind::Visbuffer, bvh, BvhBuild::CpuOnce, backend);
        RenderConfig { rays: RaySettings { reflection_bounces: 1, ..config.rays }, ..config }
    };
    let (brute, _) = render_at(&ctx, &scene, reflecting(false, RayBackend::Software), 0.0);
    let (hardware, _) = render_at(&ctx, &scene, reflecting(true, RayBackend::Hardware), 0.0);
    let difference = max_abs_difference(&brute, &hardware);
    assert!(difference <= TOLERANCE, "with reflections: max abs difference {difference} from brute force");
}

/// A scene with no lights and no decals, then with no triangles either: the top levels are built over
/// no instance.
#[test]
fn hardware_queries_over_no_volumes() {
    let scene = demo_scene();
    let mut empty = scene.clone();
    empty.lights.clear();
    empty.light_groups = Default::default();
    let ctx = ray_queries();
    let (brute, _) = render_at(&ctx, &empty, backend_config(PipelineKind::Visbuffer, false, BvhBuild::CpuOnce, RayBackend::Software), 0.0);
    let (hardware, _) =
        render_at(&ctx, &empty, backend_config(PipelineKind::Visbuffer, true, BvhBuild::CpuOnce, RayBackend::Hardware), 0.0);
    assert!(max_abs_difference(&brute, &hardware) <= TOLERANCE);
    // And rays traced over no triangles: the rays' top level is built over no instance.
    let mut bare = empty;
    bare.meshes.clear();
    bare.instances.clear();
    let shadows = backend_config(PipelineKind::Visbuffer, true, BvhBuild::CpuOnce, RayBackend::Hardware);
    let shadows = RenderConfig { rays: RaySettings { sun_shadows: SunShadows::Hard, ..shadows.rays }, ..shadows };
    render_at(&ctx, &bare, shadows, 0.0);
}

/// `auto` takes ray queries where the GPU runs them (`plan`'s unit tests), not where a CPU adapter
/// emulates them, as lavapipe does, nor where the device has none; `hardware` takes emulated ones, and
/// on a device without any is refused, naming the fix.
#[test]
fn auto_takes_ray_queries_only_where_the_gpu_runs_them() {
    let scene = with_decals_and_lights(demo_scene(), 50, 50, 2);
    let auto = backend_config(PipelineKind::Visbuffer, true, BvhBuild::CpuOnce, RayBackend::Auto);
    let ctx = ray_queries();
    let expected = match Capabilities::of(&ctx).ray_queries {
        RayQueries::Native => RayTracer::Hardware,
        RayQueries::Emulated | RayQueries::None => RayTracer::Software,
    };
    let (with, tracer) = render_at(&ctx, &scene, auto.clone(), 0.0);
    assert_eq!(tracer, expected, "{}", ctx.describe());
    let without = GpuContext::without(wgpu::Features::EXPERIMENTAL_RAY_QUERY).unwrap();
    assert!(!without.has_ray_queries());
    let (fallback, tracer) = render_at(&without, &scene, auto, 0.0);
    assert_eq!(tracer, RayTracer::Software);
    assert!(max_abs_difference(&with, &fallback) <= TOLERANCE);
    let hardware = backend_config(PipelineKind::Visbuffer, true, BvhBuild::CpuOnce, RayBackend::Hardware);
    assert_eq!(render_at(&ctx, &scene, hardware.clone(), 0.0).1, RayTracer::Hardware);
    match Renderer::new(without, &scene, hardware) {
        Err(Error::InvalidConfig(message)) => assert!(message.contains("--ray-backend software"), "{message}"),
        Err(e) => panic!("unexpected error: {e}"),
        Ok(_) => panic!("hardware was accepted on a device without ray queries"),
    }
}

/// The demo scene with every effect that traces the triangles: sun shadows, shadowed lamps and
/// glossy reflections; its perforated panel is alpha-masked, by its texture and by vertex alphas
/// alternating 1 and 0.2.
fn traced_scene() -> Scene {
    let mut scene = demo_scene();
    let masked: Vec<bool> = scene.materials.iter().map(|m| matches!(m.alpha_mode, AlphaMode::Mask { .. })).collect();
    for primitive in scene.meshes.iter_mut().flat_map(|m| &mut m.primitives).filter(|p| masked[p.material]) {
        for (i, v) in primitive.vertices.iter_mut().enumerate() {
            v.color = Vertex::color_from([1.0, 1.0, 1.0, if i % 2 == 0 { 1.0 } else { 0.2 }]);
        }
    }
    for light in &mut scene.lights {
        light.cast_shadows = true;
    }
    for material in &mut scene.materials {
        material.roughness_factor = material.roughness_factor.min(0.2);
    }
    scene
}

/// `bvh`: lights and decals through the back end too; otherwise brute force, whose loops stream the
/// lights in the same order whatever traces, as `restir`'s sampling needs to draw the same lights.
fn traced_config(pipeline: PipelineKind, rays: RaySettings, backend: RayBackend, bvh: bool) -> RenderConfig {
    let config = backend_config(pipeline, bvh, BvhBuild::CpuOnce, backend);
    RenderConfig { rays: RaySettings { backend, ..rays }, ..config }
}

/// Renders `frames` frames back to back with each back end and compares the last.
fn assert_rays_agree(scene: &Scene, pipeline: PipelineKind, rays: RaySettings, frames: u32, what: &str) {
    let ctx = ray_queries();
    // restir's reservoirs keep the light streamed by an order-dependent draw: the same lights must
    // come in the same order, so its lights are looped over, not queried.
    let bvh = rays.direct_lighting != DirectLighting::Restir;
    let [software, hardware] = [RayBackend::Software, RayBackend::Hardware].map(|backend| {
        let mut r = Renderer::new(ctx.clone(), scene, traced_config(pipeline, rays, backend, bvh)).expect("renderer");
        r.render_frames(&scene.cameras[0], frames).expect("frames");
        r.read_hdr().expect("hdr")
    });
    let difference = max_abs_difference(&software, &hardware);
    let off = software.pixels.iter().zip(&hardware.pixels).filter(|(a, b)| (0..3).any(|c| (a[c] - b[c]).abs() > TOLERANCE)).count();
    assert!(difference <= TOLERANCE, "{} {what}: hardware rays differ from software by {difference} in {off} pixels", pipeline.name());
}

#[test]
fn hardware_rays_give_the_software_image_in_every_pipeline() {
    let scene = traced_scene();
    let reflecting = RaySettings { reflection_bounces: 2, light_shadow_rays: 8, ..RaySettings::default() };
    for pipeline in PipelineKind::ALL {
        for sun_shadows in [SunShadows::Hard, SunShadows::Soft] {
            assert_rays_agree(&scene, pipeline, RaySettings { sun_shadows, ..reflecting }, 1, &format!("{sun_shadows} shadows"));
        }
    }
    let reference = RaySettings { direct_lighting: DirectLighting::Reference, sun_shadows: SunShadows::Hard, ..RaySettings::default() };
    assert_rays_agree(&scene, PipelineKind::Visbuffer, reference, 1, "reference lighting");
    // restir's visibility rays, its reuse's too, over a few frames, denoised.
    let restir = RaySettings { direct_lighting: DirectLighting::Restir, ..reference };
    assert_rays_agree(&scene, PipelineKind::Deferred, restir, 3, "restir");
}

/// A deforming floor, whose bottom level is rebuilt from the refitted triangles every frame, and an
/// instance flying through the room, which the top level follows: frames rendered back to back give
/// the software hierarchy's image.
#[test]
fn hardware_rays_follow_deforming_meshes_and_moving_instances() {
    let mut scene = traced_scene();
    let floor = scene.meshes.iter().position(|m| m.name == "floor").expect("the demo's floor");
    scene.deformers = vec![Deformer::wave(floor, Wave { amplitude: 0.2, wavelength: 2.0, speed: 1.0, direction: glam::Vec3::X })];
    let flying = scene.instances.iter().position(|i| i.mesh != floor).expect("an instance besides the floor");
    let start = scene.instances[flying].world_from_local.w_axis.truncate();
    fly(&mut scene, flying, start, start + glam::Vec3::new(0.5, 0.3, 0.0));
    let rays = RaySettings { sun_shadows: SunShadows::Hard, reflection_bounces: 1, ..RaySettings::default() };
    assert_rays_agree(&scene, PipelineKind::Visbuffer, rays, 3, "deforming floor");
}
