//! Particle lights (`particles/`): the GPU moves every particle where the CPU twin says, the same
//! time gives the same particles, the splat's sums are the analytic sums of the falloff over the
//! voxels, and bad settings are clear errors.

mod common;

use common::*;
use glam::{Mat4, UVec3, Vec3};
use manylights::{
    gpu::GpuContext,
    particles::{ParticleGrid, ParticleSystem, ParticleVolume},
    renderer::Image,
    scene::ParticleSettings,
    scene::{Aabb, Light, LightKind},
    settings::BvhBuild,
    settings::ParticleFilter,
    settings::RenderConfig,
    settings::{DecalMethod, LightMethod, ParticleMethod, PipelineKind},
};

fn settings(count: u32) -> ParticleSettings {
    ParticleSettings {
        count,
        seed: 7,
        emitters: vec![(Vec3::new(0.0, 0.0, 0.0), 4.0), (Vec3::new(5.0, 1.0, -3.0), 6.0), (Vec3::new(-4.0, 0.5, 2.0), 3.0)],
        ..ParticleSettings::default()
    }
}

fn grid(voxel_size: f32) -> ParticleGrid {
    ParticleGrid::covering(&Aabb::new(Vec3::new(-12.0, -8.0, -12.0), Vec3::new(12.0, 10.0, 12.0)), voxel_size, 2048).unwrap()
}

/// Where `run` places the camera (the clipmaps' centre).
const EYE: Vec3 = Vec3::new(1.3, 2.2, -0.7);

/// Runs the motion and splat passes for `time` and waits.
fn run(ctx: &GpuContext, system: &ParticleSystem, time: f32) {
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    system.record(ctx, &mut encoder, None, time, EYE);
    ctx.queue.submit([encoder.finish()]);
    ctx.wait_idle().unwrap();
}

#[test]
fn motion_follows_the_cpu_twin_and_depends_on_time_alone() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let settings = settings(20_000);
    let system = ParticleSystem::new(&ctx, &settings, ParticleVolume::World(grid(1.0))).unwrap();
    for time in [0.0, 0.4, 7.3] {
        run(&ctx, &system, time);
        let gpu = system.read_particles(&ctx).unwrap();
        assert_eq!(gpu.len(), 20_000);
        for (i, p) in gpu.iter().enumerate() {
            let cpu = settings.particle_at(i as u32, time);
            let position = Vec3::from(p.position);
            assert!(
                (position - cpu.position).length() < 1e-3 * (1.0 + cpu.position.length()),
                "particle {i} at {time} s: {position} against {}",
                cpu.position
            );
            assert!((p.radius - cpu.radius).abs() < 1e-5 && (Vec3::from(p.color) - cpu.color).abs().max_element() < 1e-5, "particle {i}");
        }
    }
    // The same time again gives the same particles, bit for bit, whatever ran in between.
    run(&ctx, &system, 0.4);
    let first: Vec<[f32; 8]> = system.read_particles(&ctx).unwrap().iter().map(|p| bytemuck::cast(*p)).collect();
    run(&ctx, &system, 3.0);
    let moved: Vec<[f32; 8]> = system.read_particles(&ctx).unwrap().iter().map(|p| bytemuck::cast(*p)).collect();
    run(&ctx, &system, 0.4);
    let again: Vec<[f32; 8]> = system.read_particles(&ctx).unwrap().iter().map(|p| bytemuck::cast(*p)).collect();
    assert_eq!(first, again);
    let moving = first.iter().zip(&moved).filter(|(a, b)| a[..3] != b[..3]).count();
    assert!(moving > 19_000, "only {moving} of 20,000 particles moved in 2.6 s");
    // Particles are launched upwards from their emitters and fall back: none runs away.
    let spread = moved.iter().map(|p| Vec3::new(p[0], p[1], p[2]).length()).fold(0.0f32, f32::max);
    assert!(spread < 40.0, "a particle is {spread} m from the origin");
}

