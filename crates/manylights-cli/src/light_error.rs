//! `manylights light-error`: how far `--direct-lighting restir`, as sampled and denoised, is from
//! `reference` (every light with a shadow ray of its own) on a scene, frame by frame, over a still
//! camera and along a camera moving sideways: FLIP (NVIDIA's perceptual difference, through the `nv-flip` crate) and PSNR of the
//! tonemapped images, the relative MSE of the linear ones, and the still camera's flicker from one
//! frame to the next. Both are tonemapped at one fixed exposure, the reference's middle grey.

use std::path::PathBuf;

use anyhow::bail;
use clap::Args;
use manylights::{
    files::{OutputFormat, OutputPlan, StagedOutputs},
    gpu::GpuContext,
    renderer::{Image, Renderer},
    scene::{Camera, Scene},
    settings::{Denoise, DirectLighting, Exposure, PostSettings, RaySettings, RenderConfig},
};

use crate::metrics::{luminance, mean_abs_difference, psnr};
use crate::render::{choose_camera, RayArgs};
use crate::scene_args::{ComparedView, SceneArgs};

/// A frame as linear radiance and tonemapped.
type Frame = (Image<[f32; 4]>, Image<[u8; 4]>);

/// Most frames along each camera path.
const MAX_FRAMES: u32 = 1024;

#[derive(Args)]
pub struct LightErrorArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    view: ComparedView,
    /// Frames rendered along each camera path (1 to 1,024): restir reuses what earlier frames kept.
    #[arg(long, default_value_t = 16)]
    frames: u32,
    /// How far the moving camera travels to its right over the frames, in metres [default: 2 % of the
    /// scene's diagonal]. 0 measures the still camera alone.
    #[arg(long, value_name = "METRES", allow_negative_numbers = true)]
    path_length: Option<f32>,
    /// The ray settings: `--restir-shadow-rays` and `--restir-reuse` shape restir; `--direct-lighting`
    /// is set for each image, and restir is measured both without the denoiser and with it.
    #[command(flatten)]
    rays: RayArgs,
    /// Write the figures, every frame's and their means, as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

/// One frame's error against the reference.
#[derive(Clone, Copy, Debug, serde::Serialize)]
struct FrameError {
    /// Mean FLIP of the tonemapped images, 0 (equal) to 1.
    flip: f64,
    /// Mean over pixels and channels of (restir − reference)² / (reference² + 0.01), linear.
    relative_mse: f64,
    /// PSNR of the tonemapped images, in dB.
    psnr: f64,
    /// Mean |frame − the frame before| of the tonemapped images' channels, 0 to 1 (still camera and scene only).
    flicker: Option<f64>,
}

/// A camera path's frames and their means.
#[derive(Debug, serde::Serialize)]
struct PathError {
    frames: Vec<FrameError>,
    mean: FrameError,
}

impl PathError {
    fn new(frames: Vec<FrameError>) -> Self {
        let n = frames.len() as f64;
        let mean = |f: fn(&FrameError) -> f64| frames.iter().map(f).sum::<f64>() / n;
        let flickers: Vec<f64> = frames.iter().filter_map(|f| f.flicker).collect();
        let mean = FrameError {
            flip: mean(|f| f.flip),
            relative_mse: mean(|f| f.relative_mse),
            psnr: mean(|f| f.psnr),
            flicker: (!flickers.is_empty()).then(|| flickers.iter().sum::<f64>() / flickers.len() as f64),
        };
        Self { frames, mean }
    }
}

