//! `manylights view`: a window showing the renderer's image beside an egui panel that switches
//! pipeline, methods, ray-traced effects and post effects live and shows per-pass GPU timings with a
//! rolling graph of the frame time. WASD (Q/E down/up, Shift faster) and the mouse with the right
//! button held fly the camera; the scene's cameras are a click away; F12 writes a screenshot; Esc
//! quits. `--frames N --screenshot FILE` (and `--set FRAME:KEY=VALUE` switches) script a run.
//!
//! The renderer draws into its own image at the size of the area beside the panel (it is rebuilt when
//! that size or a switch changes); egui shows that image as a texture and draws the panel over the
//! window's surface (egui-winit for input, egui-wgpu for drawing, both on the renderer's device).

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{bail, Context};
use clap::Args;
use glam::{Mat4, Vec3};
use manylights::{
    files::{self, OutputFormat, OutputPlan},
    gpu::{context::instance, GpuContext, PassTimings},
    image_io,
    plan::MethodChoice,
    renderer::Renderer,
    scene::{Camera, Projection, Scene},
    settings::{
        Bloom, DebugView, DecalMethod, Denoise, DepthOfField, DirectLighting, Exposure, LightMethod, MotionBlur, Named, ParticleMethod,
        ParticleOverlay, PipelineKind, RayBackend, RayOverlay, RenderConfig, RestirCandidates, SettingsOverlay, SunShadows,
    },
};
use winit::{
    application::ApplicationHandler,
    event::{DeviceEvent, ElementState, MouseButton, WindowEvent},
    event_loop::{ActiveEventLoop, EventLoop},
    keyboard::{KeyCode, PhysicalKey},
    window::{Window, WindowId},
};

use crate::scene_args::SceneArgs;

#[derive(Args)]
pub struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Window size in pixels (the panel takes part of it).
    #[arg(long, default_value_t = 1280)]
    width: u32,
    #[arg(long, default_value_t = 720)]
    height: u32,
    /// Camera index in the scene to start from (glTF cameras, or the scene file's first).
    #[arg(long)]
    camera: Option<usize>,
    /// Quit after this many frames (for scripted runs), writing --screenshot if given.
    #[arg(long)]
    frames: Option<u64>,
    /// With --frames: the last frame's image (without the panel), as .png, .jpg or .jpeg.
    #[arg(long, requires = "frames")]
    screenshot: Option<PathBuf>,
    /// A switch at a frame, as the panel would make it: FRAME:KEY=VALUE, KEY one of pipeline,
    /// light-method, decal-method, particle-method, ray-backend, shadows, direct-lighting, restir-candidates, denoise, reflections, bloom, depth-of-field,
    /// motion-blur, auto-exposure (on/off), vignette (0 to 1), debug-view (a --debug-view name), or
    /// the scattered lights, decals or particles (a count: the scene is generated again), or window
    /// (WIDTHxHEIGHT: the window is resized). Repeatable.
    #[arg(long = "set", value_name = "FRAME:KEY=VALUE")]
    sets: Vec<String>,
}

/// What the panel switches: everything that needs the renderer rebuilt.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Switches {
    pipeline: PipelineKind,
    light_method: LightMethod,
    decal_method: DecalMethod,
    particle_method: ParticleMethod,
    debug_view: DebugView,
    shadows: SunShadows,
    direct_lighting: DirectLighting,
    restir_candidates: RestirCandidates,
    denoise: Denoise,
    ray_backend: RayBackend,
    reflections: bool,
    bloom: bool,
    depth_of_field: bool,
    motion_blur: bool,
    auto_exposure: bool,
    /// The exposure with auto exposure off: the scene file's, or 1.
    fixed_exposure: f32,
    vignette: f32,
}

impl Default for Switches {
    fn default() -> Self {
        Self {
            pipeline: PipelineKind::Visbuffer,
            light_method: LightMethod::default(),
            decal_method: DecalMethod::default(),
            particle_method: ParticleMethod::Grid,
            debug_view: DebugView::Off,
            shadows: SunShadows::Off,
            direct_lighting: DirectLighting::Exact,
            restir_candidates: RestirCandidates::Auto,
            denoise: Denoise::Svgf,
            ray_backend: RayBackend::Auto,
            reflections: false,
            bloom: false,
            depth_of_field: false,
            motion_blur: false,
            auto_exposure: true,
            fixed_exposure: 1.0,
            vignette: 0.0,
        }
    }
}

impl Switches {
    /// The switches a scene file's methods, `[rays]`, `[particles]` and exposure start with.
    fn for_scene(overlay: &SettingsOverlay) -> Self {
        let defaults = Self::default();
        Self {
            light_method: overlay.methods.lights.unwrap_or(defaults.light_method),
            decal_method: overlay.methods.decals.unwrap_or(defaults.decal_method),
            particle_method: overlay.particles.method.unwrap_or(defaults.particle_method),
            shadows: overlay.rays.sun_shadows.unwrap_or(defaults.shadows),
            direct_lighting: overlay.rays.direct_lighting.unwrap_or(defaults.direct_lighting),
            restir_candidates: overlay.rays.restir_candidates.unwrap_or(defaults.restir_candidates),
            denoise: overlay.rays.denoise.unwrap_or(defaults.denoise),
            ray_backend: overlay.rays.backend.unwrap_or(defaults.ray_backend),
            reflections: overlay.rays.reflection_bounces.is_some_and(|bounces| bounces > 0),
            auto_exposure: overlay.exposure.is_none(),
            fixed_exposure: overlay.exposure.unwrap_or(defaults.fixed_exposure),
            ..defaults
        }
    }

