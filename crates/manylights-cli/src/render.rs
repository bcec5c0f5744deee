//! `manylights render`: load a scene, render frames, write images and timings.

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::Args;
use manylights::{
    files::{OutputFormat, OutputPlan, StagedOutputs},
    gpu::GpuContext,
    image_io,
    renderer::{FrameTiming, Renderer},
    scene::{Camera, Scene},
    settings::{
        AutoExposure, Bloom, BvhBuild, DebugView, DecalMethod, Denoise, DepthOfField, DirectLighting, Exposure, LightMethod, MotionBlur,
        ParticleFilter, ParticleMethod, ParticleOverlay, PipelineKind, PostSettings, RayBackend, RayOverlay, RaySettings, RenderConfig,
        RestirCandidates, RestirReuse, SunShadows, Tonemapper, EV100_RANGE, MAX_ANISOTROPY, MAX_COC_RADIUS, MAX_MOTION_BLUR_LENGTH,
        MAX_MOTION_BLUR_SAMPLES, MAX_REFLECTION_BOUNCES, MAX_RESTIR_SHADOW_RAYS, MAX_SHADOW_RAYS,
    },
};

use crate::progress;
use crate::scene_args::SceneArgs;
use crate::timing::{FrameSamples, Stat};

/// Most frames one run may time or warm up with: a few minutes even on a fast GPU.
pub(crate) const MAX_FRAMES: u32 = 100_000;

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[arg(long, default_value_t = RenderConfig::default().width)]
    width: u32,
    #[arg(long, default_value_t = RenderConfig::default().height)]
    height: u32,
    /// Camera index in the scene (glTF cameras, or the scene file's camera first); without cameras the
    /// scene is framed automatically.
    #[arg(long)]
    camera: Option<usize>,
    /// Frame graph: visibility buffer (shading in compute), deferred (G-buffer, lighting in compute)
    /// or forward (depth prepass, shading in fragments).
    #[arg(long, value_enum, default_value_t = RenderConfig::default().pipeline)]
    pipeline: PipelineKind,
    #[arg(long, value_enum, help = format!("How shading finds the local lights reaching a point: the fastest for the scene, pipeline and settings (auto: `info` and --timings say which and why), none (sun and ambient only), loop over all, point queries in a BVH, or per-froxel lists built every frame (clustered shading). [default: the scene file's, or {}]", RenderConfig::default().light_method))]
    light_method: Option<LightMethod>,
    /// How the light BVH is built (with --light-method bvh): once on the CPU, or every frame on the
    /// GPU (auto then weighs the rebuild).
    #[arg(long, value_enum, default_value_t = RenderConfig::default().light_bvh_build)]
    light_bvh_build: BvhBuild,
    #[arg(long, value_enum, help = format!("How shading finds the decals covering a point: the fastest for the scene (auto), none, loop over all, point queries in a BVH, per-froxel lists built every frame (clustered shading), or decal boxes rasterised into the G-buffer (deferred decals, --pipeline deferred only). [default: the scene file's, or {}]", RenderConfig::default().decal_method))]
    decal_method: Option<DecalMethod>,
    /// How the decal BVH is built (with --decal-method bvh): once on the CPU, or every frame on the
    /// GPU (auto then weighs the rebuild).
    #[arg(long, value_enum, default_value_t = RenderConfig::default().decal_bvh_build)]
    decal_bvh_build: BvhBuild,
    #[arg(long, value_enum, help = format!("How particle lights (--particles, or a scene file's [particles]) light the scene: not at all, through the 3D textures they are splatted into every frame, or exactly, as point lights in the lights' BVH rebuilt every frame (with --light-method bvh). [default: the scene file's, or {}]", RenderConfig::default().particle_method))]
    particle_method: Option<ParticleMethod>,
    #[arg(long, allow_negative_numbers = true, help = format!("Edge of the particle grid's voxels, in metres. [default: the scene file's, or {}]", RenderConfig::default().particle_voxel_size))]
    particle_voxel_size: Option<f32>,
    #[arg(long, value_enum, help = format!("How shading reads the particle grid: the voxel the point is in, the eight around it, or a cubic B-spline over 64 (smooth across voxel faces). [default: the scene file's, or {}]", RenderConfig::default().particle_filter))]
    particle_filter: Option<ParticleFilter>,
    #[arg(long, help = format!("Points around each shading point, within half a voxel, whose grid light is averaged (supersampling; 1 = the point alone). [default: the scene file's, or {}]", RenderConfig::default().particle_samples))]
    particle_samples: Option<u32>,
    #[arg(long, help = format!("Camera-centred clipmap cascades of the particle grid, each with voxels twice the size of the one before; 0 is one grid fixed over the whole scene, whose size grows with the world. [default: the scene file's, or {}]", RenderConfig::default().particle_cascades))]
    particle_cascades: Option<u32>,
    #[arg(long, help = format!("Voxels per axis of each particle cascade (even). [default: the scene file's, or {}]", RenderConfig::default().particle_cascade_resolution))]
    particle_cascade_resolution: Option<u32>,
    #[command(flatten)]
    rays: RayArgs,
    #[command(flatten)]
    post: PostArgs,
    #[arg(long, value_enum, default_value_t = RenderConfig::default().tonemapper)]
    tonemap: Tonemapper,
    /// Show, instead of radiance, a heat map of the lights reaching each point, of the light method's
    /// work (BVH nodes visited, cluster occupancy, lights tested) or of the decals covering it, the
    /// particle lights' radiance alone, or a horizontal slice through the particle grid.
    #[arg(long, value_enum, default_value_t = RenderConfig::default().debug_view)]
    debug_view: DebugView,
    /// Height in metres of the particle-grid-slice debug view's plane. [default: a metre below the eye]
    #[arg(long, allow_negative_numbers = true)]
    debug_slice_height: Option<f32>,
    /// Largest texture size kept on the GPU (larger images are downsampled).
    #[arg(long, default_value_t = RenderConfig::default().max_texture_size)]
    texture_size: u32,
    #[arg(long, default_value_t = RenderConfig::default().anisotropy, help = format!("Maximum anisotropy of texture filtering (1 = trilinear, up to {})", MAX_ANISOTROPY))]
    anisotropy: u16,
    /// Output image (tonemapped, sRGB): .png, or .jpg / .jpeg.
    #[arg(short, long, default_value = "out.png")]
    output: PathBuf,
    /// Also write linear HDR radiance as OpenEXR.
    #[arg(long)]
    exr: Option<PathBuf>,
    /// Print per-pass GPU times (median and p95 over the timed frames).
    #[arg(long)]
    timings: bool,
    /// Write per-pass GPU times and run details as JSON.
    #[arg(long)]
    timings_json: Option<PathBuf>,
    /// Frames to time (after the warm-up); the image is the last one.
    #[arg(long, default_value_t = 1)]
    frames: u32,
    /// Untimed frames before timing starts.
    #[arg(long, default_value_t = 0)]
    warmup: u32,
    /// Scene time of the first frame, in seconds: where the glTF animation, spinning groups and
    /// particles are (each frame adds 1/60 s).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    time: f32,
    /// Moves the camera at this velocity, in metres per second (x,y,z), from frame to frame: motion
    /// blur's camera motion. Each frame is then submitted and waited for on its own.
    #[arg(long, value_delimiter = ',', allow_negative_numbers = true, value_name = "X,Y,Z")]
    camera_velocity: Option<Vec<f32>>,
}

