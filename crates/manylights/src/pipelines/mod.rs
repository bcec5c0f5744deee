//! Frame graphs: each pipeline orders the passes of one frame, read top to bottom in its own file:
//! `visbuffer.rs` (raster ids, shade in compute), `deferred.rs` (G-buffer, light in compute) and
//! `forward.rs` (depth prepass, shade in fragments).
//! Both call the same shading core; enumeration methods plug in through `LightMethod` and
//! `DecalMethod`.

pub mod deferred;
pub mod forward;
pub mod visbuffer;

pub use deferred::DeferredPipeline;
pub use forward::ForwardPipeline;
pub use visbuffer::VisbufferPipeline;

use crate::gpu::textures::target;
use crate::gpu::{GpuContext, GpuScene, GpuTimer};
use crate::passes::{visbuffer_raster::DEPTH_FORMAT, visbuffer_shade::HDR_FORMAT};
use crate::passes::{FrameInputs, Structures};
use crate::plan::ShadingMethods;
use crate::post::{tonemap::LDR_FORMAT, PostChain};
use crate::settings::{PipelineKind, PostSettings, SunShadows};
use crate::Result;

/// The pipeline a renderer runs. Boxed: the variants hold hundreds of bytes of GPU handles each.
pub enum FramePipeline {
    Visbuffer(Box<VisbufferPipeline>),
    Deferred(Box<DeferredPipeline>),
    Forward(Box<ForwardPipeline>),
}

impl FramePipeline {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, kind: PipelineKind, setup: FrameSetup) -> Result<Self> {
        Ok(match kind {
            PipelineKind::Visbuffer => Self::Visbuffer(Box::new(VisbufferPipeline::new(ctx, scene, setup)?)),
            PipelineKind::Deferred => Self::Deferred(Box::new(DeferredPipeline::new(ctx, scene, setup)?)),
            PipelineKind::Forward => Self::Forward(Box::new(ForwardPipeline::new(ctx, scene, setup)?)),
        })
    }

    /// Records one frame. The frame uniforms must already be written.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, inputs: &FrameInputs) {
        match self {
            Self::Visbuffer(p) => p.record(encoder, timer, inputs),
            Self::Deferred(p) => p.record(encoder, timer, inputs),
            Self::Forward(p) => p.record(encoder, timer, inputs),
        }
    }

    pub fn targets(&self) -> &FrameTargets {
        match self {
            Self::Visbuffer(p) => &p.targets,
            Self::Deferred(p) => &p.targets,
            Self::Forward(p) => &p.targets,
        }
    }

    /// Forgets the denoiser's history, if the pipeline has a denoiser: the next frame starts afresh.
    pub fn clear_denoiser_history(&self, ctx: &GpuContext) {
        let denoiser = match self {
            Self::Visbuffer(p) => p.denoiser.as_ref(),
            Self::Deferred(p) => p.denoiser.as_ref(),
            Self::Forward(p) => p.denoiser.as_ref(),
        };
        if let Some(denoiser) = denoiser {
            denoiser.clear_history(ctx);
        }
    }

    /// Whether the blended surfaces' layers held every fragment of the frames since the last call;
    /// if not, they grow and the frames must be rendered again.
    pub fn blended_layers_fitted(&mut self, ctx: &GpuContext) -> Result<bool> {
        let transparent = match self {
            Self::Visbuffer(p) => p.transparent.as_mut(),
            Self::Deferred(p) => p.transparent.as_mut(),
            Self::Forward(p) => p.transparent.as_mut(),
        };
        transparent.map_or(Ok(true), |t| t.fitted(ctx))
    }

    /// The post chain every pipeline ends with.
    pub fn post(&self) -> &PostChain {
        match self {
            Self::Visbuffer(p) => &p.post,
            Self::Deferred(p) => &p.post,
            Self::Forward(p) => &p.post,
        }
    }
}

/// What every pipeline is built for: the shading core's methods, how the sun's shadows are traced
/// (`passes::ray_shadows`; `Off`: not at all), the post effects (`post/`), the light and decal
/// structures, the image size, and whether surfaces' motion is tracked.
#[derive(Clone, Copy)]
pub struct FrameSetup<'a> {
    pub methods: ShadingMethods,
    pub shadows: SunShadows,
    pub post: PostSettings,
    pub structures: Structures<'a>,
    pub size: (u32, u32),
    /// Animated instances' surface motion is recorded for reuse (`plan::FramePlan::tracks_surface_motion`).
    pub surface_motion: bool,
}

impl FrameSetup<'_> {
    /// The sun's shadow mode when it traces shadows.
    pub fn traced_shadows(&self) -> Option<SunShadows> {
        (self.shadows != SunShadows::Off).then_some(self.shadows)
    }
}

/// The images every pipeline writes; `hdr` and `ldr` can be read back.
pub struct FrameTargets {
    pub width: u32,
    pub height: u32,
    pub depth: wgpu::Texture,
    pub hdr: wgpu::Texture,
    pub ldr: wgpu::Texture,
}

impl FrameTargets {
    fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        use wgpu::TextureUsages as U;
        Self {
            width,
            height,
            depth: target(device, "depth", width, height, DEPTH_FORMAT, U::RENDER_ATTACHMENT | U::TEXTURE_BINDING),
            // Written by a compute pass (visibility buffer) or as a colour attachment (forward).
            hdr: target(
                device,
                "hdr",
                width,
                height,
                HDR_FORMAT,
                U::STORAGE_BINDING | U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
            ),
            // Sampled by the viewer to show it.
            ldr: target(device, "ldr", width, height, LDR_FORMAT, U::STORAGE_BINDING | U::COPY_SRC | U::TEXTURE_BINDING),
        }
    }
}
