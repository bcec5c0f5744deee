//! One configuration measured: a renderer on the shared device, its first frames against the time cap,
//! the warm-up, then the timed frames' GPU passes and CPU recording times.

use std::time::Instant;

use manylights::{
    accel::overlap,
    gpu::GpuContext,
    plan::MethodChoice,
    renderer::{FrameTiming, Renderer},
    scene::{generators, Camera, Scene},
    settings::{DecalMethod, LightMethod, RenderConfig},
};

use super::Suite;
use crate::timing::{FrameSamples, Stat};

pub(crate) struct Plan {
    pub frames: u32,
    pub warmup: u32,
    pub time_cap_ms: f64,
}

/// A configuration and what came of it.
pub(crate) struct Measurement {
    pub suite: Suite,
    pub scene: String,
    pub lights: usize,
    pub decals: usize,
    /// Mean count of lights (light scenes) or decals reaching a surface point, after the exact test.
    pub overlap: Option<f64>,
    pub config: RenderConfig,
    pub outcome: Outcome,
}

impl Measurement {
    /// The method measured: of the decals where the scene has decals, else of the lights.
    pub fn method(&self) -> &'static str {
        method_name(&self.config)
    }

    pub fn same_method(&self, config: &RenderConfig) -> bool {
        self.method() == method_name(config) && self.config.pipeline == config.pipeline
    }
}

pub(crate) fn method_name(config: &RenderConfig) -> &'static str {
    match (config.light_method, config.decal_method) {
        (LightMethod::Off, DecalMethod::Off) => "off",
        (LightMethod::Off, decal) => decal.name(),
        (light, _) => light.name(),
    }
}

pub(crate) enum Outcome {
    Timed(Timing),
    /// The second frame's GPU time, over the cap like the first: not timed further.
    OverCap(f64),
    /// Not run, and why.
    Skipped(String),
    /// The renderer refused the configuration or failed; the error's message.
    Failed(String),
}

impl Outcome {
    pub fn is_timed(&self) -> bool {
        matches!(self, Outcome::Timed(_))
    }

    pub fn status(&self) -> &'static str {
        match self {
            Outcome::Timed(_) => "timed",
            Outcome::OverCap(_) => "over-cap",
            Outcome::Skipped(_) => "skipped",
            Outcome::Failed(_) => "failed",
        }
    }
}

/// The statistics of the timed frames.
pub(crate) struct Timing {
    pub frames: usize,
    /// Every pass, in frame order.
    pub passes: Vec<(&'static str, Stat)>,
    /// Per-frame sums of the passes of each [`PassGroup`] the frame has.
    pub groups: Vec<(PassGroup, Stat)>,
    pub gpu_frame: Stat,
    /// The CPU's time to record and submit a frame.
    pub cpu_frame: Stat,
    /// Wall-clock time per frame while the timed frames were submitted back to back.
    pub wall_ms_per_frame: f64,
    /// The light and decal methods that ran (`auto`'s choice, or those asked for).
    pub chosen: MethodChoice,
}

/// Passes summed into the columns of the tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PassGroup {
    /// Per-frame builds: BVHs rebuilt on the GPU and their items put in leaf order, clustered lists.
    Build,
    /// The pipeline's raster pass: visibility buffer, G-buffer or depth prepass.
    Raster,
    DeferredDecals,
    /// The opaque shading pass: visibility-buffer resolve, deferred lighting or forward shading.
    Shade,
    /// Everything else: transparent surfaces, tonemapping.
    Other,
}

impl PassGroup {
    pub const ALL: [PassGroup; 5] = [PassGroup::Build, PassGroup::Raster, PassGroup::DeferredDecals, PassGroup::Shade, PassGroup::Other];