    /// The settings of these switches, with the rest of the scene file's `[rays]` and `[particles]`
    /// (sun angle, ray budgets, the grid's voxels) under them.
    fn config(&self, (width, height): (u32, u32), overlay: &SettingsOverlay) -> RenderConfig {
        let bounces = overlay.rays.reflection_bounces.filter(|&bounces| bounces > 0).unwrap_or(1);
        let rays = RayOverlay {
            sun_shadows: Some(self.shadows),
            direct_lighting: Some(self.direct_lighting),
            restir_candidates: Some(self.restir_candidates),
            denoise: Some(self.denoise),
            backend: Some(self.ray_backend),
            reflection_bounces: Some(if self.reflections { bounces } else { 0 }),
            ..overlay.rays
        };
        let particles = ParticleOverlay { method: Some(self.particle_method), ..overlay.particles };
        let mut config = RenderConfig {
            width,
            height,
            pipeline: self.pipeline,
            light_method: self.light_method,
            decal_method: self.decal_method,
            debug_view: self.debug_view,
            rays: rays.settings(),
            ..RenderConfig::default()
        }
        .with_particles(particles);
        config.post.bloom = self.bloom.then(Bloom::default);
        config.post.depth_of_field = self.depth_of_field.then(DepthOfField::default);
        config.post.motion_blur = self.motion_blur.then(MotionBlur::default);
        config.post.exposure = if self.auto_exposure { Exposure::default() } else { Exposure::Fixed(self.fixed_exposure) };
        config.post.vignette = self.vignette;
        config
    }

    /// Applies `key=value` (a `--set`); the message names what is wrong.
    fn set(&mut self, key: &str, value: &str) -> anyhow::Result<()> {
        let on = || match value {
            "on" | "true" | "1" => Ok(true),
            "off" | "false" | "0" => Ok(false),
            _ => bail!("{key}={value}: give on or off"),
        };
        match key {
            "pipeline" => self.pipeline = choose(key, value)?,
            "light-method" => self.light_method = choose(key, value)?,
            "decal-method" => self.decal_method = choose(key, value)?,
            "particle-method" => self.particle_method = choose(key, value)?,
            "debug-view" => self.debug_view = choose(key, value)?,
            "shadows" => self.shadows = choose(key, value)?,
            "direct-lighting" => self.direct_lighting = choose(key, value)?,
            "restir-candidates" => self.restir_candidates = choose(key, value)?,
            "denoise" => self.denoise = choose(key, value)?,
            "ray-backend" => self.ray_backend = choose(key, value)?,
            "reflections" => self.reflections = on()?,
            "bloom" => self.bloom = on()?,
            "depth-of-field" => self.depth_of_field = on()?,
            "motion-blur" => self.motion_blur = on()?,
            "auto-exposure" => self.auto_exposure = on()?,
            // Its range is checked with the rest of the settings when the renderer is built.
            "vignette" => self.vignette = value.parse().with_context(|| format!("vignette={value}: give a number"))?,
            _ => bail!(
                "unknown switch {key}: give pipeline, light-method, decal-method, particle-method, debug-view, shadows, direct-lighting, restir-candidates, denoise, ray-backend, \
                 reflections, bloom, \
                 depth-of-field, motion-blur, auto-exposure, vignette, lights, decals or particles"
            ),
        }
        Ok(())
    }
}

/// The option `value` names, for the switch `key`; the message lists the names.
fn choose<T: Named>(key: &str, value: &str) -> anyhow::Result<T> {
    T::named(value).with_context(|| format!("{key}={value}: give {}", T::choices("")))
}

/// The scattered lights, decals and particles the scene is generated with (`SceneArgs`): changing
/// them generates the scene again.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Counts {
    lights: u32,
    decals: u32,
    particles: u32,
}

impl Counts {
    /// Applies `key=value` when it is a count; `Ok(false)` when the key is not one.
    fn set(&mut self, key: &str, value: &str) -> anyhow::Result<bool> {
        let count = || value.parse::<u32>().with_context(|| format!("{key}={value}: give a count"));
        match key {
            "lights" => self.lights = count()?,
            "decals" => self.decals = count()?,
            "particles" => self.particles = count()?,
            _ => return Ok(false),
        }
        Ok(true)
    }
}

/// Applies a `--set` or panel switch to whichever it belongs to.
fn apply(switches: &mut Switches, counts: &mut Counts, key: &str, value: &str) -> anyhow::Result<()> {
    if !counts.set(key, value)? {
        switches.set(key, value)?;
    }
    Ok(())
}

/// A `--set FRAME:KEY=VALUE`.
struct ScriptedSet {
    frame: u64,
    key: String,
    value: String,
}