/// Post effects after shading, each off unless asked for; tonemapping is `--tonemap`.
#[derive(Args)]
pub(crate) struct PostArgs {
    #[arg(long, allow_negative_numbers = true, value_name = "EV100", help = format!("A fixed exposure, in EV100 ({} to {}; 0 maps a luminance of 1.2 to white, each step up halves the image's brightness) instead of measuring each frame's. [default: the scene file's `exposure`, or auto]", EV100_RANGE.0, EV100_RANGE.1))]
    exposure: Option<f32>,
    /// Measure the exposure from each frame's luminance histogram (of the surfaces in view, or the
    /// background where none is) even where the scene file fixes one (without a scene file's
    /// `exposure` or --exposure, frames are exposed so anyway).
    #[arg(long, conflicts_with = "exposure")]
    auto_exposure: bool,
    #[arg(long, conflicts_with = "exposure", allow_negative_numbers = true, help = format!("Stops brighter (+) or darker (−) than auto exposure's middle grey. [default: {}]", AutoExposure::default().compensation_ev))]
    exposure_compensation: Option<f32>,
    #[arg(long, conflicts_with = "exposure", allow_negative_numbers = true, help = format!("How fast auto exposure follows the image, per second (the first frame takes it at once). [default: {}]", AutoExposure::default().adaptation_speed))]
    exposure_adaptation: Option<f32>,
    /// Bloom: the image blurred over a chain of half-resolution levels, blended over it.
    #[arg(long)]
    bloom: bool,
    #[arg(long, requires = "bloom", allow_negative_numbers = true, help = format!("Bloom's share of the image, above 0 and at most 1. [default: {}]", Bloom::default().intensity))]
    bloom_intensity: Option<f32>,
    /// Depth of field of a thin lens with the camera's field of view on a 24 mm-high sensor.
    #[arg(long)]
    depth_of_field: bool,
    /// Distance in focus, in metres. [default: what the image's centre shows]
    #[arg(long, requires = "depth_of_field", allow_negative_numbers = true)]
    focus_distance: Option<f32>,
    #[arg(long, requires = "depth_of_field", allow_negative_numbers = true, help = format!("The lens's f-number: lower is shallower. [default: {}]", DepthOfField::default().f_number))]
    f_number: Option<f32>,
    #[arg(long, requires = "depth_of_field", allow_negative_numbers = true, help = format!("Largest circle of confusion's radius, in pixels, 1 to {}. [default: {}]", MAX_COC_RADIUS, DepthOfField::default().max_radius))]
    max_coc: Option<f32>,
    /// Motion blur from per-pixel velocities: the camera's motion between frames and animated
    /// instances' (glTF animation) over the frame interval.
    #[arg(long)]
    motion_blur: bool,
    #[arg(long, requires = "motion_blur", allow_negative_numbers = true, help = format!("Shutter time as a fraction of the frame interval (0.5: a 180° shutter). [default: {}]", MotionBlur::default().shutter))]
    shutter: Option<f32>,
    #[arg(long, requires = "motion_blur", help = format!("Samples per pixel along the blur, 1 to {}. [default: {}]", MAX_MOTION_BLUR_SAMPLES, MotionBlur::default().samples))]
    motion_blur_samples: Option<u32>,
    #[arg(long, requires = "motion_blur", allow_negative_numbers = true, help = format!("Longest blur, in pixels, 1 to {}. [default: {}]", MAX_MOTION_BLUR_LENGTH, MotionBlur::default().max_length))]
    max_motion_blur: Option<f32>,
    /// Natural vignetting: 0 none, 1 the cos⁴ falloff of a real lens.
    #[arg(long, default_value_t = PostSettings::default().vignette, allow_negative_numbers = true)]
    vignette: f32,
}