    pub fn of(pass: &str) -> PassGroup {
        match pass {
            p if p.ends_with("_build") || p.ends_with("_leaf_order") => PassGroup::Build,
            "visbuffer_raster" | "gbuffer_raster" | "depth_prepass" => PassGroup::Raster,
            "deferred_decals" => PassGroup::DeferredDecals,
            "visbuffer_shade" | "deferred_shade" | "forward_shade" => PassGroup::Shade,
            _ => PassGroup::Other,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            PassGroup::Build => "build",
            PassGroup::Raster => "raster",
            PassGroup::DeferredDecals => "deferred_decals",
            PassGroup::Shade => "shade",
            PassGroup::Other => "other",
        }
    }
}

impl Timing {
    fn new(frames: &[FrameTiming], wall_ms_per_frame: f64, chosen: MethodChoice) -> Self {
        let samples = FrameSamples::new(frames);
        let passes = samples.passes.iter().map(|(name, s)| (*name, Stat::of(s))).collect();
        let groups = PassGroup::ALL
            .into_iter()
            .filter(|group| samples.passes.iter().any(|(name, _)| PassGroup::of(name) == *group))
            .map(|group| {
                let sums: Vec<f64> = frames
                    .iter()
                    .map(|f| f.passes.iter().filter(|(name, _)| PassGroup::of(name) == group).map(|(_, ms)| ms).sum())
                    .collect();
                (group, Stat::of(&sums))
            })
            .collect();
        Self {
            frames: frames.len(),
            passes,
            groups,
            gpu_frame: Stat::of(&samples.gpu_frame),
            cpu_frame: Stat::of(&samples.cpu_frame),
            wall_ms_per_frame,
            chosen,
        }
    }

    pub fn group(&self, group: PassGroup) -> Option<Stat> {
        self.groups.iter().find(|(g, _)| *g == group).map(|(_, s)| *s)
    }
}

/// Renders the configuration and times it; any error of the renderer is the outcome, not the end of
/// the run. The device must have timestamps (checked before the run).
pub(crate) fn measure(ctx: &GpuContext, scene: &Scene, camera: &Camera, config: RenderConfig, plan: &Plan) -> Outcome {
    match try_measure(ctx, scene, camera, config, plan) {
        Ok(outcome) => outcome,
        Err(e) => Outcome::Failed(e.to_string()),
    }
}

fn try_measure(ctx: &GpuContext, scene: &Scene, camera: &Camera, config: RenderConfig, plan: &Plan) -> manylights::Result<Outcome> {
    let mut renderer = Renderer::new(ctx.clone(), scene, config)?;
    // A first frame may pay one-time costs (lavapipe compiles shaders at their first dispatch), so
    // only two frames over the cap put a configuration over it.
    let mut warm = 0;
    for _ in 0..2 {
        let frame = renderer.render_frames(camera, 1)?;
        warm += 1;
        let ms = frame.first().map_or(0.0, FrameTiming::gpu_ms);
        if ms <= plan.time_cap_ms {
            break;
        }
        if warm == 2 {
            return Ok(Outcome::OverCap(ms));
        }
    }
    renderer.render_frames(camera, plan.warmup.saturating_sub(warm))?;
    let start = Instant::now();
    let frames = renderer.render_frames(camera, plan.frames)?;
    let wall_ms_per_frame = start.elapsed().as_secs_f64() * 1e3 / frames.len().max(1) as f64;
    Ok(Outcome::Timed(Timing::new(&frames, wall_ms_per_frame, renderer.methods_chosen())))
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Volumes {
    Lights,
    Decals,
}

/// The mean count of the scene's lights or decals reaching a surface point, after the exact test, at
/// seeded points spread by area.
pub(crate) fn mean_overlap(scene: &Scene, volumes: Volumes, seed: u64, points: usize) -> manylights::Result<f64> {
    let points = generators::surface_points(scene, points, seed);
    let result = match volumes {
        Volumes::Lights => overlap::light_overlap(scene, &points)?,
        Volumes::Decals => overlap::decal_overlap(scene, &points)?,
    };
    Ok(result.mean)
}