/// The CPU's splat of the same particle lights: per voxel, colour × falloff and direction × falloff ×
/// luminance over the voxel centres each particle's radius reaches.
fn cpu_splat(grid: &ParticleGrid, lights: &[manylights::particles::GpuParticleLight]) -> (Vec<[f64; 6]>, Vec<u32>) {
    let mut sums = vec![[0.0f64; 6]; grid.voxel_count() as usize];
    let mut contributions = vec![0u32; sums.len()];
    for light in lights {
        let position = Vec3::from(light.position);
        let color = Vec3::from(light.color);
        let luminance = color.dot(Vec3::new(0.2126, 0.7152, 0.0722));
        for z in 0..grid.dims.z {
            for y in 0..grid.dims.y {
                for x in 0..grid.dims.x {
                    let voxel = UVec3::new(x, y, z);
                    let to_light = position - grid.centre(voxel);
                    let distance = to_light.length();
                    if distance >= light.radius {
                        continue;
                    }
                    let weight = grid.falloff(distance, light.radius);
                    let direction = if distance > 0.0 { to_light / distance } else { Vec3::ZERO } * (weight * luminance);
                    let sum = &mut sums[grid.index(voxel)];
                    for (k, value) in (color * weight).to_array().into_iter().chain(direction.to_array()).enumerate() {
                        sum[k] += f64::from(value);
                    }
                    contributions[grid.index(voxel)] += 1;
                }
            }
        }
    }
    (sums, contributions)
}

#[test]
fn the_splat_sums_the_falloff_over_the_voxels() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let settings = settings(2_000);
    let grid = grid(0.75);
    let system = ParticleSystem::new(&ctx, &settings, ParticleVolume::World(grid)).unwrap();
    run(&ctx, &system, 1.3);
    let lights = system.read_particles(&ctx).unwrap();
    let gpu = system.read_sums(&ctx).unwrap();
    let (cpu, contributions) = cpu_splat(&grid, &lights);
    assert_eq!(system.scales().unwrap().fixed, manylights::particles::MAX_SPLAT_SCALE, "2,000 dim particles need no coarser steps");
    assert_sums_match(&gpu, &cpu, &contributions, system.scales().unwrap().fixed, "");
}

/// The GPU's sums equal the CPU's within the fixed-point rounding of each contribution (dithered: under
/// one step of 1 / `fixed`), and hold the same light in total (conservation) to a part in a thousand.
fn assert_sums_match(gpu: &[[f32; 6]], cpu: &[[f64; 6]], contributions: &[u32], fixed: f32, what: &str) {
    assert_eq!(gpu.len(), cpu.len());
    let mut total = ([0.0f64; 6], [0.0f64; 6]);
    for (v, ((g, c), n)) in gpu.iter().zip(cpu).zip(contributions).enumerate() {
        for k in 0..6 {
            let tolerance = f64::from(*n) / f64::from(fixed) + 1e-4 * c[k].abs() + 1e-6;
            assert!(
                (f64::from(g[k]) - c[k]).abs() <= tolerance,
                "{what}voxel {v} channel {k}: GPU {} against {} ({n} particles)",
                g[k],
                c[k]
            );
            total.0[k] += f64::from(g[k]);
            total.1[k] += c[k];
        }
    }
    for k in 0..3 {
        assert!(total.1[k] > 1.0, "{what}channel {k} holds almost no light: the test would mean nothing");
        assert!((total.0[k] - total.1[k]).abs() <= 1e-3 * total.1[k], "{what}channel {k}: GPU total {} against {}", total.0[k], total.1[k]);
    }
}

/// A clipmap's cascades sit around the eye, and each holds the splat of the particles into its own
/// voxels, one cascade after the other.
#[test]
fn every_cascade_of_a_clipmap_holds_its_own_splat() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let settings = settings(1_500);
    let volume = ParticleVolume::clipmap(0.5, 24, 3, 2048).unwrap();
    let system = ParticleSystem::new(&ctx, &settings, volume).unwrap();
    run(&ctx, &system, 0.9);
    let lights = system.read_particles(&ctx).unwrap();
    let gpu = system.read_sums(&ctx).unwrap();
    let cascades = volume.cascades(EYE);
    assert_eq!(gpu.len() as u64, volume.voxel_count());
    let per_cascade = cascades[0].voxel_count() as usize;
    for (k, cascade) in cascades.iter().enumerate() {
        let (cpu, contributions) = cpu_splat(cascade, &lights);
        let gpu = &gpu[k * per_cascade..(k + 1) * per_cascade];
        assert_sums_match(gpu, &cpu, &contributions, system.scales().unwrap().fixed, &format!("cascade {k}: "));
    }
}

