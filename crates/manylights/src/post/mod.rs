//! The post chain (PowerVR's last hybrid step: "the usual host of screen-space effects"), run by every
//! pipeline after the HDR image is shaded, each effect switchable:
//!
//! ```text
//! hdr ─▶ depth_of_field ─▶ motion_blur ─▶ exposure_histogram, exposure_average ─▶ bloom ─▶ tonemap ─▶ ldr
//!  (depth)  (tiles, gather)  (velocity, tiles, gather)  (auto exposure)         (down, up)  (exposure,
//!                                                                                            bloom blend,
//!                                                                                            vignette)
//! ```
//!
//! Effects that are off cost nothing: their passes are not built and the next reads what the last
//! one wrote. Each pass is a file here beside its WGSL; they bind the scene as group 0 (frame uniforms,
//! camera rays) and the chain's [`PostUniforms`] as group 1's first binding. `Renderer::read_hdr`
//! still returns the shaded image before the chain.

pub mod bloom;
pub mod depth_of_field;
pub mod exposure;
pub mod motion_blur;
pub mod tonemap;
pub mod velocity;

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::scene::{Camera, Projection};
use crate::{Error, Result};

/// The images between post passes: 32-bit float like the HDR image, so a pixel an effect leaves
/// alone passes through exactly.
pub const POST_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Edge of the tiles depth of field and motion blur find their reach over (`POST_TILE` in WGSL).
const TILE: u32 = 16;

/// Most samples per pixel of motion blur; the largest circle of confusion's radius and the longest
/// motion blur, in pixels: the gathers search the 3×3 tiles around a pixel, so nothing beyond a tile
/// (depth of field's radius) or two (motion blur's ±½ length) could reach it.
pub const MAX_MOTION_BLUR_SAMPLES: u32 = 64;
pub const MAX_COC_RADIUS: f32 = TILE as f32;
pub const MAX_MOTION_BLUR_LENGTH: f32 = 2.0 * TILE as f32;
/// Sensor height of the thin lens depth of field models: 35 mm film's 24 mm, so f-numbers and focus
/// behave as on a full-frame camera with the view's field of view.
pub const SENSOR_HEIGHT: f32 = 0.024;

/// Exposure measured from the image every frame (`exposure.wgsl`), instead of the scene's fixed one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutoExposure {
    /// Stops above (+) or below (−) mapping the image's mean luminance to middle grey.
    pub compensation_ev: f32,
    /// How fast the exposure follows the measurement, per second (the first frame takes it at once):
    /// after 1 / speed seconds it has moved 63 % of the way.
    pub adaptation_speed: f32,
}

impl Default for AutoExposure {
    fn default() -> Self {
        Self { compensation_ev: 0.0, adaptation_speed: 3.0 }
    }
}

/// Bloom (`bloom.wgsl`): the blurred image's share of the result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bloom {
    pub intensity: f32,
}

impl Default for Bloom {
    fn default() -> Self {
        Self { intensity: 0.05 }
    }
}

/// Depth of field of a thin lens (`depth_of_field.wgsl`) with the view's field of view on a
/// 24 mm-high sensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthOfField {
    /// Distance in focus, in metres; `None` focuses on what the image's centre shows.
    pub focus_distance: Option<f32>,
    /// Focal length over aperture diameter: lower is shallower.
    pub f_number: f32,
    /// Largest circle of confusion's radius, in pixels.
    pub max_radius: f32,
}

impl Default for DepthOfField {
    fn default() -> Self {
        Self { focus_distance: None, f_number: 2.8, max_radius: 16.0 }
    }
}

/// Motion blur (`motion_blur.wgsl`) from per-pixel velocities (`velocity.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionBlur {
    /// Shutter time as a fraction of the frame interval (0.5: a 180° shutter).
    pub shutter: f32,
    /// Samples per pixel along the blur.
    pub samples: u32,
    /// Longest blur, in pixels.
    pub max_length: f32,
}

