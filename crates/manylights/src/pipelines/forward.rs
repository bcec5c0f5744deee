//! The forward frame: a depth prepass, then every visible fragment shaded in the fragment stage by the
//! same shading core as the visibility buffer's compute resolve, then tonemapping. On GPUs with few
//! graphics units fragment shading is many times slower than the compute resolve (BENCHMARKS.md);
//! this pipeline is there to compare, as the paper's table does, and for surfaces only a forward
//! pass can draw.
//!
//! ```text
//! light / decal structures ─▶ (tlas/blas builds, when groups move or change)
//! GpuScene ─▶ depth_prepass ─▶ depth (cleared to 0)
//!                                   │
//!                                   ▼
//!             surface_motion, when kept state follows animated instances ─▶ surface motions (group 0)
//!                                   │
//!                                   ▼
//!             ray_shadows (+ shadow_filter), with sun shadows ─▶ sun visibility and blocker distance (Rg32Float)
//!                                   │
//!                                   ▼
//!             forward_shade (EQUAL depth; material, decals, lights; then sky) ─▶ hdr (Rgba32Float)
//!                                   │
//!                                   ▼
//!             denoiser, with restir (`passes/denoise/`) ─▶ denoised light added to hdr
//!                                   │
//!                                   ▼
//!             transmission_background, with transmissive draws ─▶ mip chain of hdr (Rgba16Float)
//!                                   │
//!                                   ▼
//!             transmissive_shade (transmissive draws' nearest ids rasterized, then shaded in
//!             compute) ─▶ over hdr; blended_shade (BLEND draws' layers linked per pixel, sorted and
//!             shaded in compute) ─▶ over hdr
//!                                   │
//!                                   ▼
//!             post chain (depth of field, motion blur, exposure, bloom; tonemap) ─▶ ldr (Rgba8Unorm, sRGB-encoded)
//! ```

use crate::gpu::{GpuContext, GpuScene, GpuTimer};
use crate::passes::denoise::Denoiser;
use crate::passes::surface_motion::SurfaceMotion;
use crate::passes::{
    depth_prepass::DepthPrepass, forward_shade::ForwardShade, ray_shadows::RayShadows, transparent_shade::TransparentShade,
};
use crate::post::{PostChain, PostImages};
use crate::{
    passes::{FrameInputs, ShadedImage},
    pipelines::{FrameSetup, FrameTargets},
    Result,
};

pub struct ForwardPipeline {
    pub targets: FrameTargets,
    depth_view: wgpu::TextureView,
    hdr_view: wgpu::TextureView,
    prepass: DepthPrepass,
    /// Present when the sun casts ray-traced shadows.
    shadows: Option<RayShadows>,
    shade: ForwardShade,
    /// Present when animated instances' motion is tracked (`plan::FramePlan::tracks_surface_motion`).
    surface_motion: Option<SurfaceMotion>,
    /// Present when `restir`'s lighting is denoised (`plan::FramePlan::denoises`).
    pub(super) denoiser: Option<Denoiser>,
    /// Present when the scene has blended or transmissive draws.
    pub(super) transparent: Option<TransparentShade>,
    /// Depth of field, motion blur, exposure, bloom, vignette and tonemapping (`post/`).
    pub post: PostChain,
}

impl ForwardPipeline {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, setup: FrameSetup) -> Result<Self> {
        let FrameSetup { methods, post, structures, size: (width, height), .. } = setup;
        let targets = FrameTargets::new(&ctx.device, width, height);
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let (depth_view, hdr_view) = (view(&targets.depth), view(&targets.hdr));
        let shadows = setup
            .traced_shadows()
            .map(|mode| RayShadows::new(ctx, scene, mode, setup.methods.ray_trace_module(), &depth_view, (width, height)))
            .transpose()?;
        Ok(Self {
            prepass: DepthPrepass::new(ctx, scene)?,
            shade: ForwardShade::new(ctx, scene, methods, structures, shadows.as_ref())?,
            shadows,
            surface_motion: setup.surface_motion.then(|| SurfaceMotion::new(ctx, scene, &depth_view)).transpose()?,
            denoiser: methods.denoised.then(|| Denoiser::new(ctx, scene, &depth_view, &targets.hdr, (width, height))).transpose()?,
            transparent: TransparentShade::new(ctx, scene, methods, structures, (&targets.hdr, &targets.depth))?,
            post: PostChain::new(ctx, scene, post, PostImages { depth: &targets.depth, hdr: &targets.hdr, ldr: &targets.ldr })?,
            targets,
            depth_view,
            hdr_view,
        })
    }

    /// Records one frame. The frame uniforms must already be written.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, inputs: &FrameInputs) {
        self.prepass.record(encoder, timer.as_deref_mut(), inputs.scene, &self.depth_view);
        if let Some(motion) = &self.surface_motion {
            motion.record(encoder, timer.as_deref_mut(), inputs.scene, &self.depth_view);
        }
        if let Some(shadows) = &self.shadows {
            shadows.record(encoder, timer.as_deref_mut(), inputs.scene, (self.targets.width, self.targets.height));
        }
        self.shade.record(encoder, timer.as_deref_mut(), inputs, ShadedImage { hdr: &self.hdr_view, depth: &self.depth_view });
        if let Some(denoiser) = &self.denoiser {
            denoiser.record(encoder, timer.as_deref_mut(), inputs);
        }
        if let Some(transparent) = &self.transparent {
            transparent.record(encoder, timer.as_deref_mut(), inputs, ShadedImage { hdr: &self.hdr_view, depth: &self.depth_view });
        }
        self.post.record(encoder, timer, inputs.scene);
    }
}
