//! `manylights bench`: the paper's Table 1 (Hansen & Peters 2021) over every pipeline and method,
//! scaling sweeps of lights and decals from 1k to 1M, and their report (Markdown, JSON, CSV, PNG).
//!
//! One device serves every configuration (`measure.rs`); each gets a fresh renderer, a warm-up and
//! timed frames, or is reported over the time cap or failed (its scene could not be generated, or the
//! renderer refused it), and the run goes on. `report.rs` writes
//! the files, `plot.rs` the sweep plots.

mod measure;
mod plot;
mod report;

use std::path::PathBuf;

use anyhow::{bail, Context};
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use manylights::{
    files::OutputPlan,
    gpu::GpuContext,
    plan::{Capabilities, RayTracer},
    scene::{
        self,
        generators::{self, ScatterDecals, ScatterLights},
        paper_scenes::{PaperScene, PAPER_DECAL_SIZE, SMALL_LIGHT_RANGE},
        Camera, Scene,
    },
    settings::{BvhBuild, DecalMethod, Exposure, LightMethod, Named, PipelineKind, PostSettings, RayBackend, RaySettings, RenderConfig},
};

use crate::render::choose_camera;
use measure::{Measurement, Plan};

/// Sponza from the shared assets, where the repository's own scene files find it.
const DEFAULT_SCENE: &str = "../shared/assets/sponza/Sponza.gltf";
/// The sweeps' first count; each step multiplies it by 4.
const SWEEP_START: u32 = 1024;
/// Points on the surfaces at which the mean overlap of a configuration is counted.
const OVERLAP_POINTS: usize = 20_000;

#[derive(Args)]
pub struct BenchArgs {
    /// Base scene on which the paper's scenes and the sweeps are generated: a .gltf, .glb or .toml
    /// file, or `demo` (built in).
    #[arg(long, default_value = DEFAULT_SCENE)]
    scene: String,
    /// Camera index in the scene (default: its first camera, or a framing one without cameras).
    #[arg(long)]
    camera: Option<usize>,
    #[arg(long, default_value_t = 1920)]
    width: u32,
    #[arg(long, default_value_t = 1080)]
    height: u32,
    /// A short run: 10 frames after 2 warm-up frames, sweeps up to 16k.
    #[arg(long)]
    quick: bool,
    /// Frames timed per configuration [default: 100; with --quick 10].
    #[arg(long)]
    frames: Option<u32>,
    /// Untimed frames before timing [default: 20; with --quick 2].
    #[arg(long)]
    warmup: Option<u32>,
    /// The paper's scenes to run, comma-separated, or `none` [default: all].
    #[arg(long, value_enum, value_delimiter = ',')]
    scenes: Vec<SceneChoice>,
    /// Pipelines of the table, comma-separated [default: all].
    #[arg(long, value_enum, value_delimiter = ',')]
    pipelines: Vec<PipelineKind>,
    /// Methods of the table, comma-separated; each runs where it applies (deferred decals: decal
    /// scenes in the deferred pipeline) [default: all]. `off` gives each pipeline's baseline row.
    #[arg(long, value_enum, value_delimiter = ',')]
    methods: Vec<DecalMethod>,
    /// Scaling sweeps to run, comma-separated, or `none` [default: lights,decals].
    #[arg(long, value_enum, value_delimiter = ',')]
    sweeps: Vec<SweepArg>,
    /// Largest count of the sweeps, which go from 1,024 up by factors of 4 [default: 1048576; with
    /// --quick 16384].
    #[arg(long)]
    sweep_max: Option<u32>,
    /// Dense-light scenes to run, comma-separated, or `none` [default: all]: the paper's small lights
    /// and lights sized for overlaps of about 10, 50 and 100, in every pipeline, with bvh built once
    /// and rebuilt every frame, clustered shading and auto.
    #[arg(long, value_enum, value_delimiter = ',')]
    dense: Vec<DenseArg>,
    /// Pipeline of the sweeps.
    #[arg(long, value_enum, default_value_t = PipelineKind::Visbuffer)]
    sweep_pipeline: PipelineKind,
    /// How the sweeps' bvh is built: every frame on the GPU, as for anything that moves, or once on
    /// the CPU at load (clustered lists are built every frame either way).
    #[arg(long, value_enum, default_value_t = BvhBuild::GpuEveryFrame)]
    sweep_build: BvhBuild,
    /// A configuration whose first two frames each take longer than this on the GPU is reported over
    /// the cap and not timed further (brute force on large counts); in a sweep, larger counts of that
    /// method are skipped.
    #[arg(long, default_value_t = 500.0, allow_negative_numbers = true)]
    time_cap_ms: f64,
    /// Seed of the generated lights and decals.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Largest texture size kept on the GPU.
    #[arg(long, default_value_t = 1024)]
    texture_size: u32,
    /// Maximum anisotropy of texture filtering (1 = trilinear).
    #[arg(long, default_value_t = 8)]
    anisotropy: u16,
    /// What traces the bvh methods' point queries: the GPU's ray queries (hardware), our own BVHs
    /// (software), or hardware where the GPU runs ray queries (auto: not where a CPU emulates them).
    #[arg(long, value_enum, default_value_t = RayBackend::Auto)]
    ray_backend: RayBackend,
    /// Folder for bench.md, bench.json, bench.csv and the sweep plots (created if missing).
    #[arg(short, long, default_value = "bench-results")]
    out: PathBuf,
}