/// Particles crowded into one spot, bright enough that fixed steps of 1/1024 would wrap a voxel's
/// i32 sum and the sums would overflow half floats (65504): the splat's scales keep both in range,
/// and the wall is lit as the one particle lights it, times all their colours.
#[test]
fn crowded_bright_particles_neither_wrap_nor_overflow() {
    let crowd = ParticleSettings { count: 200_000, radius: (1.0, 1.0), ..still_particle() };
    let scales = manylights::particles::SplatScales::new(&crowd, 0.5);
    assert!(scales.fixed < 1024.0 && scales.texture < 1.0, "{scales:?}: the crowd would not have overflowed");
    let alone = ParticleSettings { count: 1, ..crowd.clone() };
    let one = particle_wall_of(alone.clone());
    let all = particle_wall_of(crowd.clone());
    // Every particle sits at the emitter with the same radius: the wall's light scales with the
    // luminance of their summed colours.
    let luminance_of = |c: Vec3| c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    let total: Vec3 = (0..crowd.count).map(|i| crowd.particle_at(i, 0.0).color).sum();
    let ratio = luminance_of(total) / luminance_of(alone.particle_at(0, 0.0).color);
    let peak = one.pixels.iter().map(|&p| luminance(p)).fold(0.0, f32::max);
    let mut worst = 0.0f32;
    for (a, o) in all.pixels.iter().zip(&one.pixels) {
        assert!(a.iter().all(|c| c.is_finite()), "a pixel is {a:?}");
        if luminance(*o) > 0.05 * peak {
            worst = worst.max((luminance(*a) / (luminance(*o) * ratio) - 1.0).abs());
        }
    }
    assert!(worst < 0.01, "the crowd's light is off by {worst} of the expected");
}

#[test]
fn bad_particle_settings_are_clear_errors() {
    let bounds = Aabb::new(Vec3::ZERO, Vec3::splat(10.0));
    for size in [0.0, -1.0, f32::NAN, f32::INFINITY] {
        let err = ParticleGrid::covering(&bounds, size, 2048).unwrap_err().to_string();
        assert!(err.contains("voxel size") && err.contains("> 0"), "{err}");
    }
    let err = ParticleGrid::covering(&Aabb::new(Vec3::ZERO, Vec3::splat(5000.0)), 1.0, 2048).unwrap_err().to_string();
    assert!(err.contains("3D texture limit of 2048") && err.contains("larger voxels"), "{err}");
    let err = ParticleSettings { emitters: Vec::new(), ..settings(10) }.validate().unwrap_err().to_string();
    assert!(err.contains("emitter"), "{err}");
    let err = ParticleSettings { radius: (1.0, 0.5), ..settings(10) }.validate().unwrap_err().to_string();
    assert!(err.contains("radius"), "{err}");
    let err =
        ParticleSettings { count: manylights::scene::particles::MAX_PARTICLES + 1, ..settings(10) }.validate().unwrap_err().to_string();
    assert!(err.contains("exceed the maximum"), "{err}");
    for (voxel, resolution, cascades, expected) in [
        (0.5, 32, 0, "at least 1 particle cascade"),
        (0.5, 32, 9, "give 1 to 8"),
        (0.5, 31, 2, "even number"),
        (0.5, 16, 2, "at least 24"),
        (0.5, 512, 8, "3D texture limit of 2048"),
        (-1.0, 32, 2, "voxel size"),
    ] {
        let err = ParticleVolume::clipmap(voxel, resolution, cascades, 2048).unwrap_err().to_string();
        assert!(err.contains(expected), "{voxel} m, {resolution}, {cascades}: {err}");
    }
    // A particle reaching 16 m splats into more voxels of 0.25 m than any particle may.
    let ctx = GpuContext::new().expect("a GPU adapter");
    let wide = ParticleSettings { radius: (1.0, 16.0), ..settings(10) };
    let err = ParticleSystem::new(&ctx, &wide, ParticleVolume::World(grid(0.25))).err().expect("a 16 m particle").to_string();
    assert!(err.contains("larger voxels") && err.contains("smaller particle radius"), "{err}");
    // As exact lights, the most particles allowed and 255 scene lights fill what one structure
    // addresses (2^24 items and instances) but for one slot, and the instance slots of the two
    // groups overflow it: an error before anything is allocated.
    let lights = (0..255).map(|i| point_light(Vec3::new(0.01 * i as f32, 0.0, 1.0), 1.0, 1.0)).collect();
    let (mut scene, _) = wall_scene(lights);
    scene.particles = Some(ParticleSettings { count: manylights::scene::particles::MAX_PARTICLES, ..settings(10) });
    let exact =
        RenderConfig { particle_method: ParticleMethod::Bvh, decal_method: DecalMethod::Off, ..config(SIZE.0, SIZE.1, LightMethod::Bvh) };
    let err = manylights::renderer::Renderer::new(ctx, &scene, exact).err().expect("too many lights").to_string();
    assert!(
        err.contains("255 lights (and 16776960 particle lights) and 2 instance slots")
            && err.contains("at most 16777216")
            && err.contains("use fewer lights or particles"),
        "{err}"
    );
}