/// The scripted switch that resizes the window rather than switching the renderer.
const WINDOW_KEY: &str = "window";

fn parse_set(text: &str) -> anyhow::Result<ScriptedSet> {
    let parsed = text.split_once(':').and_then(|(frame, rest)| Some((frame.parse().ok()?, rest.split_once('=')?)));
    let Some((frame, (key, value))) = parsed else { bail!("--set {text}: write FRAME:KEY=VALUE, e.g. 5:light-method=clustered") };
    // Checked now, so a bad switch fails before a window opens.
    if key == WINDOW_KEY {
        parse_window_size(value)?;
    } else {
        apply(&mut Switches::default(), &mut Counts { lights: 0, decals: 0, particles: 0 }, key, value)?;
    }
    Ok(ScriptedSet { frame, key: key.into(), value: value.into() })
}

/// A `window=WIDTHxHEIGHT` size, each side 1 to [`MAX_WINDOW_SIZE`].
fn parse_window_size(value: &str) -> anyhow::Result<(u32, u32)> {
    let size = value.split_once('x').and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)));
    size.filter(|&(w, h)| (1..=MAX_WINDOW_SIZE).contains(&w) && (1..=MAX_WINDOW_SIZE).contains(&h))
        .with_context(|| format!("{WINDOW_KEY}={value}: give WIDTHxHEIGHT, each 1 to {MAX_WINDOW_SIZE} pixels, e.g. 800x600"))
}

/// A free-flying camera: position, yaw about +Y and pitch, with the scene camera's lens.
struct FlyCamera {
    position: Vec3,
    yaw: f32,
    pitch: f32,
    projection: Projection,
}

impl FlyCamera {
    fn from_camera(camera: &Camera) -> Self {
        let forward = -camera.world_from_view.z_axis.truncate().normalize();
        Self {
            position: camera.position(),
            yaw: forward.x.atan2(-forward.z),
            pitch: forward.y.clamp(-1.0, 1.0).asin(),
            projection: camera.projection,
        }
    }

    fn camera(&self) -> Camera {
        let rotation = glam::Quat::from_rotation_y(-self.yaw) * glam::Quat::from_rotation_x(self.pitch);
        Camera {
            name: "fly".into(),
            world_from_view: Mat4::from_rotation_translation(rotation, self.position),
            projection: self.projection,
        }
    }
}

/// The first `manylights-screenshot-N.png` in `folder` after number `last` that does not exist yet
/// (`last` moves on to it): a screenshot never replaces a file, an earlier session's included.
fn free_screenshot_path(folder: &std::path::Path, last: &mut u32) -> PathBuf {
    loop {
        *last += 1;
        let path = folder.join(format!("manylights-screenshot-{last}.png"));
        if std::fs::symlink_metadata(&path).is_err() {
            return path.strip_prefix(".").map_or(path.clone(), std::path::Path::to_path_buf);
        }
    }
}

/// Points the panel is wide.
const PANEL_WIDTH: f32 = 270.0;
/// Largest window side asked for: X11 sizes are 16-bit; the GPU's own limit is checked once it is open.
const MAX_WINDOW_SIZE: u32 = 32_767;
/// Frames the rolling graph of frame times holds.
const GRAPH_FRAMES: usize = 240;

struct Gpu {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    surface_config: wgpu::SurfaceConfiguration,
    ctx: GpuContext,
    egui_state: egui_winit::State,
    egui_renderer: egui_wgpu::Renderer,
    renderer: Option<Renderer>,
    /// The switches the renderer was made with: others, from the panel or a script, rebuild it.
    built: Option<Switches>,
    /// The renderer's image as egui sees it, and the size it was made at.
    image: Option<(egui::TextureId, (u32, u32))>,
}

struct App {
    /// The scene file's rendering choices: the switches start from them, and the settings they do not
    /// switch come from them.
    overlay: SettingsOverlay,
    args: ViewArgs,
    scene: Scene,
    /// The counts the scene was generated with, those asked for, and those being edited in the panel.
    counts: Counts,
    wanted_counts: Counts,
    edited_counts: Counts,
    fly: FlyCamera,
    switches: Switches,
    scripted: Vec<ScriptedSet>,
    gpu: Option<Gpu>,
    /// Keys held down, and whether the right mouse button is.
    keys: std::collections::HashSet<KeyCode>,
    looking: bool,
    frame: u64,
    last_frame: std::time::Instant,
    timings: PassTimings,
    history: VecDeque<f64>,
    /// A switch the renderer refused (shown in the panel), and the number of the last screenshot
    /// name tried.
    message: Option<String>,
    screenshots: u32,
    /// Set when the viewer must stop: `Err` ends the program with that error.
    result: Option<anyhow::Result<()>>,
}

pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    let scripted = args.sets.iter().map(|s| parse_set(s)).collect::<anyhow::Result<Vec<_>>>()?;
    if args.width == 0 || args.height == 0 || args.width > MAX_WINDOW_SIZE || args.height > MAX_WINDOW_SIZE {
        bail!("window {}×{}: give --width and --height from 1 to {MAX_WINDOW_SIZE} pixels", args.width, args.height);
    }
    if args.frames == Some(0) {
        bail!("--frames 0 would stop before the first frame; give at least 1");
    }
    if let (Some(frames), Some(late)) = (args.frames, scripted.iter().find(|s| Some(s.frame) >= args.frames)) {
        bail!(
            "--set {}:{}={}: the run stops after {frames} frames (0 to {}); give an earlier frame",
            late.frame,
            late.key,
            late.value,
            frames - 1
        );
    }
    if cfg!(target_os = "linux") && std::env::var_os("DISPLAY").is_none() && std::env::var_os("WAYLAND_DISPLAY").is_none() {
        bail!(
            "the viewer needs a display, and neither DISPLAY nor WAYLAND_DISPLAY is set; run it in a desktop session, \
             or headless under Xvfb (xvfb-run -a manylights view …), or use `manylights render` for images without a window"
        );
    }
    let mut outputs = OutputPlan::new();
    if let Some(path) = &args.screenshot {
        outputs.add("--screenshot", path, &OutputFormat::IMAGES)?;
    }
    let (scene, overlay) = args.scene.load(None)?;
    outputs.check_inputs(&scene.source_files)?;
    let camera = crate::render::choose_camera(&scene, args.camera)?;
    let counts = Counts { lights: args.scene.lights, decals: args.scene.decals, particles: args.scene.particles };
    let event_loop =
        EventLoop::new().context("cannot open a window: the display refused the connection (check DISPLAY or WAYLAND_DISPLAY)")?;
    let mut app = App {
        fly: FlyCamera::from_camera(&camera),
        args,
        scene,
        counts,
        wanted_counts: counts,
        edited_counts: counts,
        switches: Switches::for_scene(&overlay),
        overlay,
        scripted,
        gpu: None,
        keys: Default::default(),
        looking: false,
        frame: 0,
        last_frame: std::time::Instant::now(),
        timings: Vec::new(),
        history: VecDeque::new(),
        message: None,
        screenshots: 0,
        result: None,
    };
    event_loop.run_app(&mut app).context("the window's event loop failed")?;
    app.result.unwrap_or(Ok(()))
}

impl App {
    fn stop(&mut self, event_loop: &ActiveEventLoop, result: anyhow::Result<()>) {
        self.result.get_or_insert(result);
        event_loop.exit();
    }

    fn open(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<Gpu> {
        let attributes = Window::default_attributes()
            .with_title("manylights")
            .with_inner_size(winit::dpi::PhysicalSize::new(self.args.width.max(320), self.args.height.max(200)));
        let window = Arc::new(event_loop.create_window(attributes).context("cannot create the window")?);
        let instance = instance();
        let surface = instance.create_surface(window.clone()).context("cannot draw into the window (no Vulkan, Metal or DX12 surface)")?;
        let ctx = GpuContext::for_surface(&instance, &surface)?;
        let size = window.inner_size();
        let most = ctx.limits.max_texture_dimension_2d;
        if size.width > most || size.height > most {
            bail!(
                "a window of {}×{} pixels is over this GPU's surface limit of {most} per side; give a smaller --width or --height",
                size.width,
                size.height
            );
        }
        let caps = surface.get_capabilities(&ctx.adapter);
        // egui draws in gamma space into a plain (non-sRGB) format, and the renderer's image holds
        // sRGB-encoded values already.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or(caps.formats.first().copied())
            .context("the window's surface offers no format")?;
        let surface_config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&ctx.device, &surface_config);
        let egui_ctx = egui::Context::default();
        let egui_state = egui_winit::State::new(egui_ctx, egui::ViewportId::ROOT, &window, Some(window.scale_factor() as f32), None, None);
        let egui_renderer = egui_wgpu::Renderer::new(&ctx.device, format, egui_wgpu::RendererOptions::default());
        Ok(Gpu { window, surface, surface_config, ctx, egui_state, egui_renderer, renderer: None, built: None, image: None })
    }

    /// The renderer's image size: the window beside the panel, in pixels.
    fn image_size(gpu: &Gpu) -> (u32, u32) {
        let scale = gpu.window.scale_factor() as f32;
        let panel = (PANEL_WIDTH * scale).ceil() as u32;
        (gpu.surface_config.width.saturating_sub(panel).max(16), gpu.surface_config.height.max(16))
    }

    /// Rebuilds the renderer for the current switches and image size; a refused combination keeps the
    /// previous renderer, and its error is the caller's to show or to end a scripted run with.
    fn rebuild(&mut self) -> anyhow::Result<()> {
        let Some(gpu) = &mut self.gpu else { return Ok(()) };
        let size = Self::image_size(gpu);
        match Renderer::new(gpu.ctx.clone(), &self.scene, self.switches.config(size, &self.overlay)) {
            Ok(mut renderer) => {
                renderer.time = gpu.renderer.as_ref().map_or(0.0, |r| r.time);
                let view = renderer.output().create_view(&Default::default());
                let id = match gpu.image {
                    Some((id, _)) => {
                        gpu.egui_renderer.update_egui_texture_from_wgpu_texture(&gpu.ctx.device, &view, wgpu::FilterMode::Linear, id);
                        id
                    }
                    None => gpu.egui_renderer.register_native_texture(&gpu.ctx.device, &view, wgpu::FilterMode::Linear),
                };
                gpu.image = Some((id, size));
                gpu.renderer = Some(renderer);
                gpu.built = Some(self.switches);
                self.message = None;
                Ok(())
            }
            Err(e) => Err(anyhow::anyhow!("not switched: {e}")),
        }
    }