impl PostArgs {
    /// The post settings, exposed as the command line, then the scene file (`scene_exposure`), asks.
    pub(crate) fn settings(&self, scene_exposure: Option<f32>) -> anyhow::Result<PostSettings> {
        let auto = AutoExposure::default();
        let bloom = Bloom::default();
        let dof = DepthOfField::default();
        let blur = MotionBlur::default();
        if let Some(ev100) = self.exposure.filter(|ev| !(EV100_RANGE.0..=EV100_RANGE.1).contains(ev)) {
            bail!(
                "--exposure {ev100}: give an EV100 from {} to {} (or leave it out to expose automatically)",
                EV100_RANGE.0,
                EV100_RANGE.1
            );
        }
        Ok(PostSettings {
            exposure: Exposure::chosen(
                self.exposure,
                self.auto_exposure,
                scene_exposure,
                AutoExposure {
                    compensation_ev: self.exposure_compensation.unwrap_or(auto.compensation_ev),
                    adaptation_speed: self.exposure_adaptation.unwrap_or(auto.adaptation_speed),
                },
            ),
            bloom: self.bloom.then(|| Bloom { intensity: self.bloom_intensity.unwrap_or(bloom.intensity) }),
            depth_of_field: self.depth_of_field.then(|| DepthOfField {
                focus_distance: self.focus_distance,
                f_number: self.f_number.unwrap_or(dof.f_number),
                max_radius: self.max_coc.unwrap_or(dof.max_radius),
            }),
            motion_blur: self.motion_blur.then(|| MotionBlur {
                shutter: self.shutter.unwrap_or(blur.shutter),
                samples: self.motion_blur_samples.unwrap_or(blur.samples),
                max_length: self.max_motion_blur.unwrap_or(blur.max_length),
            }),
            vignette: self.vignette,
        })
    }
}