impl Default for MotionBlur {
    fn default() -> Self {
        Self { shutter: 0.5, samples: 16, max_length: 32.0 }
    }
}

/// Which post effects a frame runs, and how. Tonemapping is always on (`RenderConfig::tonemapper`
/// picks its curve, `None` clamps).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PostSettings {
    pub auto_exposure: Option<AutoExposure>,
    pub bloom: Option<Bloom>,
    pub depth_of_field: Option<DepthOfField>,
    pub motion_blur: Option<MotionBlur>,
    /// Natural vignetting's strength: 0 none, 1 the cos⁴ law of a real lens.
    pub vignette: f32,
}

impl PostSettings {
    /// Checks every setting; messages name the command-line flag.
    pub fn validate(&self) -> Result<()> {
        let invalid = |m: String| Err(Error::InvalidConfig(m));
        let in_range = |v: f32, low: f32, high: f32| v.is_finite() && v >= low && v <= high;
        if !in_range(self.vignette, 0.0, 1.0) {
            return invalid(format!("vignette strength {} must be between 0 (none) and 1 (the cos⁴ law) (--vignette)", self.vignette));
        }
        if let Some(auto) = self.auto_exposure {
            if !in_range(auto.compensation_ev, -16.0, 16.0) {
                return invalid(format!(
                    "exposure compensation {} EV must be between -16 and 16 (--exposure-compensation)",
                    auto.compensation_ev
                ));
            }
            if !in_range(auto.adaptation_speed, 0.0, 1000.0) || auto.adaptation_speed == 0.0 {
                return invalid(format!(
                    "exposure adaptation speed {} per second must be above 0 and at most 1000 (--exposure-adaptation)",
                    auto.adaptation_speed
                ));
            }
        }
        if let Some(bloom) = self.bloom {
            if !in_range(bloom.intensity, 0.0, 1.0) || bloom.intensity == 0.0 {
                return invalid(format!("bloom intensity {} must be above 0 and at most 1 (--bloom-intensity)", bloom.intensity));
            }
        }
        if let Some(dof) = self.depth_of_field {
            if let Some(focus) = dof.focus_distance {
                if !(focus.is_finite() && focus > 0.0) {
                    return invalid(format!("focus distance {focus} m must be a finite distance above 0 (--focus-distance)"));
                }
            }
            if !in_range(dof.f_number, 0.1, 1000.0) {
                return invalid(format!("f-number {} must be between 0.1 and 1000 (--f-number)", dof.f_number));
            }
            if !in_range(dof.max_radius, 1.0, MAX_COC_RADIUS) {
                return invalid(format!(
                    "largest circle of confusion {} px must be between 1 and {MAX_COC_RADIUS} pixels in radius (--max-coc)",
                    dof.max_radius
                ));
            }
        }
        if let Some(blur) = self.motion_blur {
            if !in_range(blur.shutter, 0.0, 1.0) || blur.shutter == 0.0 {
                return invalid(format!("shutter {} must be above 0 and at most 1 frame interval (--shutter)", blur.shutter));
            }
            if !(1..=MAX_MOTION_BLUR_SAMPLES).contains(&blur.samples) {
                return invalid(format!(
                    "{} motion blur samples: give 1 to {MAX_MOTION_BLUR_SAMPLES} (--motion-blur-samples)",
                    blur.samples
                ));
            }
            if !in_range(blur.max_length, 1.0, MAX_MOTION_BLUR_LENGTH) {
                return invalid(format!(
                    "longest motion blur {} px must be between 1 and {MAX_MOTION_BLUR_LENGTH} pixels (--max-motion-blur)",
                    blur.max_length
                ));
            }
        }
        Ok(())
    }
}

/// The chain's per-frame constants. Keep in sync with `PostUniforms` in `post/post_types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PostUniforms {
    pub previous_clip_from_relative: [[f32; 4]; 4],
    pub exposure: [f32; 4],
    pub bloom: [f32; 4],
    pub depth_of_field: [f32; 4],
    pub motion_blur: [f32; 4],
}