    /// Generates the scene again with the counts the panel asks for; a refused count keeps the scene,
    /// and its error is the caller's to show or to end a scripted run with.
    fn regenerate_scene(&mut self) -> anyhow::Result<()> {
        let Counts { lights, decals, particles } = self.wanted_counts;
        let args = SceneArgs { lights, decals, particles, ..self.args.scene.clone() };
        match args.load(self.gpu.as_ref().map(|g| &g.ctx)) {
            Ok((scene, _)) => {
                self.scene = scene;
                self.message = None;
                self.counts = self.wanted_counts;
                Ok(())
            }
            Err(e) => {
                self.wanted_counts = self.counts;
                Err(anyhow::anyhow!("not generated: {e:#}"))
            }
        }
    }

    fn move_camera(&mut self, dt: f32) {
        let speed = if self.keys.contains(&KeyCode::ShiftLeft) { 12.0 } else { 3.0 } * dt;
        let camera = self.fly.camera();
        let forward = -camera.world_from_view.z_axis.truncate();
        let right = camera.world_from_view.x_axis.truncate();
        let mut step = Vec3::ZERO;
        for (key, direction) in [
            (KeyCode::KeyW, forward),
            (KeyCode::KeyS, -forward),
            (KeyCode::KeyD, right),
            (KeyCode::KeyA, -right),
            (KeyCode::KeyE, Vec3::Y),
            (KeyCode::KeyQ, -Vec3::Y),
        ] {
            if self.keys.contains(&key) {
                step += direction;
            }
        }
        self.fly.position += step.normalize_or_zero() * speed;
    }

    fn next_screenshot_path(&mut self) -> PathBuf {
        free_screenshot_path(std::path::Path::new("."), &mut self.screenshots)
    }

    /// Writes the frame to `path`: a new file for F12 and the panel's button (a name found free), the
    /// file `--screenshot` named (checked before the window opened) otherwise.
    fn screenshot(&mut self, path: &std::path::Path, new: bool) -> anyhow::Result<()> {
        let renderer = self.gpu.as_ref().and_then(|g| g.renderer.as_ref()).context("no frame has been rendered yet")?;
        let format = OutputFormat::from_path(path).unwrap_or(OutputFormat::Png);
        let bytes = image_io::encode_ldr(&renderer.read_ldr()?, format).with_context(|| format!("cannot encode {}", path.display()))?;
        if new {
            files::write::write_new(path, &bytes)?;
        } else {
            files::write_atomic(path, &bytes)?;
        }
        self.message = Some(format!("wrote {}", path.display()));
        println!("wrote {}", path.display());
        Ok(())
    }