/// Ray-traced effects; each overrides the scene file's `[rays]`.
#[derive(Args)]
pub(crate) struct RayArgs {
    #[arg(long, value_enum, help = format!("Sun shadows by rays from every pixel: none, one ray to the sun's centre, or rays to points of its disc (--shadow-rays) and a spatial filter. [default: the scene file's, or {}]", RaySettings::default().sun_shadows))]
    shadows: Option<SunShadows>,
    #[arg(long, allow_negative_numbers = true, help = format!("The sun's angular diameter in degrees: the width of soft shadows' penumbrae. [default: the scene file's, or {}]", RaySettings::default().sun_angle_degrees))]
    sun_angle: Option<f32>,
    #[arg(long, help = format!("Rays per pixel towards the sun's disc with --shadows soft (1 to {}). [default: the scene file's, or {}]", MAX_SHADOW_RAYS, RaySettings::default().shadow_rays))]
    shadow_rays: Option<u32>,
    /// Ray-traced reflections on glossy surfaces, their hits shaded by the full shading core.
    #[arg(long)]
    reflections: bool,
    #[arg(long, requires = "reflections", help = format!("Reflection bounces with --reflections (1 to {}). [default: the scene file's, or 1]", MAX_REFLECTION_BOUNCES))]
    bounces: Option<u32>,
    #[arg(long, allow_negative_numbers = true, help = format!("Surfaces below this perceptual roughness reflect (above 0, at most 1). [default: the scene file's, or {}]", RaySettings::default().reflection_roughness))]
    reflection_roughness: Option<f32>,
    #[arg(long, help = format!("Shadow rays each shading point may trace towards local lights that cast shadows (glTF and scene-file lights; scattered ones do not), 0 to {}, in the order the light method finds them. [default: the scene file's, or {}]", MAX_SHADOW_RAYS, RaySettings::default().light_shadow_rays))]
    light_shadow_rays: Option<u32>,
    #[arg(long, value_enum, help = format!("How local lights light a point: every light found, unshadowed but for --light-shadow-rays (exact); every light with its own shadow ray, the ground truth (reference); or resampled importance sampling with --restir-shadow-rays shadow rays (restir). [default: the scene file's, or {}]", RaySettings::default().direct_lighting))]
    direct_lighting: Option<DirectLighting>,
    #[arg(long, help = format!("Samples per shading point with --direct-lighting restir, each with one shadow ray (1 to {}). [default: the scene file's, or {}]", MAX_RESTIR_SHADOW_RAYS, RaySettings::default().restir_shadow_rays))]
    restir_shadow_rays: Option<u32>,
    #[arg(long, value_enum, help = format!("What --direct-lighting restir reuses at each pixel's surface from the frame before: nothing, its own reservoir (found by reprojection), or that and its neighbours'. [default: the scene file's, or {}]", RaySettings::default().restir_reuse))]
    restir_reuse: Option<RestirReuse>,
    #[arg(long, value_enum, help = format!("Where --direct-lighting restir finds its candidates at a point: every light the light method finds there (enumeration), a few drawn through the lights' BVH by their estimated light (tree: the same cost however many lights reach; bvh lights, particle lights too), or by the scene's light density (auto). [default: the scene file's, or {}]", RaySettings::default().restir_candidates))]
    restir_candidates: Option<RestirCandidates>,
    #[arg(long, value_enum, help = format!("How --direct-lighting restir's lighting is denoised at the pixels' opaque surfaces: not at all, for error studies (off), or by temporal accumulation and a variance-guided spatial filter (svgf). [default: the scene file's, or {}]", RaySettings::default().denoise))]
    denoise: Option<Denoise>,
    #[arg(long, value_enum, help = format!("What traces the bvh lights' and decals' point queries and every ray (shadows, reflections, restir's): the GPU's ray queries through acceleration structures wgpu builds (hardware: an error where the adapter has none), manylights' own BVHs in WGSL (software), or hardware where the GPU runs ray queries and software where it has none or a CPU adapter such as lavapipe emulates them (auto; `manylights info` says which). [default: the scene file's, or {}]", RaySettings::default().backend))]
    ray_backend: Option<RayBackend>,
}

