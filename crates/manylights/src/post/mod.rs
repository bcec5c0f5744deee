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
use crate::passes::builder::ComputeStep;
use crate::scene::{Camera, Projection};
use crate::settings::{PostSettings, POST_TILE};
use crate::{Error, Result};
use velocity::VelocityImages;

/// The images between post passes: 32-bit float like the HDR image, so a pixel an effect leaves
/// alone passes through exactly.
pub const POST_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Sensor height of the thin lens depth of field models: 35 mm film's 24 mm, so f-numbers and focus
/// behave as on a full-frame camera with the view's field of view.
pub const SENSOR_HEIGHT: f32 = 0.024;

/// The frame's images the chain reads and writes: its depth and shaded HDR image, and the 8-bit
/// image it ends in.
#[derive(Clone, Copy)]
pub struct PostImages<'a> {
    pub depth: &'a wgpu::Texture,
    pub hdr: &'a wgpu::Texture,
    pub ldr: &'a wgpu::Texture,
}

/// The images a screen-space effect reads and writes: the frame's depth, its input, its output.
#[derive(Clone, Copy)]
pub struct EffectImages<'a> {
    pub depth: &'a wgpu::TextureView,
    pub input: &'a wgpu::TextureView,
    pub output: &'a wgpu::TextureView,
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

        let (key, rate) = match settings.exposure.auto() {
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
    (width.div_ceil(POST_TILE), height.div_ceil(POST_TILE))
}

/// An image of one texel per tile, written by a tile pass and read by its gather.
fn tile_image(device: &wgpu::Device, label: &str, format: wgpu::TextureFormat, (width, height): (u32, u32)) -> wgpu::TextureView {
    let (columns, rows) = tile_count(width, height);
    let usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING;
    crate::gpu::textures::target(device, label, columns, rows, format, usage).create_view(&Default::default())
}

/// A pass in two dispatches of one shader — a reduction per 16×16 tile, then a per-pixel gather that
/// reads it (depth of field, motion blur) — each timed under its entry point's name.
pub struct TiledGather {
    steps: [TiledStep; 2],
}

struct TiledStep {
    step: ComputeStep,
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
            let step = ComputeStep::new(&ctx.device, &ShaderDesc::new(shader), entry, &[&scene.bind_group_layout, &layout], &[])?;
            let bind_group = bindings::bind_group_at(&ctx.device, entry, &layout, resources);
            Ok(TiledStep { step, bind_group, workgroups: crate::passes::dispatch_size(width, height) })
        };
        Ok(Self { steps: [step(tiles, (columns, rows))?, step(gather, size)?] })
    }

    fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, scene: &GpuScene) {
        for step in &self.steps {
            step.step.record(encoder, timer.as_deref_mut(), &[&scene.bind_group, &step.bind_group], step.workgroups);
        }
    }
}

/// An intermediate image of the chain.
fn post_image(device: &wgpu::Device, label: &str, (width, height): (u32, u32)) -> wgpu::TextureView {
    let usage = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING;
    crate::gpu::textures::target(device, label, width, height, POST_FORMAT, usage).create_view(&Default::default())
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
    pub fn new(ctx: &GpuContext, scene: &GpuScene, settings: PostSettings, PostImages { depth, hdr, ldr }: PostImages) -> Result<Self> {
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
                let pass = depth_of_field::new(
                    ctx,
                    scene,
                    &uniforms,
                    EffectImages { depth: &depth_view, input: &current, output: &output },
                    size,
                )?;
                current = output;
                Some(pass)
            }
            None => None,
        };
        let motion_blur = match settings.motion_blur {
            Some(_) => {
                let velocity_image = crate::gpu::textures::target(
                    device,
                    "velocity",
                    size.0,
                    size.1,
                    velocity::VELOCITY_FORMAT,
                    wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::RENDER_ATTACHMENT,
                );
                let velocity_view = view(&velocity_image);
                let velocity =
                    velocity::Velocity::new(ctx, scene, &uniforms, VelocityImages { depth: &depth_view, velocity: &velocity_view })?;
                let output = post_image(device, "motion blur", size);
                let pass = motion_blur::new(
                    ctx,
                    scene,
                    &uniforms,
                    EffectImages { depth: &depth_view, input: &current, output: &output },
                    &velocity_view,
                    size,
                )?;
                current = output;
                Some((velocity, velocity_view, pass))
            }
            None => None,
        };
        let exposure = settings
            .exposure
            .auto()
            .map(|_| exposure::AutoExposurePass::new(ctx, scene, &uniforms, &current, &depth_view, &exposure_state))
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
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, scene: &GpuScene) {
        if let Some(pass) = &self.depth_of_field {
            pass.record(encoder, timer.as_deref_mut(), scene);
        }
        if let Some((velocity, velocity_view, pass)) = &self.motion_blur {
            velocity.record(
                encoder,
                timer.as_deref_mut(),
                scene,
                VelocityImages { depth: &self.depth, velocity: velocity_view },
                self.size,
            );
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
