//! The denoiser of sampled direct lighting (`restir`), after SVGF (Schied et al. 2017) on demodulated
//! diffuse and specular light, with its history clamped to the frame's samples around each pixel and
//! kept unfiltered. The shading core writes each pixel's sample (`DenoiseSample`: its
//! sampled light divided by the albedos, its normal and position; `shading/shading_pixel.wgsl`)
//! instead of adding that light to the image; then, in compute:
//!
//! ```text
//! samples + history (previous frame's half) ─▶ temporal ─▶ history (this frame's half: moments, surface)
//!                                                  │        + light A (lobes and their variance) + guides
//!                                                  ▼
//!                                      variance (short histories: spatial moments) ─▶ light B
//!                                                  │
//!                                                  ▼
//!         filter × FILTER_STEPS (3×3 à-trous, steps 1, 2, 4, 8) ─▶ light A/B
//!                                                  │
//!                                                  ▼
//!                 compose (light × albedos, added to a copy of hdr) ─▶ hdr
//! ```
//!
//! The history's two halves alternate with the frame's parity. Pixels without a surface (depth 0)
//! keep nothing and add nothing.

pub mod compose;
pub mod filter;
pub mod temporal;
pub mod variance;

use crate::gpu::{bindings, scene::pixel_buffer, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::passes::{builder::ComputeStep, FrameInputs};
use crate::Result;

/// À-trous steps of a 3×3 kernel: taps 1 to 8 pixels apart, a 31-pixel-wide footprint.
pub const FILTER_STEPS: u32 = 4;
/// A pixel's history (`DenoiseHistory` in `denoise_types.wgsl`) and its light between the filters
/// (`DenoiseLight`, eight halves).
const HISTORY_BYTES: usize = 64;
const LIGHT_BYTES: usize = 16;
/// A pixel's surface as the spatial passes read it (`denoise_guide`).
const GUIDE_BYTES: usize = 16;

pub struct Denoiser {
    temporal: ParityStep,
    variance: ParityStep,
    filter: filter::Filter,
    compose: compose::Compose,
    /// Two halves, the frames alternating which they write and which they read.
    history: [wgpu::Buffer; 2],
    /// The frame's HDR image, which `compose` adds the light to.
    hdr: wgpu::Texture,
    size: (u32, u32),
}

impl Denoiser {
    /// The denoiser for images of `size` whose depth is `depth` and HDR image `hdr`.
    pub fn new(ctx: &GpuContext, scene: &GpuScene, depth: &wgpu::TextureView, hdr: &wgpu::Texture, size: (u32, u32)) -> Result<Self> {
        let device = &ctx.device;
        let pixels = u64::from(size.0) * u64::from(size.1);
        let limit = ctx.limits.max_storage_buffer_binding_size;
        let buffer = |what, bytes| pixel_buffer(device, what, pixels, bytes, limit, "--denoise off");
        let history = [buffer("the denoiser's history", HISTORY_BYTES)?, buffer("the denoiser's history", HISTORY_BYTES)?];
        let light = [buffer("the denoiser's light", LIGHT_BYTES)?, buffer("the denoiser's light", LIGHT_BYTES)?];
        let guides = buffer("the denoiser's guides", GUIDE_BYTES)?;
        let temporal = temporal::step(ctx, scene, depth, &history, &light[0], &guides)?;
        let variance = variance::step(ctx, scene, &history, [&light[0], &light[1]], &guides)?;
        let filter = filter::Filter::new(ctx, scene, &light, &guides)?;
        let compose = compose::Compose::new(ctx, scene, filter.result(&light), hdr)?;
        Ok(Self { temporal, variance, filter, compose, history, hdr: hdr.clone(), size })
    }

    /// Denoises the frame's samples and adds the light to the HDR image.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, inputs: &FrameInputs) {
        let workgroups = super::dispatch_size(self.size.0, self.size.1);
        let scene = &inputs.scene.bind_group;
        self.temporal.record(encoder, timer.as_deref_mut(), scene, inputs.parity, workgroups);
        self.variance.record(encoder, timer.as_deref_mut(), scene, inputs.parity, workgroups);
        self.filter.record(encoder, timer.as_deref_mut(), scene, workgroups);
        self.compose.record(encoder, timer, scene, &self.hdr, workgroups);
    }

    /// Forgets every pixel's history: the next frame starts afresh.
    pub fn clear_history(&self, ctx: &GpuContext) {
        let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("clear denoiser history") });
        for half in &self.history {
            encoder.clear_buffer(half, 0, None);
        }
        ctx.queue.submit([encoder.finish()]);
    }
}

/// A compute pass over every pixel whose group 1 depends on the frame's parity (which half of the
/// history it reads or writes); group 0 is the scene.
pub struct ParityStep {
    step: ComputeStep,
    bind_groups: [wgpu::BindGroup; 2],
}

impl ParityStep {
    /// `entry` of `shader` over group 1 laid out as `entries`, bound to `resources(parity)`.
    fn new<'a>(
        ctx: &GpuContext,
        scene: &GpuScene,
        (shader, entry): (&'static str, &'static str),
        entries: &[wgpu::BindGroupLayoutEntry],
        resources: impl Fn(usize) -> Vec<wgpu::BindingResource<'a>>,
    ) -> Result<Self> {
        let device = &ctx.device;
        let layout = bindings::layout(device, entry, entries);
        let step = ComputeStep::new(device, &ShaderDesc::new(shader), entry, &[&scene.bind_group_layout, &layout], &[])?;
        let bind_groups = [0, 1].map(|parity| bindings::bind_group(device, entry, &layout, resources(parity)));
        Ok(Self { step, bind_groups })
    }

    fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        scene: &wgpu::BindGroup,
        parity: usize,
        workgroups: (u32, u32),
    ) {
        self.step.record(encoder, timer, &[scene, &self.bind_groups[parity]], workgroups);
    }
}