/// One particle that stays where it is launched (no speed, no gravity): 1 m in front of the white
/// wall of `wall_scene`, reaching 3 m.
fn still_particle() -> ParticleSettings {
    ParticleSettings {
        count: 1,
        seed: 3,
        emitters: vec![(Vec3::new(0.5, -0.3, 1.0), 0.0)],
        gravity: 0.0,
        swirl: 0.0,
        radius: (3.0, 3.0),
        intensity: 2.0,
        ..ParticleSettings::default()
    }
}

const SIZE: (u32, u32) = (96, 96);

fn particle_wall(voxel_size: f32, pipeline: PipelineKind) -> Image<[f32; 4]> {
    particle_wall_filtered(voxel_size, pipeline, ParticleFilter::Trilinear, 1)
}

fn particle_wall_filtered(voxel_size: f32, pipeline: PipelineKind, filter: ParticleFilter, samples: u32) -> Image<[f32; 4]> {
    let config =
        RenderConfig { pipeline, particle_voxel_size: voxel_size, particle_filter: filter, particle_samples: samples, ..wall_config() };
    particle_wall_with(still_particle(), config)
}

fn wall_config() -> RenderConfig {
    RenderConfig { particle_voxel_size: 0.5, decal_method: DecalMethod::Off, ..config(SIZE.0, SIZE.1, LightMethod::Off) }
}

/// The wall lit by `particles` through the grid of 0.5 m voxels over the scene.
fn particle_wall_of(particles: ParticleSettings) -> Image<[f32; 4]> {
    particle_wall_with(particles, wall_config())
}

fn particle_wall_with(particles: ParticleSettings, config: RenderConfig) -> Image<[f32; 4]> {
    let (mut scene, camera) = wall_scene(Vec::new());
    scene.particles = Some(particles);
    render_with(&scene, &camera, config).1
}

fn clipmap_config(voxel_size: f32, resolution: u32, cascades: u32) -> RenderConfig {
    RenderConfig { particle_voxel_size: voxel_size, particle_cascades: cascades, particle_cascade_resolution: resolution, ..wall_config() }
}

/// The camera stands 4 m from the wall. A clipmap whose finest cascade holds the wall's visible part
/// (32 voxels of 0.5 m around the eye) lies on the same voxel lattice as the grid over the scene at
/// 0.5 m, and lights the wall the same; so does one whose finest cascade (24 voxels of 0.25 m) ends
/// before the wall, through its coarser cascade of 0.5 m voxels.
#[test]
fn a_clipmap_lights_the_wall_as_the_grid_over_the_scene_does() {
    let world = particle_wall_of(still_particle());
    for (voxel_size, resolution, what) in [(0.5, 32, "the finest cascade"), (0.25, 24, "the coarser cascade")] {
        let clipmap = particle_wall_with(still_particle(), clipmap_config(voxel_size, resolution, 2));
        let difference = max_abs_difference(&world, &clipmap);
        assert!(difference < 1e-4, "through {what}: max abs difference {difference} from the grid over the scene");
    }
    // Three cascades: the wall lies in the band where the 0.5 m cascade blends into the 1 m one,
    // still close to the particle's point light.
    let blended = particle_wall_with(still_particle(), clipmap_config(0.25, 24, 3));
    let error = mean_relative_error(&blended, &point_light_wall());
    assert!(error < 0.15, "blended cascades: mean relative error {error} against the point light");
}

