//! `manylights particle-error`: how far each particle-grid setting is from the exact method (the same
//! particles as point lights through the BVH), on a scene at one time: the particles' light in error,
//! relative to their exact light, and the PSNR of the tonemapped image.

use anyhow::bail;
use clap::Args;
use manylights::{
    gpu::GpuContext,
    renderer::{Image, Renderer},
    scene::Scene,
    settings::{DecalMethod, LightMethod, ParticleFilter, ParticleMethod, RenderConfig},
};

use crate::metrics::{luminance, psnr};
use crate::render::choose_camera;
use crate::scene_args::{ComparedView, SceneArgs};

#[derive(Args)]
pub struct ParticleErrorArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    view: ComparedView,
    /// Scene time of the compared frame, in seconds.
    #[arg(long, default_value_t = 1.0)]
    time: f32,
    /// Voxel edges to compare, in metres, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1.0, 0.5, 0.25])]
    voxel_sizes: Vec<f32>,
    /// Filters to compare, comma-separated.
    #[arg(long, value_enum, value_delimiter = ',', default_values_t = [ParticleFilter::Trilinear, ParticleFilter::Tricubic])]
    filters: Vec<ParticleFilter>,
    /// Samples per shading point to compare, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1, 8])]
    samples: Vec<u32>,
    /// Clipmap cascade counts to compare, comma-separated (0: one grid over the scene).
    #[arg(long, value_delimiter = ',', default_values_t = [0])]
    cascades: Vec<u32>,
    /// Voxels per axis of each cascade.
    #[arg(long, default_value_t = 64)]
    cascade_resolution: u32,
}

/// A frame as linear radiance and tonemapped.
type Frame = (Image<[f32; 4]>, Image<[u8; 4]>);

pub fn run(args: &ParticleErrorArgs) -> anyhow::Result<()> {
    let ctx = GpuContext::new()?;
    let (scene, _) = args.scene.load(Some(&ctx))?;
    if scene.particles.as_ref().is_none_or(|p| p.count == 0) {
        bail!("the scene has no particles; add them with --particles N (or a scene file's [particles])");
    }
    if !(args.time.is_finite() && args.time >= 0.0) {
        bail!("--time {}: give a finite time ≥ 0 in seconds", args.time);
    }
    let camera = choose_camera(&scene, args.view.camera)?;
    let config = |particle_method| RenderConfig {
        width: args.view.width,
        height: args.view.height,
        pipeline: args.view.pipeline,
        light_method: LightMethod::Bvh,
        decal_method: DecalMethod::Bvh,
        particle_method,
        ..RenderConfig::default()
    };
    let frame = |config: RenderConfig| -> anyhow::Result<Frame> {
        let mut renderer = Renderer::new(ctx.clone(), &scene, config)?;
        renderer.time = args.time;
        renderer.render(&camera)?;
        Ok((renderer.read_hdr()?, renderer.read_ldr()?))
    };
    // Every grid setting, checked before the first frame so a bad one fails at once.
    let mut settings = Vec::new();
    for &cascades in &args.cascades {
        for &voxel in &args.voxel_sizes {
            for &filter in &args.filters {
                for &samples in &args.samples {
                    let setting = RenderConfig {
                        particle_voxel_size: voxel,
                        particle_filter: filter,
                        particle_samples: samples,
                        particle_cascades: cascades,
                        particle_cascade_resolution: args.cascade_resolution,
                        ..config(ParticleMethod::Grid)
                    };
                    setting.validate(&ctx.device_limits())?;
                    settings.push(setting);
                }
            }
        }
    }
    let (without, _) = frame(config(ParticleMethod::Off))?;
    let (exact, exact_ldr) = frame(config(ParticleMethod::Bvh))?;
    let exact_light: f64 = exact.pixels.iter().zip(&without.pixels).map(|(e, w)| f64::from((luminance(e) - luminance(w)).abs())).sum();
    if exact_light <= 0.0 {
        bail!("the particles light nothing the camera sees at {} s; choose another --time or --camera", args.time);
    }
    println!("GPU: {}", ctx.describe());
    println!(
        "{} particles, {}×{}, {} s; error: Σ|grid − exact| / Σ|exact − no particles| (luminance), PSNR of the tonemapped image",
        particle_count(&scene),
        args.view.width,
        args.view.height,
        args.time
    );
    println!("{:>8} {:>8} {:>10} {:>8} {:>12} {:>9}", "cascades", "voxel m", "filter", "samples", "error %", "PSNR dB");
    for setting in settings {
        let (cascades, voxel, filter, samples) =
            (setting.particle_cascades, setting.particle_voxel_size, setting.particle_filter, setting.particle_samples);
        let (grid, grid_ldr) = frame(setting)?;
        let error: f64 = grid.pixels.iter().zip(&exact.pixels).map(|(g, e)| f64::from((luminance(g) - luminance(e)).abs())).sum();
        println!(
            "{cascades:>8} {voxel:>8} {:>10} {samples:>8} {:>12.2} {:>9.2}",
            filter.name(),
            100.0 * error / exact_light,
            psnr(&grid_ldr, &exact_ldr)
        );
    }
    Ok(())
}

fn particle_count(scene: &Scene) -> u32 {
    scene.particles.as_ref().map_or(0, |p| p.count)
}