impl RayArgs {
    /// The command line's choices over `file`'s (the scene file's `[rays]`), over the defaults.
    pub(crate) fn settings(&self, file: &RayOverlay) -> anyhow::Result<RaySettings> {
        let reflection_bounces = match (self.reflections, self.bounces) {
            (true, Some(0)) => {
                bail!("--bounces 0 would trace no reflections: give 1 to {MAX_REFLECTION_BOUNCES}, or leave out --reflections")
            }
            (true, bounces) => Some(bounces.or(file.reflection_bounces.filter(|&b| b > 0)).unwrap_or(1)),
            (false, _) => None,
        };
        let command_line = RayOverlay {
            sun_shadows: self.shadows,
            sun_angle_degrees: self.sun_angle,
            shadow_rays: self.shadow_rays,
            reflection_bounces,
            reflection_roughness: self.reflection_roughness,
            light_shadow_rays: self.light_shadow_rays,
            direct_lighting: self.direct_lighting,
            restir_shadow_rays: self.restir_shadow_rays,
            restir_reuse: self.restir_reuse,
            restir_candidates: self.restir_candidates,
            denoise: self.denoise,
            backend: self.ray_backend,
        };
        Ok(command_line.over(*file).settings())
    }
}

pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    if !(1..=MAX_FRAMES).contains(&args.frames) || args.warmup > MAX_FRAMES {
        bail!("--frames must be between 1 and {MAX_FRAMES} and --warmup at most {MAX_FRAMES} (got {} and {})", args.frames, args.warmup);
    }
    // Every output is checked before the scene loads, and against its files once it has.
    let mut outputs = OutputPlan::new();
    let image_format = outputs.add("-o", &args.output, &OutputFormat::IMAGES)?;
    if let Some(exr) = &args.exr {
        outputs.add("--exr", exr, &[OutputFormat::Exr])?;
    }
    if let Some(json) = &args.timings_json {
        outputs.add("--timings-json", json, &[OutputFormat::Json])?;
    }
    let ctx = GpuContext::new()?;
    let (scene, overlay) = args.scene.load(Some(&ctx))?;
    outputs.check_inputs(&scene.source_files)?;
    let camera = choose_camera(&scene, args.camera)?;
    let particles = ParticleOverlay {
        method: args.particle_method,
        voxel_size: args.particle_voxel_size,
        filter: args.particle_filter,
        samples: args.particle_samples,
        cascades: args.particle_cascades,
        cascade_resolution: args.particle_cascade_resolution,
    };
    let config = RenderConfig {
        width: args.width,
        height: args.height,
        pipeline: args.pipeline,
        light_method: args.light_method.or(overlay.methods.lights).unwrap_or_default(),
        light_bvh_build: args.light_bvh_build,
        decal_method: args.decal_method.or(overlay.methods.decals).unwrap_or_default(),
        decal_bvh_build: args.decal_bvh_build,
        tonemapper: args.tonemap,
        max_texture_size: args.texture_size,
        anisotropy: args.anisotropy,
        rays: args.rays.settings(&overlay.rays)?,
        post: args.post.settings(overlay.exposure)?,
        debug_view: args.debug_view,
        debug_slice_height: args.debug_slice_height,
        ..RenderConfig::default()
    }
    // The command line first, then the scene file, then the defaults.
    .with_particles(particles.over(overlay.particles));

    let device = ctx.describe();
    let mut renderer = {
        let _step = progress::step("building the renderer (structures, shaders)");
        Renderer::new(ctx, &scene, config)?
    };
    if (args.timings || args.timings_json.is_some()) && !renderer.has_timestamps() {
        bail!("--timings needs GPU timestamp queries, which this adapter lacks ({device}); run without --timings");
    }
    if !args.time.is_finite() {
        bail!("--time {} must be a finite number of seconds", args.time);
    }
    renderer.time = args.time;
    let _step = progress::step(format!("rendering {} frame(s) after {} warm-up", args.frames, args.warmup));
    let frames = match &args.camera_velocity {
        None => {
            renderer.render_frames(&camera, args.warmup)?;
            renderer.render_frames(&camera, args.frames)?
        }
        Some(velocity) => {
            let &[x, y, z] = &velocity[..] else {
                bail!("--camera-velocity takes three numbers, x,y,z in metres per second; got {}", velocity.len());
            };
            let velocity = glam::Vec3::new(x, y, z);
            if !velocity.is_finite() {
                bail!("--camera-velocity {velocity} must be finite metres per second");
            }
            let mut frames = Vec::with_capacity(args.frames as usize);
            for frame in 0..args.warmup + args.frames {
                let offset = velocity * (frame as f32 * manylights::renderer::FRAME_INTERVAL);
                let moved = Camera { world_from_view: glam::Mat4::from_translation(offset) * camera.world_from_view, ..camera.clone() };
                let timing = renderer.render_frames(&moved, 1)?;
                if frame >= args.warmup {
                    frames.extend(timing);
                }
            }
            frames
        }
    };

    drop(_step);
    // All written together at the end: a failure leaves every earlier file as it was.
    let mut staged = StagedOutputs::new();
    let encoded =
        |path: &std::path::Path, bytes: image::ImageResult<Vec<u8>>| bytes.with_context(|| format!("cannot encode {}", path.display()));
    staged.stage(&args.output, &encoded(&args.output, image_io::encode_ldr(&renderer.read_ldr()?, image_format))?)?;
    if let Some(exr) = &args.exr {
        staged.stage(exr, &encoded(exr, image_io::encode_exr(&renderer.read_hdr()?))?)?;
    }
    let report = TimingReport::new(&frames);
    if let Some(path) = &args.timings_json {
        let json = report.to_json(&device, args, &renderer, &scene);
        staged.stage(path, serde_json::to_string_pretty(&json)?.as_bytes())?;
    }
    staged.commit()?;
    if args.timings {
        report.print(&device, args, &renderer, &scene);
    }
    println!("wrote {}", args.output.display());
    Ok(())
}