/// What one frame's post constants depend on besides the settings.
#[derive(Clone, Copy, Debug)]
pub struct PostFrame<'a> {
    pub camera: &'a Camera,
    /// The camera of the frame before (the same camera for a first frame).
    pub previous_camera: &'a Camera,
    pub size: (u32, u32),
    /// Seconds since the frame before, for the exposure's adaptation; `None` for a first frame.
    pub interval: Option<f32>,
}

impl PostUniforms {
    pub fn new(settings: &PostSettings, frame: PostFrame, bloom_levels: u32) -> Result<Self> {
        let (width, height) = frame.size;
        let aspect = width as f32 / height as f32;
        // The previous view's clip space from the current camera-relative world, in f64: the
        // translation between the two cameras is small against the world's coordinates.
        let previous = frame.previous_camera;
        let previous_clip_from_world = previous.clip_from_view(aspect).as_dmat4() * previous.world_from_view.as_dmat4().inverse();
        let relative_to_world = glam::DMat4::from_translation(frame.camera.position().as_dvec3());
        let previous_clip_from_relative = (previous_clip_from_world * relative_to_world).as_mat4();

        let (key, rate) = match settings.auto_exposure {
            Some(auto) => {
                let rate = frame.interval.map_or(1.0, |dt| 1.0 - (-dt * auto.adaptation_speed).exp());
                (0.18 * 2f32.powf(auto.compensation_ev), rate)
            }
            None => (1.0, 1.0),
        };
        let bloom = settings.bloom.map_or([0.0; 4], |b| [b.intensity, 1.0 / bloom_levels as f32, 0.0, 0.0]);
        let depth_of_field = match settings.depth_of_field {
            None => [0.0; 4],
            Some(dof) => {
                let Projection::Perspective { yfov, .. } = frame.camera.projection else {
                    return Err(Error::InvalidConfig(format!(
                        "depth of field needs a perspective camera, and camera \"{}\" is orthographic; choose another camera or leave out --depth-of-field",
                        frame.camera.name
                    )));
                };
                // The focal length that gives this field of view on the sensor; the circle of
                // confusion's diameter on the sensor is f²/N · |1/S − 1/d| · S/(S − f), in pixels here
                // (the shader applies the last factor, since S may be measured on the GPU).
                let focal_length = SENSOR_HEIGHT * 0.5 / (yfov * 0.5).tan();
                if let Some(focus) = dof.focus_distance.filter(|&focus| focus <= focal_length) {
                    return Err(Error::InvalidConfig(format!(
                        "focus distance {focus} m is within the lens's focal length ({focal_length:.4} m for camera \"{}\"'s field of view); focus farther (--focus-distance)",
                        frame.camera.name
                    )));
                }
                let pixels_per_dioptre = focal_length * focal_length / dof.f_number / SENSOR_HEIGHT * height as f32;
                [dof.focus_distance.unwrap_or(0.0), pixels_per_dioptre, dof.max_radius, focal_length]
            }
        };
        let motion_blur = settings.motion_blur.map_or([0.0; 4], |m| [m.shutter, m.samples as f32, m.max_length, 0.0]);
        Ok(Self {
            previous_clip_from_relative: previous_clip_from_relative.to_cols_array_2d(),
            exposure: [key, 0.0, rate, settings.vignette],
            bloom,
            depth_of_field,
            motion_blur,
        })
    }
}

/// The tiles over a `width`×`height` image.
fn tile_count(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(TILE), height.div_ceil(TILE))
}

/// An image of one texel per tile, written by a tile pass and read by its gather.
fn tile_image(device: &wgpu::Device, label: &str, format: wgpu::TextureFormat, (width, height): (u32, u32)) -> wgpu::TextureView {
    let (columns, rows) = tile_count(width, height);
    let usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING;
    crate::pipelines::target(device, label, columns, rows, format, usage).create_view(&Default::default())
}

/// A pass in two dispatches of one shader — a reduction per 16×16 tile, then a per-pixel gather that
/// reads it (depth of field, motion blur) — each timed under its entry point's name.
pub struct TiledGather {
    steps: [TiledStep; 2],
}