pub fn run(args: &LightErrorArgs) -> anyhow::Result<()> {
    if !(1..=MAX_FRAMES).contains(&args.frames) {
        bail!("--frames {}: give 1 to {MAX_FRAMES}", args.frames);
    }
    if args.path_length.is_some_and(|l| !(l.is_finite() && l >= 0.0)) {
        bail!("--path-length {}: give a finite distance ≥ 0 in metres", args.path_length.unwrap_or_default());
    }
    let mut outputs = OutputPlan::new();
    if let Some(json) = &args.json {
        outputs.add("--json", json, &[OutputFormat::Json])?;
    }
    let ctx = GpuContext::new()?;
    let (scene, overlay) = args.scene.load(Some(&ctx))?;
    outputs.check_inputs(&scene.source_files)?;
    if scene.lights.is_empty() && scene.particles.as_ref().is_none_or(|p| p.count == 0) {
        bail!("the scene has no local lights to shadow; add them with --lights N (or a scene file's lights)");
    }
    let camera = choose_camera(&scene, args.view.camera)?;
    let rays = args.rays.settings(&overlay.rays)?;
    // The scene file's methods and particle settings, as `render` takes them.
    let config = |direct_lighting, denoise, exposure| {
        RenderConfig {
            width: args.view.width,
            height: args.view.height,
            pipeline: args.view.pipeline,
            light_method: overlay.methods.lights.unwrap_or_default(),
            decal_method: overlay.methods.decals.unwrap_or_default(),
            rays: RaySettings { direct_lighting, denoise, ..rays },
            post: PostSettings { exposure, ..PostSettings::default() },
            ..RenderConfig::default()
        }
        .with_particles(overlay.particles)
    };
    // Every setting is checked before the first frame, so a bad one fails at once.
    for direct_lighting in [DirectLighting::Reference, DirectLighting::Restir] {
        config(direct_lighting, Denoise::Svgf, Exposure::Fixed(1.0)).validate(&ctx.device_limits())?;
    }
    // One exposure for all: the reference's log-average luminance to middle grey.
    let mut reference = Renderer::new(ctx.clone(), &scene, config(DirectLighting::Reference, Denoise::Off, Exposure::Fixed(1.0)))?;
    reference.render(&camera)?;
    let exposure = Exposure::Fixed(middle_grey_scale(&reference.read_hdr()?));
    let mut reference = Renderer::new(ctx.clone(), &scene, config(DirectLighting::Reference, Denoise::Off, exposure))?;
    let path_length = args.path_length.unwrap_or(0.02 * scene.bounds().diagonal());
    let step = path_length / args.frames as f32;
    let camera_paths: &[(&str, &dyn Fn(u32) -> Camera)] =
        &[("still", &|_| camera.clone()), ("moving", &|frame| sideways(&camera, step * frame as f32))];
    let mut paths = Vec::new();
    for &(name, camera_at) in camera_paths.iter().filter(|(name, _)| path_length > 0.0 || *name == "still") {
        for denoise in [Denoise::Off, Denoise::Svgf] {
            let restir = config(DirectLighting::Restir, denoise, exposure);
            let error = measure(&ctx, &scene, &mut reference, restir, args.frames, camera_at)?;
            paths.push((name, denoise, error));
        }
    }

    println!("GPU: {}", ctx.describe());
    println!(
        "{}×{}, {} pipeline, restir with {} shadow ray(s) a pixel and {} reuse, against the reference; \
         the moving camera travels {path_length} m to its right",
        args.view.width,
        args.view.height,
        args.view.pipeline.name(),
        rays.restir_shadow_rays,
        rays.restir_reuse.name()
    );
    println!("{:<8} {:<8} {:>6} {:>8} {:>12} {:>9} {:>9}", "camera", "restir", "frame", "FLIP", "rel. MSE", "PSNR dB", "flicker");
    for (name, denoise, path) in &paths {
        for (i, frame) in path.frames.iter().enumerate() {
            print_row(name, denoise_key(*denoise), &(i + 1).to_string(), frame);
        }
        print_row(name, denoise_key(*denoise), "mean", &path.mean);
    }
    if let Some(path) = &args.json {
        let json = serde_json::json!({
            "device": ctx.describe(),
            "scene": args.scene.scene,
            "width": args.view.width,
            "height": args.view.height,
            "pipeline": args.view.pipeline.name(),
            "restir_shadow_rays": rays.restir_shadow_rays,
            "restir_reuse": rays.restir_reuse.name(),
            "path_length_m": path_length,
            "paths": json_paths(&paths)?,
        });
        let mut staged = StagedOutputs::new();
        staged.stage(path, serde_json::to_string_pretty(&json)?.as_bytes())?;
        staged.commit()?;
    }
    Ok(())
}

fn print_row(camera: &str, restir: &str, frame: &str, e: &FrameError) {
    let flicker = e.flicker.map_or(String::new(), |f| format!("{f:.5}"));
    println!("{camera:<8} {restir:<8} {frame:>6} {:>8.4} {:>12.5} {:>9.2} {flicker:>9}", e.flip, e.relative_mse, e.psnr);
}

/// How the figures name restir without and with the denoiser.
fn denoise_key(denoise: Denoise) -> &'static str {
    match denoise {
        Denoise::Off => "sampled",
        Denoise::Svgf => "denoised",
    }
}

/// `{camera path: {sampled: …, denoised: …}}`.
fn json_paths(paths: &[(&str, Denoise, PathError)]) -> anyhow::Result<serde_json::Value> {
    let mut json = serde_json::Map::new();
    for (name, denoise, path) in paths {
        let entry = json.entry(name.to_string()).or_insert_with(|| serde_json::json!({}));
        entry[denoise_key(*denoise)] = serde_json::to_value(path)?;
    }
    Ok(json.into())
}