pub(crate) fn choose_camera(scene: &Scene, index: Option<usize>) -> anyhow::Result<Camera> {
    match (index, scene.cameras.len()) {
        (Some(i), n) if i >= n => {
            bail!("--camera {i}: the scene has {n} camera(s){}", if n > 0 { format!(", numbered 0 to {}", n - 1) } else { String::new() })
        }
        (Some(i), _) => Ok(scene.cameras[i].clone()),
        (None, 0) => {
            let bounds = scene.bounds();
            Ok(if bounds.is_empty() {
                Camera::look_at("auto", glam::Vec3::new(0.0, 1.0, 5.0), glam::Vec3::ZERO, 60f32.to_radians(), 0.05)
            } else {
                Camera::framing(&bounds)
            })
        }
        (None, _) => Ok(scene.cameras[0].clone()),
    }
}

/// Per-pass statistics over the timed frames.
struct TimingReport {
    samples: FrameSamples,
}

impl TimingReport {
    fn new(frames: &[FrameTiming]) -> Self {
        Self { samples: FrameSamples::new(frames) }
    }

    fn print(&self, device: &str, args: &RenderArgs, renderer: &Renderer, scene: &Scene) {
        println!("GPU: {device}");
        println!(
            "{}×{}, {} triangles, {} lights, {} decals{}, {} timed frames after {} warm-up",
            args.width,
            args.height,
            renderer.scene.triangle_count,
            scene.lights.len(),
            scene.decals.len(),
            if is_animated(scene) { " (animated)" } else { "" },
            args.frames,
            args.warmup
        );
        let chosen = renderer.methods_chosen();
        println!(
            "{} pipeline; lights: {}; decals: {}; ray backend: {}",
            renderer.config.pipeline.name(),
            chosen.lights,
            chosen.decals,
            renderer.ray_tracer()
        );
        if let Some(particles) = scene.particles.as_ref().filter(|p| p.count > 0) {
            let config = &renderer.config;
            let grid = match (config.particle_method, config.particle_cascades) {
                (ParticleMethod::Grid, 0) => {
                    format!(", {} m voxels over the scene, {}", config.particle_voxel_size, config.particle_filter.name())
                }
                (ParticleMethod::Grid, cascades) => format!(
                    ", {cascades} cascades of {}³ from {} m voxels, {}",
                    config.particle_cascade_resolution,
                    config.particle_voxel_size,
                    config.particle_filter.name()
                ),
                _ => String::new(),
            };
            println!("{} particles, method {}{grid}", particles.count, config.particle_method.name());
        }
        let rays = &renderer.config.rays;
        if let Some(built) = renderer.ray_structure() {
            println!(
                "ray hierarchy: {} triangles in {} instances, {} nodes; CPU build: BLASes {:.1} ms, TLAS {:.3} ms",
                built.triangles, built.instances, built.nodes, built.blas_build_ms, built.tlas_build_ms
            );
            println!(
                "sun shadows {}{}, direct lighting {}, reflections: {}",
                rays.sun_shadows.name(),
                if rays.sun_shadows == SunShadows::Soft {
                    format!(" ({} rays, sun {}°)", rays.shadow_rays, rays.sun_angle_degrees)
                } else {
                    String::new()
                },
                match rays.direct_lighting {
                    DirectLighting::Exact => format!("exact ({} light shadow rays)", rays.light_shadow_rays),
                    DirectLighting::Reference => "reference (a shadow ray per light)".into(),
                    DirectLighting::Restir => format!(
                        "restir ({} shadow rays, {} reuse, candidates {}, denoise {})",
                        rays.restir_shadow_rays,
                        rays.restir_reuse,
                        restir_candidates(renderer),
                        rays.denoise
                    ),
                },
                if rays.reflection_bounces > 0 {
                    format!("{} bounce(s) below roughness {}", rays.reflection_bounces, rays.reflection_roughness)
                } else {
                    "off".into()
                }
            );
        }
        println!("{:<20} {:>10} {:>10}", "pass", "median ms", "p95 ms");
        let line = |name: &str, samples: &[f64]| {
            let Stat { median, p95 } = Stat::of(samples);
            println!("{name:<20} {median:>10.3} {p95:>10.3}");
        };
        for (name, samples) in &self.samples.passes {
            line(name, samples);
        }
        line("frame (sum)", &self.samples.gpu_frame);
        line("cpu (record)", &self.samples.cpu_frame);
    }