/// A world kilometres wide: one grid over it would exceed the 3D texture limit, the clipmap's size
/// does not depend on it, and lights the wall exactly as in the small world.
#[test]
fn a_clipmap_needs_no_world_sized_texture() {
    let (mut scene, camera) = wall_scene(Vec::new());
    scene.particles = Some(still_particle());
    // Far enough for more 0.5 m voxels along x than the device's 3D textures hold (5 km on lavapipe).
    let ctx = GpuContext::new().unwrap();
    let distance = (ctx.limits.max_texture_dimension_3d as f32 * 0.5).max(5000.0) + 500.0;
    let far = manylights::scene::Instance { mesh: 0, world_from_local: glam::Mat4::from_translation(Vec3::new(distance, 0.0, 0.0)) };
    scene.instances.push(far);
    let err = manylights::renderer::Renderer::new(ctx, &scene, wall_config())
        .err()
        .unwrap_or_else(|| panic!("a {distance} m grid of 0.5 m voxels"))
        .to_string();
    assert!(err.contains("3D texture limit") && err.contains("--particle-cascades"), "{err}");
    let large = render_with(&scene, &camera, clipmap_config(0.5, 32, 4)).1;
    let small = particle_wall_with(still_particle(), clipmap_config(0.5, 32, 4));
    assert_eq!(large.pixels, small.pixels);
}

/// The wall lit by the particle as an ordinary point light (same place, colour and range).
fn point_light_wall() -> Image<[f32; 4]> {
    let particle = still_particle().particle_at(0, 0.0);
    let light = Light {
        kind: LightKind::Point,
        position: particle.position,
        direction: Vec3::NEG_Z,
        color: particle.color,
        intensity: 1.0,
        range: particle.radius,
        cast_shadows: false,
    };
    let (scene, camera) = wall_scene(vec![light]);
    render_with(&scene, &camera, config(SIZE.0, SIZE.1, LightMethod::Brute)).1
}

/// Mean relative error of `image` against `reference` where the reference is over 5 % of its peak.
fn mean_relative_error(image: &Image<[f32; 4]>, reference: &Image<[f32; 4]>) -> f32 {
    let peak = reference.pixels.iter().map(|&p| luminance(p)).fold(0.0, f32::max);
    let (sum, count) = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .filter(|(_, r)| luminance(**r) > 0.05 * peak)
        .fold((0.0, 0), |(sum, count), (i, r)| (sum + (luminance(*i) - luminance(*r)).abs() / luminance(*r), count + 1));
    assert!(count > 500, "only {count} lit pixels");
    sum / count as f32
}

/// Two particles grazing the wall on either side of its middle: between them their directions' mean
/// points straight out of the wall, where neither is, and its length says so. The wall's light comes
/// nearer their point lights' with the rest of their light taken as from all around than through
/// that mean alone.
#[test]
fn particles_on_either_side_light_the_wall_between_them_near_their_point_lights() {
    let pair = ParticleSettings {
        count: 2,
        emitters: vec![(Vec3::new(-1.0, 0.0, 0.3), 0.0), (Vec3::new(1.0, 0.0, 0.3), 0.0)],
        ..still_particle()
    };
    let lights = (0..2)
        .map(|i| {
            let particle = pair.particle_at(i, 0.0);
            let light = point_light(particle.position, 1.0, particle.radius);
            Light { color: particle.color, ..light }
        })
        .collect();
    let (scene, camera) = wall_scene(lights);
    let reference = render_with(&scene, &camera, config(SIZE.0, SIZE.1, LightMethod::Brute)).1;
    let grid = particle_wall_with(pair, RenderConfig { particle_voxel_size: 0.25, ..wall_config() });
    let error = mean_relative_error(&grid, &reference);
    // Measured on lavapipe: 15.9 % through the mean direction alone, 8.7 % with the spread.
    assert!(error < 0.12, "mean relative error {error} against the two point lights");
}