/// The dense-light scenes of `--dense`: 28,000 lights of the paper's small range, or of a range found
/// for a mean overlap.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum DenseArg {
    SmallLights,
    #[value(name = "overlap-10")]
    Overlap10,
    #[value(name = "overlap-50")]
    Overlap50,
    #[value(name = "overlap-100")]
    Overlap100,
    None,
}

impl DenseArg {
    /// The mean overlap aimed at; `None` for the paper's range.
    fn target_overlap(self) -> Option<f64> {
        match self {
            DenseArg::Overlap10 => Some(10.0),
            DenseArg::Overlap50 => Some(50.0),
            DenseArg::Overlap100 => Some(100.0),
            DenseArg::SmallLights | DenseArg::None => None,
        }
    }

    fn name(self) -> &'static str {
        match self {
            DenseArg::SmallLights => "small-lights",
            DenseArg::Overlap10 => "overlap-10",
            DenseArg::Overlap50 => "overlap-50",
            DenseArg::Overlap100 => "overlap-100",
            DenseArg::None => "none",
        }
    }
}

/// Lights of the dense scenes: as many as the paper's small lights.
const DENSE_LIGHTS: usize = 28_000;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum SweepArg {
    Lights,
    Decals,
    None,
}

/// One configuration to measure: a scene (by name and how to make it), render settings.
struct Job {
    suite: Suite,
    /// Which scene: a paper scene's name, `base` (no lights or decals), or the sweep's count.
    scene_name: String,
    make_scene: SceneRecipe,
    config: RenderConfig,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Suite {
    Table,
    Dense,
    Sweep(SweepArg),
}

impl Suite {
    fn name(self) -> &'static str {
        match self {
            Suite::Table => "table",
            Suite::Dense => "dense",
            Suite::Sweep(SweepArg::Lights) => "sweep-lights",
            Suite::Sweep(_) => "sweep-decals",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum SceneRecipe {
    Base,
    Paper(PaperScene),
    SweepLights(u32),
    SweepDecals(u32),
    Dense(DenseArg),
}

impl SceneRecipe {
    /// What the recipe adds, whose overlap the report states.
    fn varies(self) -> Option<measure::Volumes> {
        match self {
            SceneRecipe::Base => None,
            SceneRecipe::Paper(paper) if paper.has_decals() => Some(measure::Volumes::Decals),
            SceneRecipe::Paper(_) | SceneRecipe::SweepLights(_) | SceneRecipe::Dense(_) => Some(measure::Volumes::Lights),
            SceneRecipe::SweepDecals(_) => Some(measure::Volumes::Decals),
        }
    }

    fn build(self, base: &Scene, seed: u64) -> manylights::Result<Scene> {
        let mut scene = base.clone();
        match self {
            SceneRecipe::Base => {}
            SceneRecipe::Paper(paper) => paper.add_to(&mut scene, seed)?,
            SceneRecipe::SweepLights(count) => {
                let params = ScatterLights { count: count as usize, seed, range: Some(SMALL_LIGHT_RANGE), ..Default::default() };
                generators::add_scattered_lights(&mut scene, &params)?;
            }
            SceneRecipe::Dense(dense) => {
                let range = match dense.target_overlap() {
                    None => SMALL_LIGHT_RANGE,
                    Some(target) => {
                        let range = dense_range(base, seed, target)?;
                        (range, range)
                    }
                };
                let params = ScatterLights { count: DENSE_LIGHTS, seed, range: Some(range), ..Default::default() };
                generators::add_scattered_lights(&mut scene, &params)?;
            }
            SceneRecipe::SweepDecals(count) => {
                let size = Some(scene.bounds().diagonal() * PAPER_DECAL_SIZE);
                generators::add_scattered_decals(&mut scene, &ScatterDecals { count: count as usize, seed, size })?;
            }
        }
        Ok(scene)
    }
}

/// The range at which [`DENSE_LIGHTS`] lights just above the surfaces of `base` reach `target` of them
/// a surface point, on average: the overlap grows about as the range squared (the disc a light
/// reaches of a surface), so a few corrections from a guess converge on it.
fn dense_range(base: &Scene, seed: u64, target: f64) -> manylights::Result<f32> {
    let mut range = base.bounds().diagonal() * 0.02;
    for _ in 0..4 {
        let mut scene = base.clone();
        generators::add_scattered_lights(
            &mut scene,
            &ScatterLights { count: DENSE_LIGHTS, seed, range: Some((range, range)), ..Default::default() },
        )?;
        let overlap = measure::mean_overlap(&scene, measure::Volumes::Lights, seed, 2000)?;
        range *= (target / overlap.max(1e-3)).sqrt().clamp(0.25, 4.0) as f32;
    }
    Ok(range)
}

/// Everything the report needs besides the measurements.
pub(crate) struct RunInfo {
    pub device: String,
    pub driver: String,
    pub backend: String,
    /// The ray back end of the configurations' `bvh` queries (`plan::RayTracer`).
    pub ray_tracer: &'static str,
    pub commit: &'static str,
    pub scene: String,
    pub camera: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub warmup: u32,
    pub time_cap_ms: f64,
    pub seed: u64,
    pub triangles: usize,
    pub quick: bool,
}

pub fn run(args: &BenchArgs) -> anyhow::Result<()> {
    let frames = args.frames.unwrap_or(if args.quick { 10 } else { 100 });
    let warmup = args.warmup.unwrap_or(if args.quick { 2 } else { 20 });
    if !(1..=crate::render::MAX_FRAMES).contains(&frames) || warmup > crate::render::MAX_FRAMES {
        bail!("--frames must be between 1 and {} and --warmup at most that (got {frames} and {warmup})", crate::render::MAX_FRAMES);
    }
    if args.scenes.len() > 1 && args.scenes.contains(&SceneChoice(None)) {
        bail!("--scenes: `none` runs no scene, so give it alone, not with others");
    }
    if args.dense.len() > 1 && args.dense.contains(&DenseArg::None) {
        bail!("--dense: `none` runs no dense scene, so give it alone, not with others");
    }
    if args.sweeps.len() > 1 && args.sweeps.contains(&SweepArg::None) {
        bail!("--sweeps: `none` runs no sweep, so give it alone, not with others");
    }
    if !(args.time_cap_ms.is_finite() && args.time_cap_ms > 0.0) {
        bail!("--time-cap-ms {}: the cap must be a positive number of milliseconds", args.time_cap_ms);
    }
    let sweep_max = args.sweep_max.unwrap_or(if args.quick { 16 * 1024 } else { 1 << 20 });
    if sweep_max < SWEEP_START || sweep_max as usize > generators::MAX_SCATTERED_LIGHTS {
        bail!(
            "--sweep-max {sweep_max}: the sweeps start at {SWEEP_START}; give a count from {SWEEP_START} to {}",
            generators::MAX_SCATTERED_LIGHTS
        );
    }
    let jobs = plan_jobs(args, sweep_max);
    if jobs.is_empty() {
        bail!("nothing to run: --scenes none with --dense none and --sweeps none, or no method applies to the scenes asked for");
    }

    // The folder and its files are checked before the run, which may take a long time.
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create the output folder {}", args.out.display()))?;
    let mut outputs = OutputPlan::new();
    for (name, format) in report::FILES {
        outputs.add("--out", &args.out.join(name), &[format])?;
    }
    let base = load_base_scene(args)?;
    outputs.check_inputs(&base.source_files)?;
    let camera = choose_camera(&base, args.camera)?;
    let ctx = GpuContext::new()?;
    // Settings every configuration shares (resolution, texture options) fail here, not once per configuration.
    for job in &jobs {
        job.config.validate(&ctx.device_limits())?;
    }
    if !ctx.has_timestamps() {
        bail!("the benchmark times passes with GPU timestamp queries, which this adapter lacks ({})", ctx.describe());
    }
    let info = RunInfo {
        device: ctx.info.name.clone(),
        driver: format!("{} {}", ctx.info.driver, ctx.info.driver_info).trim().to_owned(),
        backend: format!("{:?}", ctx.info.backend),
        ray_tracer: RayTracer::resolve(args.ray_backend, Capabilities::of(&ctx))?.name(),
        commit: env!("MANYLIGHTS_COMMIT"),
        scene: args.scene.clone(),
        camera: camera.name.clone(),
        width: args.width,
        height: args.height,
        frames,
        warmup,
        time_cap_ms: args.time_cap_ms,
        seed: args.seed,
        triangles: base.drawn_triangle_count(),
        quick: args.quick,
    };
    let plan = Plan { frames, warmup, time_cap_ms: args.time_cap_ms };
    let results = run_jobs(&ctx, &base, &camera, &jobs, &plan, args.seed);

    let written = report::write_all(&args.out, &info, &results)?;
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn load_base_scene(args: &BenchArgs) -> anyhow::Result<Scene> {
    let path = std::path::Path::new(&args.scene);
    let scene = if args.scene == "demo" {
        scene::demo::demo_scene()
    } else if !path.exists() {
        bail!(
            "base scene {} not found; pass --scene with a .gltf, .glb or .toml file, or `demo` (the default is Sponza from the shared assets, relative to the repository)",
            args.scene
        );
    } else {
        scene::load_path(path)?
    };
    if !scene.lights.is_empty() || !scene.decals.is_empty() {
        log::warn!(
            "the base scene has {} lights and {} decals of its own; every configuration includes them",
            scene.lights.len(),
            scene.decals.len()
        );
    }
    Ok(scene)
}

/// The configurations asked for, in the order they run: the table (baselines, then each paper scene
/// by pipeline and method), then the sweeps (by count, then method).
fn plan_jobs(args: &BenchArgs, sweep_max: u32) -> Vec<Job> {
    let pipelines: Vec<PipelineKind> = if args.pipelines.is_empty() { PipelineKind::ALL.to_vec() } else { dedup(&args.pipelines) };
    let methods = if args.methods.is_empty() { DecalMethod::ALL.to_vec() } else { dedup(&args.methods) };
    let scenes: Vec<PaperScene> =
        if args.scenes.is_empty() { PaperScene::ALL.to_vec() } else { dedup(&args.scenes).into_iter().filter_map(|s| s.0).collect() };
    let config = |pipeline, light_method, decal_method, bvh_build| RenderConfig {
        width: args.width,
        height: args.height,
        pipeline,
        light_method,
        light_bvh_build: bvh_build,
        decal_method,
        decal_bvh_build: bvh_build,
        max_texture_size: args.texture_size,
        anisotropy: args.anisotropy,
        // Timings compare methods: a fixed exposure keeps the meter's passes out of them.
        post: PostSettings { exposure: Exposure::Fixed(1.0), ..PostSettings::default() },
        rays: RaySettings { backend: args.ray_backend, ..RaySettings::default() },
        ..RenderConfig::default()
    };

    let mut jobs = Vec::new();
    if !scenes.is_empty() && methods.contains(&DecalMethod::Off) {
        for &pipeline in &pipelines {
            let config = config(pipeline, LightMethod::Off, DecalMethod::Off, BvhBuild::CpuOnce);
            jobs.push(Job { suite: Suite::Table, scene_name: "base".into(), make_scene: SceneRecipe::Base, config });
        }
    }
    for &paper in &scenes {
        for &pipeline in &pipelines {
            for &method in methods.iter().filter(|&&m| m != DecalMethod::Off) {
                let (light_method, decal_method) = match (paper.has_decals(), method) {
                    (true, m) => (LightMethod::Off, m),
                    (false, DecalMethod::DeferredDecals) => continue,
                    (false, m) => (light_method(m), DecalMethod::Off),
                };
                if !decal_method.works_in(pipeline) {
                    continue;
                }
                let config = config(pipeline, light_method, decal_method, BvhBuild::CpuOnce);
                jobs.push(Job { suite: Suite::Table, scene_name: paper.name().into(), make_scene: SceneRecipe::Paper(paper), config });
            }
        }
    }
    let dense = if args.dense.is_empty() {
        vec![DenseArg::SmallLights, DenseArg::Overlap10, DenseArg::Overlap50, DenseArg::Overlap100]
    } else {
        dedup(&args.dense)
    };
    for scene in dense.into_iter().filter(|&d| d != DenseArg::None) {
        for &pipeline in &pipelines {
            let runs = [
                (LightMethod::Bvh, BvhBuild::CpuOnce),
                (LightMethod::Bvh, BvhBuild::GpuEveryFrame),
                (LightMethod::Clustered, BvhBuild::CpuOnce),
                (LightMethod::Auto, BvhBuild::CpuOnce),
                (LightMethod::Auto, BvhBuild::GpuEveryFrame),
            ];
            for (light_method, build) in runs {
                let config = config(pipeline, light_method, DecalMethod::Off, build);
                jobs.push(Job { suite: Suite::Dense, scene_name: scene.name().into(), make_scene: SceneRecipe::Dense(scene), config });
            }
        }
    }
    let sweeps = if args.sweeps.is_empty() { vec![SweepArg::Lights, SweepArg::Decals] } else { dedup(&args.sweeps) };
    for sweep in sweeps.into_iter().filter(|&s| s != SweepArg::None) {
        let mut count = SWEEP_START;
        while count <= sweep_max {
            // By default the BVH is rebuilt on the GPU every frame, as clustered lists are: build
            // times compare.
            for method in [DecalMethod::Bvh, DecalMethod::Clustered, DecalMethod::Brute] {
                let build = args.sweep_build;
                let (config, make_scene) = match sweep {
                    SweepArg::Lights => {
                        (config(args.sweep_pipeline, light_method(method), DecalMethod::Off, build), SceneRecipe::SweepLights(count))
                    }
                    _ => (config(args.sweep_pipeline, LightMethod::Off, method, build), SceneRecipe::SweepDecals(count)),
                };
                jobs.push(Job { suite: Suite::Sweep(sweep), scene_name: count.to_string(), make_scene, config });
            }
            count = count.saturating_mul(4);
        }
    }
    jobs
}

fn dedup<T: PartialEq + Copy>(items: &[T]) -> Vec<T> {
    let mut out: Vec<T> = Vec::new();
    for &item in items {
        if !out.contains(&item) {
            out.push(item);
        }
    }
    out
}

/// The light method of a bench method's name (decal methods name the superset): off for those
/// only decals have.
fn light_method(method: DecalMethod) -> LightMethod {
    LightMethod::named(method.name()).unwrap_or(LightMethod::Off)
}

/// The paper's scenes, or `none`, for `--scenes`: spelled as `PaperScene` spells them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct SceneChoice(Option<PaperScene>);

impl ValueEnum for SceneChoice {
    fn value_variants<'a>() -> &'a [Self] {
        static CHOICES: std::sync::LazyLock<Vec<SceneChoice>> =
            std::sync::LazyLock::new(|| PaperScene::ALL.iter().map(|&s| SceneChoice(Some(s))).chain([SceneChoice(None)]).collect());
        &CHOICES
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(self.0.map_or("none", PaperScene::name)))
    }
}

/// Runs the jobs in order with a progress bar, generating each scene once. In a sweep, a method over
/// the cap (or failing) at one count is skipped at larger ones.
fn run_jobs(ctx: &GpuContext, base: &Scene, camera: &Camera, jobs: &[Job], plan: &Plan, seed: u64) -> Vec<Measurement> {
    let progress = ProgressBar::new(jobs.len() as u64);
    progress
        .set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} {elapsed_precise} {wide_msg}").expect("a valid progress template"));
    let mut results: Vec<Measurement> = Vec::with_capacity(jobs.len());
    // The scene of the jobs in hand, generated once for all of them, or why it could not be.
    let mut current: Option<SceneRecipe> = None;
    let mut generated: Result<(Scene, Option<f64>), String> = Err(String::new());
    for job in jobs {
        progress.set_message(format!("{} {} {}", job.suite.name(), job.scene_name, describe_config(&job.config)));
        if current != Some(job.make_scene) {
            generated = generate(job.make_scene, base, seed);
            current = Some(job.make_scene);
        }
        let (made, overlap) = match &generated {
            Ok((made, overlap)) => (made, overlap),
            Err(reason) => {
                let reason = format!("cannot generate the {} scene: {reason}", job.scene_name);
                progress.suspend(|| eprintln!("{} {}: {reason}", job.suite.name(), describe_config(&job.config)));
                results.push(Measurement {
                    suite: job.suite,
                    scene: job.scene_name.clone(),
                    lights: base.lights.len(),
                    decals: base.decals.len(),
                    overlap: None,
                    config: job.config.clone(),
                    outcome: measure::Outcome::Failed(reason),
                });
                progress.inc(1);
                continue;
            }
        };
        let gave_up_below = matches!(job.suite, Suite::Sweep(_))
            && results.iter().any(|r| r.suite == job.suite && r.same_method(&job.config) && !r.outcome.is_timed());
        let outcome = if gave_up_below {
            measure::Outcome::Skipped("over the time cap or failed at a smaller count".into())
        } else {
            measure::measure(ctx, made, camera, job.config.clone(), plan)
        };
        if let measure::Outcome::Failed(reason) = &outcome {
            // Not `progress.println`, which prints nothing when the bar is hidden (no terminal).
            progress.suspend(|| eprintln!("{} {} {}: {reason}", job.suite.name(), job.scene_name, describe_config(&job.config)));
        }
        results.push(Measurement {
            suite: job.suite,
            scene: job.scene_name.clone(),
            lights: made.lights.len(),
            decals: made.decals.len(),
            overlap: *overlap,
            config: job.config.clone(),
            outcome,
        });
        progress.inc(1);
    }
    progress.finish_and_clear();
    results
}

/// A job's scene and the mean overlap of what it varies, or why it cannot be made.
fn generate(recipe: SceneRecipe, base: &Scene, seed: u64) -> Result<(Scene, Option<f64>), String> {
    let made = recipe.build(base, seed).map_err(|e| e.to_string())?;
    let overlap = match recipe.varies() {
        Some(kind) => Some(measure::mean_overlap(&made, kind, seed, OVERLAP_POINTS).map_err(|e| e.to_string())?),
        None => None,
    };
    Ok((made, overlap))
}

fn describe_config(config: &RenderConfig) -> String {
    format!("{} lights {} decals {}", config.pipeline.name(), config.light_method.name(), config.decal_method.name())
}