    fn to_json(&self, device: &str, args: &RenderArgs, renderer: &Renderer, scene: &Scene) -> serde_json::Value {
        let pass = |samples: &[f64]| {
            let Stat { median, p95 } = Stat::of(samples);
            serde_json::json!({ "median_ms": median, "p95_ms": p95, "samples_ms": samples })
        };
        let passes: serde_json::Map<String, serde_json::Value> =
            self.samples.passes.iter().map(|(n, s)| (n.to_string(), pass(s))).collect();
        serde_json::json!({
            "device": device,
            "commit": env!("MANYLIGHTS_COMMIT"),
            "scene": args.scene.scene,
            "width": args.width,
            "height": args.height,
            "triangles": renderer.scene.triangle_count,
            "lights": scene.lights.len(),
            "pipeline": renderer.config.pipeline.name(),
            "light_method": renderer.config.light_method.name(),
            "light_method_why": renderer.methods_chosen().lights.to_string(),
            "decals": scene.decals.len(),
            "decal_method": renderer.config.decal_method.name(),
            "decal_method_why": renderer.methods_chosen().decals.to_string(),
            "animated": is_animated(scene),
            "particles": particles_json(renderer, scene),
            "rays": rays_json(renderer),
            "post": post_json(&renderer.config.post, args.camera_velocity.as_deref()),
            "warmup_frames": args.warmup,
            "timed_frames": args.frames,
            "passes": passes,
            "frame": pass(&self.samples.gpu_frame),
            "cpu_frame": pass(&self.samples.cpu_frame),
        })
    }
}

