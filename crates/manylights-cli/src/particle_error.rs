//! `manylights particle-error`: how far each particle-grid setting is from the exact method (the same
//! particles as point lights through the BVH), on a scene at one time: the particles' light in error,
//! relative to their exact light, and the PSNR of the tonemapped image. With `--restir-frames`, the
//! same for shadowed particle lights: `restir`, sampled and denoised, against the reference.

use anyhow::bail;
use clap::Args;
use manylights::{
    gpu::GpuContext,
    renderer::{Image, Renderer, FRAME_INTERVAL},
    scene::Scene,
    settings::{
        DecalMethod, Denoise, DirectLighting, LightMethod, ParticleFilter, ParticleMethod, RaySettings, RenderConfig, RestirCandidates,
    },
};

use crate::metrics::{luminance, psnr};
use crate::render::{choose_camera, MAX_FRAMES};
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
    /// Also measure shadowed particle lights: `restir` (temporal reuse; sampled, then denoised)
    /// after this many frames ending at --time, against the reference (a shadow ray per particle
    /// reaching a point). 0 leaves them out.
    #[arg(long, default_value_t = 0)]
    restir_frames: u32,
    /// Where those `restir` frames find their candidates.
    #[arg(long, value_enum, default_value_t = RestirCandidates::Auto)]
    restir_candidates: RestirCandidates,
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
    // restir's frames end at --time, one frame interval apart.
    if args.restir_frames > MAX_FRAMES {
        bail!("--restir-frames {}: give at most {MAX_FRAMES}", args.restir_frames);
    }
    let earliest = args.restir_frames.saturating_sub(1) as f32 * FRAME_INTERVAL;
    if args.time < earliest {
        bail!(
            "--restir-frames {} ending at --time {} s would start before time 0 (frames are {FRAME_INTERVAL:.4} s apart): give --time {earliest:.3} or later, or fewer frames",
            args.restir_frames,
            args.time
        );
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
    // A renderer that has drawn `frames` frames ending at --time.
    let rendered = |config: RenderConfig, frames: u32| -> anyhow::Result<Renderer> {
        let mut renderer = Renderer::new(ctx.clone(), &scene, config)?;
        renderer.time = args.time - frames.saturating_sub(1) as f32 * FRAME_INTERVAL;
        renderer.render_frames(&camera, frames)?;
        Ok(renderer)
    };
    let frame = |config: RenderConfig| -> anyhow::Result<Frame> {
        let renderer = rendered(config, 1)?;
        Ok((renderer.read_hdr()?, renderer.read_ldr()?))
    };
    let shadowed = |direct_lighting, denoise| RenderConfig {
        rays: RaySettings { direct_lighting, denoise, restir_candidates: args.restir_candidates, ..RaySettings::default() },
        ..config(ParticleMethod::Bvh)
    };
    if args.restir_frames > 0 {
        for denoise in [Denoise::Off, Denoise::Svgf] {
            shadowed(DirectLighting::Restir, denoise).validate(&ctx.device_limits())?;
        }
    }
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
    let exact_light = light_difference(&exact, &without);
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
        println!(
            "{cascades:>8} {voxel:>8} {:>10} {samples:>8} {:>12.2} {:>9.2}",
            filter.name(),
            100.0 * light_difference(&grid, &exact) / exact_light,
            psnr(&grid_ldr, &exact_ldr)
        );
    }
    if args.restir_frames == 0 {
        return Ok(());
    }
    // Shadowed: the particles' light is the reference's less the frame without particles, both with
    // every light shadowed.
    let (without, _) = frame(RenderConfig { particle_method: ParticleMethod::Off, ..shadowed(DirectLighting::Reference, Denoise::Off) })?;
    let (reference, reference_ldr) = frame(shadowed(DirectLighting::Reference, Denoise::Off))?;
    let shadowed_light = light_difference(&reference, &without);
    if shadowed_light <= 0.0 {
        bail!("the shadowed particles light nothing the camera sees at {} s; choose another --time or --camera", args.time);
    }
    println!(
        "shadowed: restir after {} frames against the reference; error: Σ|restir − reference| / Σ|reference − no particles|",
        args.restir_frames
    );
    println!("{:>10} {:>12} {:>12} {:>9}", "restir", "candidates", "error %", "PSNR dB");
    for denoise in [Denoise::Off, Denoise::Svgf] {
        let renderer = rendered(shadowed(DirectLighting::Restir, denoise), args.restir_frames)?;
        let candidates = if renderer.shading_methods().light_tree { RestirCandidates::Tree } else { RestirCandidates::Enumeration };
        let (restir, restir_ldr) = (renderer.read_hdr()?, renderer.read_ldr()?);
        println!(
            "{:>10} {:>12} {:>12.2} {:>9.2}",
            if denoise == Denoise::Off { "sampled" } else { "denoised" },
            candidates.name(),
            100.0 * light_difference(&restir, &reference) / shadowed_light,
            psnr(&restir_ldr, &reference_ldr)
        );
    }
    Ok(())
}

/// Σ |luminance(a) − luminance(b)| over the pixels.
fn light_difference(a: &Image<[f32; 4]>, b: &Image<[f32; 4]>) -> f64 {
    a.pixels.iter().zip(&b.pixels).map(|(p, q)| f64::from((luminance(p) - luminance(q)).abs())).sum()
}

fn particle_count(scene: &Scene) -> u32 {
    scene.particles.as_ref().map_or(0, |p| p.count)
}