#[test]
fn a_particle_lights_a_wall_as_its_point_light_does_and_finer_voxels_do_better() {
    let reference = point_light_wall();
    let errors: Vec<f32> =
        [1.0, 0.5, 0.25].iter().map(|&v| mean_relative_error(&particle_wall(v, PipelineKind::Visbuffer), &reference)).collect();
    // Measured on lavapipe: 16 %, 2.4 % and 0.6 %.
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "errors do not fall with finer voxels: {errors:?}");
    assert!(errors[1] < 0.05 && errors[2] < 0.02, "mean relative errors {errors:?} against the point light at 0.5 and 0.25 m voxels");
}

#[test]
fn particles_light_every_pipeline_alike_and_the_off_method_ignores_them() {
    let visbuffer = particle_wall(0.5, PipelineKind::Visbuffer);
    assert!(visbuffer.pixels.iter().map(|&p| luminance(p)).fold(0.0, f32::max) > 0.05, "the particle lights nothing");
    for pipeline in [PipelineKind::Deferred, PipelineKind::Forward] {
        let difference = max_abs_difference(&visbuffer, &particle_wall(0.5, pipeline));
        assert!(difference < 2e-3, "{}: max abs difference {difference} from the visibility buffer", pipeline.name());
    }
    let (mut scene, camera) = wall_scene(Vec::new());
    scene.particles = Some(still_particle());
    let off =
        RenderConfig { particle_method: ParticleMethod::Off, decal_method: DecalMethod::Off, ..config(SIZE.0, SIZE.1, LightMethod::Off) };
    let dark = render_with(&scene, &camera, off).1;
    assert!(dark.pixels.iter().all(|p| luminance(*p) == 0.0), "particles lit the wall with --particle-method off");
}

/// The paper's remedies for blocky grids: trilinear filtering beats nearest, and tricubic filtering and
/// supersampling stay close to the point light, in every pipeline.
#[test]
fn every_filter_and_supersampling_light_the_wall_like_the_point_light() {
    let reference = point_light_wall();
    let error = |filter, samples| mean_relative_error(&particle_wall_filtered(0.5, PipelineKind::Visbuffer, filter, samples), &reference);
    let nearest = error(ParticleFilter::Nearest, 1);
    let trilinear = error(ParticleFilter::Trilinear, 1);
    let tricubic = error(ParticleFilter::Tricubic, 1);
    let supersampled = error(ParticleFilter::Trilinear, 8);
    // Measured on lavapipe: 30 %, 2.4 %, 1.5 % and 1.9 %.
    assert!(nearest > 2.0 * trilinear, "nearest {nearest} against trilinear {trilinear}");
    assert!(tricubic < 0.06 && supersampled < trilinear, "tricubic {tricubic}, supersampled {supersampled}, trilinear {trilinear}");
    let visbuffer = particle_wall_filtered(0.5, PipelineKind::Visbuffer, ParticleFilter::Tricubic, 1);
    for pipeline in [PipelineKind::Deferred, PipelineKind::Forward] {
        let difference = max_abs_difference(&visbuffer, &particle_wall_filtered(0.5, pipeline, ParticleFilter::Tricubic, 1));
        assert!(difference < 2e-3, "{}: max abs difference {difference} from the visibility buffer", pipeline.name());
        // Supersampling's pattern turns with each point's exact position, which the pipelines
        // reconstruct differently: compared with the point light instead.
        let supersampled = mean_relative_error(&particle_wall_filtered(0.5, pipeline, ParticleFilter::Trilinear, 8), &reference);
        assert!(supersampled < 0.05, "{}: supersampled error {supersampled}", pipeline.name());
    }
}