    /// One frame: scripted switches, the camera, the scene's frame, the panel, presenting.
    /// One frame: the switches due now, a new scene or renderer where they ask for one, the scene's
    /// image, the window with its panel, and what the panel asked for.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let scripted = self.apply_scripted_switches()?;
        let regenerated = self.regenerate_if_asked(scripted)?;
        if self.gpu.is_none() {
            return Ok(());
        }
        self.rebuild_if_stale(regenerated, scripted)?;
        self.render_scene()?;
        let Some(asked) = self.draw_window()? else { return Ok(()) };
        self.switches = asked.switches;
        self.wanted_counts = asked.counts;
        if let Some(camera) = asked.jump.and_then(|i| self.scene.cameras.get(i)) {
            self.fly = FlyCamera::from_camera(camera);
        }
        if asked.screenshot {
            let path = self.next_screenshot_path();
            self.screenshot(&path, true)?;
        }
        self.frame += 1;
        if self.args.frames.is_some_and(|n| self.frame >= n) {
            if let Some(path) = self.args.screenshot.clone() {
                self.screenshot(&path, false)?;
            }
            self.stop(event_loop, Ok(()));
        }
        Ok(())
    }

    /// Applies the `--set` switches due this frame; whether there were any.
    fn apply_scripted_switches(&mut self) -> anyhow::Result<bool> {
        let due: Vec<(String, String)> =
            self.scripted.iter().filter(|s| s.frame == self.frame).map(|s| (s.key.clone(), s.value.clone())).collect();
        let scripted = !due.is_empty();
        for (key, value) in due {
            if key == WINDOW_KEY {
                let (width, height) = parse_window_size(&value)?;
                if let Some(gpu) = &self.gpu {
                    // The window system answers with a Resized event, as for a user's drag.
                    let _ = gpu.window.request_inner_size(winit::dpi::PhysicalSize::new(width, height));
                }
                continue;
            }
            apply(&mut self.switches, &mut self.wanted_counts, &key, &value)?;
        }
        Ok(scripted)
    }

    /// A refused switch: the run's error when a script asked for it (it must take), otherwise shown
    /// in the panel.
    fn refused(&mut self, scripted: bool, result: anyhow::Result<()>) -> anyhow::Result<()> {
        match result {
            Err(e) if scripted => Err(e.context(format!("frame {}: a --set switch was refused", self.frame))),
            Err(e) => {
                self.message = Some(format!("{e:#}"));
                Ok(())
            }
            Ok(()) => Ok(()),
        }
    }

    /// Generates the scene again where the counts asked for changed; whether it was.
    fn regenerate_if_asked(&mut self, scripted: bool) -> anyhow::Result<bool> {
        if self.wanted_counts == self.counts {
            return Ok(false);
        }
        let result = self.regenerate_scene();
        let regenerated = result.is_ok();
        self.refused(scripted, result)?;
        self.edited_counts = self.counts;
        Ok(regenerated)
    }

    /// Builds the renderer again where the scene, the image size or the switches changed.
    fn rebuild_if_stale(&mut self, regenerated: bool, scripted: bool) -> anyhow::Result<()> {
        let Some(gpu) = &self.gpu else { return Ok(()) };
        let stale = gpu.renderer.is_none()
            || gpu.image.is_some_and(|(_, size)| size != Self::image_size(gpu))
            || gpu.built != Some(self.switches)
            || regenerated;
        if !stale {
            return Ok(());
        }
        let result = self.rebuild();
        if result.is_err() {
            // Back to what the renderer was made with, so a refused panel switch is not retried
            // every frame.
            if let Some(built) = self.gpu.as_ref().and_then(|g| g.built) {
                self.switches = built;
            }
        }
        self.refused(scripted, result)
    }

    /// Moves the camera by the time since the last frame and renders the scene's image.
    fn render_scene(&mut self) -> anyhow::Result<()> {
        let now = std::time::Instant::now();
        let dt = (now - self.last_frame).as_secs_f32().min(0.1);
        self.last_frame = now;
        self.move_camera(dt);
        let camera = self.fly.camera();
        let gpu = self.gpu.as_mut().context("the window is gone")?;
        if let Some(renderer) = &mut gpu.renderer {
            self.timings = renderer.render(&camera)?;
            let total: f64 = self.timings.iter().map(|(_, ms)| ms).sum();
            self.history.push_back(total);
            if self.history.len() > GRAPH_FRAMES {
                self.history.pop_front();
            }
        }
        Ok(())
    }

    /// Draws the panel and the image into the window; what the panel asked for, or `None` when the
    /// window could not be drawn this frame.
    fn draw_window(&mut self) -> anyhow::Result<Option<PanelAsks>> {
        let gpu = self.gpu.as_mut().context("the window is gone")?;
        let raw_input = gpu.egui_state.take_egui_input(&gpu.window);
        let egui_ctx = gpu.egui_state.egui_ctx().clone();
        let mut asks = PanelAsks { switches: self.switches, counts: self.wanted_counts, jump: None, screenshot: false };
        let image = gpu.image;
        let chosen = gpu.renderer.as_ref().map(Renderer::methods_chosen);
        let mut output = egui_ctx.run_ui(raw_input, |ui| {
            egui::Panel::left("controls").exact_size(PANEL_WIDTH).show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| {
                    let shown = PanelShows {
                        scene: &self.scene,
                        chosen,
                        timings: &self.timings,
                        history: &self.history,
                        message: self.message.as_deref(),
                    };
                    panel(ui, &mut asks, &mut self.edited_counts, &shown);
                });
            });
            egui::CentralPanel::no_frame().show(ui, |ui| {
                if let Some((id, (w, h))) = image {
                    let scale = ui.ctx().pixels_per_point();
                    ui.image(egui::load::SizedTexture::new(id, egui::vec2(w as f32 / scale, h as f32 / scale)));
                }
            });
        });
        gpu.egui_state.handle_platform_output(&gpu.window, output.platform_output);
        let paint_jobs = egui_ctx.tessellate(output.shapes, output.pixels_per_point);
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [gpu.surface_config.width, gpu.surface_config.height],
            pixels_per_point: output.pixels_per_point,
        };
        // Font atlas and other egui textures: uploaded before painting, freed after.
        let mut textures = std::mem::take(&mut output.textures_delta);
        for (id, deltas) in &textures.set {
            for delta in deltas {
                gpu.egui_renderer.update_texture(&gpu.ctx.device, &gpu.ctx.queue, *id, delta);
            }
        }
        let frame = match gpu.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(frame) => frame,
            wgpu::CurrentSurfaceTexture::Suboptimal(frame) => {
                gpu.surface.configure(&gpu.ctx.device, &gpu.surface_config);
                frame
            }
            // Resized: reconfigure and draw the next frame.
            wgpu::CurrentSurfaceTexture::Outdated => {
                gpu.surface.configure(&gpu.ctx.device, &gpu.surface_config);
                return Ok(None);
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => return Ok(None),
            other => bail!("cannot draw into the window: its surface is {other:?}"),
        };
        let target = frame.texture.create_view(&Default::default());
        let mut encoder = gpu.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("viewer") });
        let mut commands = gpu.egui_renderer.update_buffers(&gpu.ctx.device, &gpu.ctx.queue, &mut encoder, &paint_jobs, &screen);
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("viewer egui"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            gpu.egui_renderer.render(&mut pass.forget_lifetime(), &paint_jobs, &screen);
        }
        commands.push(encoder.finish());
        gpu.ctx.queue.submit(commands);
        gpu.ctx.queue.present(frame);
        for id in &textures.free {
            gpu.egui_renderer.free_texture(id);
        }
        textures.clear();
        gpu.ctx.check_errors()?;
        Ok(Some(asks))
    }
}