struct TiledStep {
    entry: &'static str,
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    workgroups: (u32, u32),
}

/// An entry point and what it binds in group 1: each layout entry with the resource at its slot.
type Bindings<'a> = (&'static str, Vec<(wgpu::BindGroupLayoutEntry, wgpu::BindingResource<'a>)>);

impl TiledGather {
    fn new(ctx: &GpuContext, scene: &GpuScene, shader: &'static str, size: (u32, u32), tiles: Bindings, gather: Bindings) -> Result<Self> {
        let (columns, rows) = tile_count(size.0, size.1);
        let step = |(entry, bound): Bindings, (width, height): (u32, u32)| -> Result<TiledStep> {
            let (entries, resources): (Vec<_>, Vec<_>) = bound.into_iter().map(|(e, r)| (e, (e.binding, r))).unzip();
            let layout = bindings::layout(&ctx.device, entry, &entries);
            let pipeline = bindings::compute_pipeline(&ctx.device, entry, &ShaderDesc::new(shader), &[&scene.bind_group_layout, &layout])?;
            let bind_group = bindings::bind_group_at(&ctx.device, entry, &layout, resources);
            Ok(TiledStep { entry, pipeline, bind_group, workgroups: crate::passes::dispatch_size(width, height) })
        };
        Ok(Self { steps: [step(tiles, (columns, rows))?, step(gather, size)?] })
    }

    fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, scene: &GpuScene) {
        for step in &self.steps {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(step.entry),
                timestamp_writes: timer.as_deref_mut().map(|t| t.compute_pass(step.entry)),
            });
            pass.set_pipeline(&step.pipeline);
            pass.set_bind_group(0, &scene.bind_group, &[]);
            pass.set_bind_group(1, &step.bind_group, &[]);
            pass.dispatch_workgroups(step.workgroups.0, step.workgroups.1, 1);
        }
    }
}

/// An intermediate image of the chain.
fn post_image(device: &wgpu::Device, label: &str, (width, height): (u32, u32)) -> wgpu::TextureView {
    let usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING;
    crate::pipelines::target(device, label, width, height, POST_FORMAT, usage).create_view(&Default::default())
}

/// The post passes a pipeline built for its settings, in order, and what they share.
pub struct PostChain {
    pub settings: PostSettings,
    uniforms: wgpu::Buffer,
    /// Auto exposure's state, which frames carry over, and a copy to restore it from when frames are
    /// rendered again (`Renderer::render_frames`).
    exposure_state: wgpu::Buffer,
    exposure_saved: wgpu::Buffer,
    size: (u32, u32),
    depth: wgpu::TextureView,
    depth_of_field: Option<TiledGather>,
    /// Motion blur, its velocity pass and the velocity image.
    motion_blur: Option<(velocity::Velocity, wgpu::TextureView, TiledGather)>,
    exposure: Option<exposure::AutoExposurePass>,
    bloom: Option<bloom::BloomPass>,
    tonemap: tonemap::Tonemap,
}