/// The exact method: the particles as point lights in the lights' BVH, rebuilt on the GPU every
/// frame (leaves of several particles) beside the scene's own lights, light the scene as the same
/// lights from the CPU twin do through brute force, in every pipeline, walking the BVH a subgroup at
/// a time or, on a device without subgroups, one invocation at a time; and with the scene's lights'
/// group rebuilt on the GPU too, so their leaf-order copy runs before the particles' records.
#[test]
fn particles_as_lights_equal_their_point_lights() {
    let scene_lights: Vec<Light> =
        (0..24).map(|i| point_light(Vec3::new(-3.0 + 0.25 * i as f32, 2.0 - 0.1 * i as f32, 1.5), 0.4, 1.5 + 0.1 * i as f32)).collect();
    let (mut scene, camera) = wall_scene(scene_lights.clone());
    let settings = ParticleSettings {
        count: 3000,
        seed: 5,
        emitters: vec![(Vec3::new(-2.0, -1.0, 0.5), 2.0), (Vec3::new(1.5, 0.5, 1.0), 1.5)],
        radius: (0.3, 1.0),
        intensity: 0.05,
        ..ParticleSettings::default()
    };
    scene.particles = Some(settings.clone());
    let time = 1.7;

    let lights: Vec<Light> = (0..settings.count)
        .map(|i| {
            let p = settings.particle_at(i, time);
            Light {
                kind: LightKind::Point,
                position: p.position,
                direction: Vec3::NEG_Y,
                color: p.color,
                intensity: 1.0,
                range: p.radius,
                cast_shadows: false,
            }
        })
        .chain(scene_lights)
        .collect();
    let (mut reference_scene, _) = wall_scene(lights);
    let with_subgroups = GpuContext::new().unwrap();
    assert!(with_subgroups.features.contains(wgpu::Features::SUBGROUP), "the subgroup walk would go untested");
    let without_subgroups = GpuContext::without(wgpu::Features::SUBGROUP).unwrap();
    // The wall filling the view, then a smaller one turned about the view axis, whose edges leave
    // subgroups with some lanes on the sky (gone before the query) and so lanes whose rank among the
    // active ones differs from their index.
    let turned = Mat4::from_rotation_z(0.4) * Mat4::from_scale(Vec3::new(3.0, 2.0, 1.0));
    for (wall, placement) in [("whole wall", scene.instances[0].world_from_local), ("turned wall", turned)] {
        scene.instances[0].world_from_local = placement;
        reference_scene.instances[0].world_from_local = placement;
        for pipeline in PipelineKind::ALL {
            // Pipelines differ by their G-buffer's precision: each is compared with itself.
            let brute = RenderConfig { decal_method: DecalMethod::Off, pipeline, ..config(SIZE.0, SIZE.1, LightMethod::Brute) };
            let reference = render_with(&reference_scene, &camera, brute).1;
            assert!(reference.pixels.iter().map(|&p| luminance(p)).fold(0.0, f32::max) > 0.05, "the particles light nothing");
            let runs = [
                (&with_subgroups, "subgroup", BvhBuild::CpuOnce),
                (&without_subgroups, "invocation", BvhBuild::CpuOnce),
                (&with_subgroups, "subgroup", BvhBuild::GpuEveryFrame),
            ];
            for (ctx, walk, light_bvh_build) in runs {
                let exact = RenderConfig {
                    particle_method: ParticleMethod::Bvh,
                    decal_method: DecalMethod::Off,
                    light_bvh_build,
                    pipeline,
                    ..config(SIZE.0, SIZE.1, LightMethod::Bvh)
                };
                let mut renderer = manylights::renderer::Renderer::new(ctx.clone(), &scene, exact).unwrap();
                renderer.time = time;
                renderer.render(&camera).unwrap();
                let difference = max_abs_difference(&renderer.read_hdr().unwrap(), &reference);
                assert!(
                    difference <= 1e-3,
                    "{wall}, {} pipeline, {walk} walk, scene lights {light_bvh_build:?}: max abs difference {difference} from the point lights",
                    pipeline.name()
                );
            }
        }
    }

    // Other light methods do not read the particles' lights: a clear error.
    let err = manylights::renderer::Renderer::new(
        GpuContext::new().unwrap(),
        &scene,
        RenderConfig { particle_method: ParticleMethod::Bvh, ..config(SIZE.0, SIZE.1, LightMethod::Clustered) },
    )
    .err()
    .expect("clustered lights with bvh particles")
    .to_string();
    assert!(err.contains("--light-method bvh"), "{err}");
}