/// What the panel asks for: switches, the counts to generate the scene with, a camera to jump to,
/// a screenshot.
struct PanelAsks {
    switches: Switches,
    counts: Counts,
    jump: Option<usize>,
    screenshot: bool,
}

/// What the panel shows besides its switches.
struct PanelShows<'a> {
    scene: &'a Scene,
    /// What `auto` chose, once a renderer is built.
    chosen: Option<MethodChoice>,
    timings: &'a PassTimings,
    history: &'a VecDeque<f64>,
    message: Option<&'a str>,
}

/// A combo box choosing one of an option enum's values.
fn choice<T: Named + PartialEq>(ui: &mut egui::Ui, label: &str, value: &mut T) {
    egui::ComboBox::from_label(label).selected_text(value.name()).show_ui(ui, |ui| {
        for &v in T::all() {
            ui.selectable_value(value, v, v.name());
        }
    });
}

/// The panel: switches, counts (`edited` while they are dragged), cameras, timings and the
/// frame-time graph.
fn panel(ui: &mut egui::Ui, asks: &mut PanelAsks, edited: &mut Counts, shown: &PanelShows) {
    let switches = &mut asks.switches;
    ui.heading("manylights");
    choice(ui, "pipeline", &mut switches.pipeline);
    choice(ui, "lights", &mut switches.light_method);
    choice(ui, "decals", &mut switches.decal_method);
    if let Some(chosen) = shown.chosen {
        ui.label(format!("lights: {}", chosen.lights)).on_hover_text("the light method that runs, and why");
        ui.label(format!("decals: {}", chosen.decals)).on_hover_text("the decal method that runs, and why");
    }
    choice(ui, "particles", &mut switches.particle_method);
    choice(ui, "debug view", &mut switches.debug_view);
    choice(ui, "sun shadows", &mut switches.shadows);
    choice(ui, "direct lighting", &mut switches.direct_lighting);
    choice(ui, "restir candidates", &mut switches.restir_candidates);
    choice(ui, "ray backend", &mut switches.ray_backend);
    choice(ui, "denoise", &mut switches.denoise);
    ui.checkbox(&mut switches.reflections, "reflections");
    ui.separator();
    ui.checkbox(&mut switches.auto_exposure, "auto exposure");
    ui.checkbox(&mut switches.bloom, "bloom");
    ui.checkbox(&mut switches.depth_of_field, "depth of field");
    ui.checkbox(&mut switches.motion_blur, "motion blur");
    ui.add(egui::Slider::new(&mut switches.vignette, 0.0..=1.0).text("vignette"));
    ui.separator();
    // Counts take effect when the drag ends: every change generates the scene again.
    let mut released = false;
    for (label, value) in [("scattered lights", &mut edited.lights), ("decals", &mut edited.decals), ("particles", &mut edited.particles)] {
        let response = ui.add(egui::DragValue::new(value).range(0..=1 << 20).speed(64.0).prefix(format!("{label}: ")));
        released |= response.drag_stopped() || response.lost_focus();
    }
    if released {
        asks.counts = *edited;
    }
    if !shown.scene.cameras.is_empty() {
        ui.separator();
        ui.label("cameras");
        for (i, camera) in shown.scene.cameras.iter().enumerate() {
            if ui.button(format!("{i}: {}", camera.name)).clicked() {
                asks.jump = Some(i);
            }
        }
    }
    ui.separator();
    if ui.button("screenshot (F12)").clicked() {
        asks.screenshot = true;
    }
    if let Some(message) = shown.message {
        ui.label(message);
    }
    ui.separator();
    let total: f64 = shown.timings.iter().map(|(_, ms)| ms).sum();
    ui.label(format!("GPU frame {total:.3} ms"));
    egui::Grid::new("timings").striped(true).show(ui, |ui| {
        for (pass, ms) in shown.timings {
            ui.label(*pass);
            ui.label(format!("{ms:.3}"));
            ui.end_row();
        }
    });
    frame_graph(ui, shown.history);
}