impl PostChain {
    /// The chain from `hdr` (and `depth`) to `ldr` for `settings`.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        settings: PostSettings,
        (depth, hdr, ldr): (&wgpu::Texture, &wgpu::Texture, &wgpu::Texture),
    ) -> Result<Self> {
        settings.validate()?;
        let device = &ctx.device;
        let size = (hdr.width(), hdr.height());
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("post uniforms"),
            size: std::mem::size_of::<PostUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // The measured exposure: log2 of it, and whether it was measured (zeroed: not yet).
        let state_buffer = |label| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let (exposure_state, exposure_saved) = (state_buffer("exposure state"), state_buffer("exposure state saved"));
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let depth_view = view(depth);
        let mut current = view(hdr);

        let depth_of_field = match settings.depth_of_field {
            Some(_) => {
                let output = post_image(device, "depth of field", size);
                let pass = depth_of_field::new(ctx, scene, &uniforms, (&depth_view, &current, &output), size)?;
                current = output;
                Some(pass)
            }
            None => None,
        };
        let motion_blur = match settings.motion_blur {
            Some(_) => {
                let velocity_image = crate::pipelines::target(
                    device,
                    "velocity",
                    size.0,
                    size.1,
                    velocity::VELOCITY_FORMAT,
                    wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::RENDER_ATTACHMENT,
                );
                let velocity_view = view(&velocity_image);
                let velocity = velocity::Velocity::new(ctx, scene, &uniforms, &depth_view, &velocity_view)?;
                let output = post_image(device, "motion blur", size);
                let pass = motion_blur::new(ctx, scene, &uniforms, (&depth_view, &velocity_view, &current, &output), size)?;
                current = output;
                Some((velocity, velocity_view, pass))
            }
            None => None,
        };
        let exposure = settings
            .auto_exposure
            .map(|_| exposure::AutoExposurePass::new(ctx, scene, &uniforms, &current, &exposure_state))
            .transpose()?;
        let bloom = settings.bloom.map(|_| bloom::BloomPass::new(ctx, scene, &uniforms, &current, size)).transpose()?;
        let tonemap = tonemap::Tonemap::new(
            ctx,
            scene,
            &uniforms,
            tonemap::TonemapInputs {
                color: &current,
                bloom: bloom.as_ref().map(|b| &b.result),
                exposure_state: &exposure_state,
                auto_exposure: exposure.is_some(),
                ldr: &view(ldr),
            },
        )?;
        Ok(Self {
            settings,
            uniforms,
            exposure_state,
            exposure_saved,
            size,
            depth: depth_view,
            depth_of_field,
            motion_blur,
            exposure,
            bloom,
            tonemap,
        })
    }

    /// Whether `camera` can render these settings at `size` (depth of field needs a perspective lens
    /// whose focal length is shorter than the focus distance).
    pub fn check_camera(&self, camera: &Camera, size: (u32, u32)) -> Result<()> {
        let frame = PostFrame { camera, previous_camera: camera, size, interval: None };
        PostUniforms::new(&self.settings, frame, 1).map(|_| ())
    }

    /// Copies what frames carry over (the measured exposure) aside, for `restore_state`.
    pub fn save_state(&self, ctx: &GpuContext) {
        self.copy_state(ctx, &self.exposure_state, &self.exposure_saved);
    }

    pub fn restore_state(&self, ctx: &GpuContext) {
        self.copy_state(ctx, &self.exposure_saved, &self.exposure_state);
    }

    fn copy_state(&self, ctx: &GpuContext, from: &wgpu::Buffer, to: &wgpu::Buffer) {
        if self.exposure.is_some() {
            let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("post state") });
            encoder.copy_buffer_to_buffer(from, 0, to, 0, 16);
            ctx.queue.submit([encoder.finish()]);
        }
    }

    /// Writes the chain's constants for the next frame submitted.
    pub fn write_uniforms(&self, queue: &wgpu::Queue, frame: PostFrame) -> Result<()> {
        let levels = self.bloom.as_ref().map_or(1, |b| b.levels);
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&PostUniforms::new(&self.settings, frame, levels)?));
        Ok(())
    }

    /// Records the chain after the frame's HDR image is complete.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, scene: &GpuScene, eye: glam::Vec3) {
        if let Some(pass) = &self.depth_of_field {
            pass.record(encoder, timer.as_deref_mut(), scene);
        }
        if let Some((velocity, velocity_view, pass)) = &self.motion_blur {
            velocity.record(encoder, timer.as_deref_mut(), scene, eye, (&self.depth, velocity_view), self.size);
            pass.record(encoder, timer.as_deref_mut(), scene);
        }
        if let Some(pass) = &self.exposure {
            pass.record(encoder, timer.as_deref_mut(), scene, self.size);
        }
        if let Some(pass) = &self.bloom {
            pass.record(encoder, timer.as_deref_mut(), scene);
        }
        self.tonemap.record(encoder, timer, scene, self.size);
    }
}