/// The post effects that ran, each null when off, and the camera's velocity.
fn post_json(post: &PostSettings, camera_velocity: Option<&[f32]>) -> serde_json::Value {
    serde_json::json!({
        "exposure": match post.exposure {
            Exposure::Auto(a) => serde_json::json!({
                "auto": { "compensation_ev": a.compensation_ev, "adaptation_speed": a.adaptation_speed },
            }),
            Exposure::Fixed(scale) => serde_json::json!({ "fixed_scale": scale }),
        },
        "bloom": post.bloom.map(|b| serde_json::json!({ "intensity": b.intensity })),
        "depth_of_field": post.depth_of_field.map(|d| serde_json::json!({
            "focus_distance": d.focus_distance,
            "f_number": d.f_number,
            "max_radius": d.max_radius,
        })),
        "motion_blur": post.motion_blur.map(|m| serde_json::json!({
            "shutter": m.shutter,
            "samples": m.samples,
            "max_length": m.max_length,
        })),
        "vignette": post.vignette,
        "camera_velocity": camera_velocity,
    })
}

/// The particles and how they were rendered; null without particles.
fn particles_json(renderer: &Renderer, scene: &Scene) -> serde_json::Value {
    let Some(particles) = scene.particles.as_ref().filter(|p| p.count > 0) else { return serde_json::Value::Null };
    let config = &renderer.config;
    let mut json = serde_json::json!({
        "count": particles.count,
        "emitters": particles.emitters.len(),
        "method": config.particle_method.name(),
    });
    if config.particle_method == ParticleMethod::Grid {
        json["voxel_size"] = config.particle_voxel_size.into();
        json["filter"] = config.particle_filter.name().into();
        json["samples"] = config.particle_samples.into();
        json["cascades"] = config.particle_cascades.into();
        if config.particle_cascades > 0 {
            json["cascade_resolution"] = config.particle_cascade_resolution.into();
        }
    }
    json
}

/// The ray-traced effects, their budgets, and the hierarchy built for them.
/// Where `restir`'s candidates came from, `auto` resolved.
fn restir_candidates(renderer: &Renderer) -> &'static str {
    if renderer.shading_methods().light_tree {
        RestirCandidates::Tree.name()
    } else {
        RestirCandidates::Enumeration.name()
    }
}

fn rays_json(renderer: &Renderer) -> serde_json::Value {
    let rays = &renderer.config.rays;
    let mut json = serde_json::json!({
        "shadows": rays.sun_shadows.name(),
        "sun_angle_degrees": rays.sun_angle_degrees,
        "shadow_rays": rays.shadow_rays,
        "reflection_bounces": rays.reflection_bounces,
        "reflection_roughness": rays.reflection_roughness,
        "light_shadow_rays": rays.light_shadow_rays,
        "direct_lighting": rays.direct_lighting.name(),
        "restir_shadow_rays": rays.restir_shadow_rays,
        "restir_reuse": rays.restir_reuse.name(),
        "restir_candidates": restir_candidates(renderer),
        "denoise": rays.denoise.name(),
        "backend": renderer.ray_tracer().name(),
    });
    if let Some(built) = renderer.ray_structure() {
        json["hierarchy"] = serde_json::json!({
            "triangles": built.triangles,
            "instances": built.instances,
            "nodes": built.nodes,
            "blas_build_ms": built.blas_build_ms,
            "tlas_build_ms": built.tlas_build_ms,
        });
    }
    json
}

fn is_animated(scene: &Scene) -> bool {
    scene.light_groups.is_animated() || scene.decal_groups.is_animated()
}