/// The last frames' GPU times as a line, scaled to the largest.
fn frame_graph(ui: &mut egui::Ui, history: &VecDeque<f64>) {
    let (response, painter) = ui.allocate_painter(egui::vec2(ui.available_width(), 60.0), egui::Sense::hover());
    let rect = response.rect;
    painter.rect_stroke(rect, 0.0, egui::Stroke::new(1.0, egui::Color32::DARK_GRAY), egui::StrokeKind::Inside);
    let largest = history.iter().copied().fold(1e-6, f64::max);
    let points: Vec<egui::Pos2> = history
        .iter()
        .enumerate()
        .map(|(i, ms)| {
            let x = rect.left() + rect.width() * i as f32 / (GRAPH_FRAMES - 1) as f32;
            egui::pos2(x, rect.bottom() - rect.height() * (*ms / largest) as f32)
        })
        .collect();
    painter.add(egui::Shape::line(points, egui::Stroke::new(1.5, egui::Color32::LIGHT_GREEN)));
    painter.text(rect.left_top(), egui::Align2::LEFT_TOP, format!("{largest:.2} ms"), egui::FontId::monospace(10.0), egui::Color32::GRAY);
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(gpu) => {
                self.gpu = Some(gpu);
                // The first renderer must exist: its error is the program's.
                if let Err(e) = self.rebuild() {
                    self.stop(event_loop, Err(e));
                }
            }
            Err(e) => self.stop(event_loop, Err(e)),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(gpu) = &mut self.gpu else { return };
        let consumed = gpu.egui_state.on_window_event(&gpu.window, &event).consumed;
        match event {
            WindowEvent::CloseRequested => self.stop(event_loop, Ok(())),
            WindowEvent::Resized(size) => {
                gpu.surface_config.width = size.width.max(1);
                gpu.surface_config.height = size.height.max(1);
                gpu.surface.configure(&gpu.ctx.device, &gpu.surface_config);
            }
            WindowEvent::KeyboardInput { event, .. } if !consumed => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    match event.state {
                        ElementState::Pressed => {
                            self.keys.insert(code);
                            match code {
                                KeyCode::Escape => self.stop(event_loop, Ok(())),
                                KeyCode::F12 => {
                                    let path = self.next_screenshot_path();
                                    if let Err(e) = self.screenshot(&path, true) {
                                        self.message = Some(format!("screenshot failed: {e:#}"));
                                    }
                                }
                                _ => {}
                            }
                        }
                        ElementState::Released => {
                            self.keys.remove(&code);
                        }
                    }
                }
            }
            WindowEvent::MouseInput { button: MouseButton::Right, state, .. } => self.looking = state == ElementState::Pressed,
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.stop(event_loop, Err(e));
                }
            }
            _ => {}
        }
    }

    fn device_event(&mut self, _event_loop: &ActiveEventLoop, _id: winit::event::DeviceId, event: DeviceEvent) {
        if let DeviceEvent::MouseMotion { delta } = event {
            if self.looking {
                self.fly.yaw += delta.0 as f32 * 0.003;
                self.fly.pitch = (self.fly.pitch - delta.1 as f32 * 0.003).clamp(-1.5, 1.5);
            }
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(gpu) = &self.gpu {
            gpu.window.request_redraw();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn screenshots_skip_names_already_taken() {
        let dir = std::env::temp_dir().join(format!("manylights-screenshots-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for taken in [1, 2, 4] {
            std::fs::write(dir.join(format!("manylights-screenshot-{taken}.png")), "an earlier session's").unwrap();
        }
        let mut last = 0;
        let names: Vec<PathBuf> = (0..3).map(|_| free_screenshot_path(&dir, &mut last)).collect();
        assert_eq!(names, [3, 5, 6].map(|n| dir.join(format!("manylights-screenshot-{n}.png"))));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_direct_lighting_switch_starts_from_the_scene_file_and_reaches_the_settings() {
        let mut overlay = SettingsOverlay::default();
        overlay.rays.direct_lighting = Some(DirectLighting::Reference);
        overlay.rays.restir_shadow_rays = Some(3);
        overlay.rays.denoise = Some(Denoise::Off);
        let mut switches = Switches::for_scene(&overlay);
        assert_eq!((switches.direct_lighting, switches.denoise), (DirectLighting::Reference, Denoise::Off));
        switches.set("direct-lighting", "restir").unwrap();
        switches.set("denoise", "svgf").unwrap();
        let rays = switches.config((64, 36), &overlay).rays;
        assert_eq!(rays.denoise, Denoise::Svgf);
        // The switch, with the scene file's budget under it.
        assert_eq!((rays.direct_lighting, rays.restir_shadow_rays), (DirectLighting::Restir, 3));
        assert!(switches.set("direct-lighting", "sampled").unwrap_err().to_string().contains("restir"));
    }

    #[test]
    fn the_ray_backend_switch_starts_from_the_scene_file_and_reaches_the_settings() {
        let mut overlay = SettingsOverlay::default();
        overlay.rays.backend = Some(RayBackend::Software);
        let mut switches = Switches::for_scene(&overlay);
        assert_eq!(switches.config((64, 36), &overlay).rays.backend, RayBackend::Software);
        switches.set("ray-backend", "hardware").unwrap();
        assert_eq!(switches.config((64, 36), &overlay).rays.backend, RayBackend::Hardware);
        assert!(switches.set("ray-backend", "rtx").unwrap_err().to_string().contains("software"));
    }

    #[test]
    fn window_sizes_are_checked_when_the_script_is_read() {
        assert_eq!(parse_window_size("800x600").unwrap(), (800, 600));
        for bad in ["800", "0x600", "800x", "99999x10", "axb"] {
            assert!(parse_window_size(bad).unwrap_err().to_string().contains("give WIDTHxHEIGHT"), "{bad}");
        }
        assert!(parse_set("3:window=640x360").is_ok());
        assert!(parse_set("3:window=big").is_err());
    }
}