/// `frames` frames of restir (`config`) along `camera_at(1..=frames)`, each against the reference.
fn measure(
    ctx: &GpuContext,
    scene: &Scene,
    reference: &mut Renderer,
    config: RenderConfig,
    frames: u32,
    camera_at: impl Fn(u32) -> Camera,
) -> anyhow::Result<PathError> {
    let mut restir = Renderer::new(ctx.clone(), scene, config)?;
    // The reference renders each frame at restir's time where the camera or the scene moves.
    let still = !scene.changes_over_time() && (1..=frames).all(|frame| camera_at(frame).world_from_view == camera_at(1).world_from_view);
    let mut expected: Option<Frame> = None;
    let mut previous: Option<Image<[u8; 4]>> = None;
    let mut errors = Vec::new();
    for frame in 1..=frames {
        let camera = camera_at(frame);
        if expected.is_none() || !still {
            reference.time = restir.time;
            reference.render(&camera)?;
            expected = Some((reference.read_hdr()?, reference.read_ldr()?));
        }
        restir.render(&camera)?;
        let (hdr, ldr) = (restir.read_hdr()?, restir.read_ldr()?);
        let (expected_hdr, expected_ldr) = expected.as_ref().expect("rendered above");
        errors.push(FrameError {
            flip: flip(expected_ldr, &ldr),
            relative_mse: relative_mse(&hdr, expected_hdr),
            psnr: psnr(&ldr, expected_ldr),
            flicker: previous.as_ref().filter(|_| still).map(|before| mean_abs_difference(&ldr, before)),
        });
        previous = Some(ldr);
    }
    Ok(PathError::new(errors))
}

/// `camera` moved `distance` metres to its right.
fn sideways(camera: &Camera, distance: f32) -> Camera {
    let right = camera.world_from_view.x_axis.truncate();
    Camera { world_from_view: glam::Mat4::from_translation(right * distance) * camera.world_from_view, ..camera.clone() }
}

/// The exposure scale that maps `image`'s log-average luminance to middle grey (0.18); 1 for a black
/// image.
fn middle_grey_scale(image: &Image<[f32; 4]>) -> f32 {
    let lit: Vec<f64> = image.pixels.iter().map(luminance).filter(|&l| l > 1e-6).map(|l| f64::from(l).ln()).collect();
    if lit.is_empty() {
        return 1.0;
    }
    (0.18 / (lit.iter().sum::<f64>() / lit.len() as f64).exp()) as f32
}

/// Mean FLIP of two tonemapped images, at FLIP's default 67 pixels per degree.
fn flip(reference: &Image<[u8; 4]>, test: &Image<[u8; 4]>) -> f64 {
    let rgb = |image: &Image<[u8; 4]>| {
        let bytes: Vec<u8> = image.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
        nv_flip::FlipImageRgb8::with_data(image.width, image.height, &bytes)
    };
    let error = nv_flip::flip(rgb(reference), rgb(test), nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    f64::from(nv_flip::FlipPool::from_image(&error).mean())
}

/// Mean over pixels and colour channels of (a − b)² / (b² + 0.01).
fn relative_mse(a: &Image<[f32; 4]>, b: &Image<[f32; 4]>) -> f64 {
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(p, q)| (0..3).map(move |c| f64::from(p[c] - q[c]).powi(2) / (f64::from(q[c]).powi(2) + 0.01)))
        .sum();
    sum / (a.pixels.len() * 3) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(pixels: Vec<[u8; 4]>) -> Image<[u8; 4]> {
        Image { width: pixels.len() as u32, height: 1, pixels }
    }

    #[test]
    fn equal_images_have_no_error_and_different_ones_some() {
        let a = image(vec![[10, 200, 30, 255]; 64]);
        let b = image(vec![[200, 10, 30, 255]; 64]);
        assert_eq!(flip(&a, &a), 0.0);
        assert!(flip(&a, &b) > 0.3, "{}", flip(&a, &b));
        assert!(psnr(&a, &a).is_infinite() && psnr(&a, &b) < 10.0);
        assert!((mean_abs_difference(&a, &b) - 2.0 * 190.0 / 255.0 / 3.0).abs() < 1e-9);
        let hdr = |v: f32| Image { width: 1, height: 1, pixels: vec![[v, v, v, 1.0]] };
        assert_eq!(relative_mse(&hdr(2.0), &hdr(2.0)), 0.0);
        assert!((relative_mse(&hdr(3.0), &hdr(2.0)) - 1.0 / 4.01).abs() < 1e-9);
    }

    #[test]
    fn the_exposure_maps_the_log_average_to_middle_grey() {
        let image = Image { width: 2, height: 1, pixels: vec![[1.0, 1.0, 1.0, 1.0], [4.0, 4.0, 4.0, 1.0]] };
        assert!((middle_grey_scale(&image) - 0.18 / 2.0).abs() < 1e-6);
        assert_eq!(middle_grey_scale(&Image { width: 1, height: 1, pixels: vec![[0.0; 4]] }), 1.0);
    }

    #[test]
    fn sideways_moves_the_camera_along_its_right() {
        let camera = Camera::look_at("c", glam::Vec3::new(0.0, 0.0, 4.0), glam::Vec3::ZERO, 1.0, 0.1);
        let moved = sideways(&camera, 2.0);
        assert!((moved.position() - glam::Vec3::new(2.0, 0.0, 4.0)).length() < 1e-6);
    }
}
