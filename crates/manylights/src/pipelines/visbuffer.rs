//! The visibility-buffer frame: raster ids and depth, then resolve and shade every pixel in compute,
//! then tonemap. Shading in compute rather than in fragments matters on our benchmark GPUs, where the
//! same shading loop ran 35× slower as a fragment shader.
//!
//! ```text
//! light / decal structures ─▶ (tlas/blas builds, when groups move or change)
//! GpuScene ─▶ visbuffer_raster ─▶ visibility (R32Uint, not cleared) + depth (cleared to 0)
//!                                   │
//!                                   ▼
//!             surface_motion, when kept state follows animated instances ─▶ surface motions (group 0)
//!                                   │
//!                                   ▼
//!             ray_shadows (+ shadow_filter), with sun shadows ─▶ sun visibility and blocker distance (Rg32Float)
//!                                   │
//!                                   ▼
//!             visbuffer_shade (material, decals, lights; reflections) ─▶ hdr (Rgba32Float)
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
    ray_shadows::RayShadows,
    transparent_shade::TransparentShade,
    visbuffer_raster::{VisbufferImages, VisbufferRaster, VISIBILITY_FORMAT},
    visbuffer_shade::{VisbufferShade, VisbufferShadeImages},
};
use crate::post::{PostChain, PostImages};
use crate::{
    passes::{FrameInputs, ShadedImage},
    pipelines::{FrameSetup, FrameTargets},
    Result,
};

pub struct VisbufferPipeline {
    pub targets: FrameTargets,
    visibility_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    hdr_view: wgpu::TextureView,
    raster: VisbufferRaster,
    /// Present when the sun casts ray-traced shadows.
    shadows: Option<RayShadows>,
    shade: VisbufferShade,
    /// Present when animated instances' motion is tracked (`plan::FramePlan::tracks_surface_motion`).
    surface_motion: Option<SurfaceMotion>,
    /// Present when `restir`'s lighting is denoised (`plan::FramePlan::denoises`).
    pub(super) denoiser: Option<Denoiser>,
    /// Present when the scene has blended or transmissive draws.
    pub(super) transparent: Option<TransparentShade>,
    /// Depth of field, motion blur, exposure, bloom, vignette and tonemapping (`post/`).
    pub post: PostChain,
}

impl VisbufferPipeline {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, setup: FrameSetup) -> Result<Self> {
        let FrameSetup { methods, post, structures, size: (width, height), .. } = setup;
        let targets = FrameTargets::new(&ctx.device, width, height);
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let visibility = super::target(&ctx.device, "visibility", width, height, VISIBILITY_FORMAT, usage);
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let (visibility_view, depth_view, hdr_view) = (view(&visibility), view(&targets.depth), view(&targets.hdr));
        let shadows = setup
            .traced_shadows()
            .map(|mode| RayShadows::new(ctx, scene, mode, setup.methods.ray_trace_module(), &depth_view, (width, height)))
            .transpose()?;
        Ok(Self {
            raster: VisbufferRaster::new(ctx, scene)?,
            shade: VisbufferShade::new(
                ctx,
                scene,
                methods,
                structures,
                shadows.as_ref(),
                VisbufferShadeImages { visibility: &visibility_view, depth: &depth_view, hdr: &hdr_view },
            )?,
            shadows,
            surface_motion: setup.surface_motion.then(|| SurfaceMotion::new(ctx, scene, &depth_view)).transpose()?,
            denoiser: methods.denoised.then(|| Denoiser::new(ctx, scene, &depth_view, &targets.hdr, (width, height))).transpose()?,
            transparent: TransparentShade::new(ctx, scene, methods, structures, (&targets.hdr, &targets.depth))?,
            post: PostChain::new(ctx, scene, post, PostImages { depth: &targets.depth, hdr: &targets.hdr, ldr: &targets.ldr })?,
            targets,
            visibility_view,
            depth_view,
            hdr_view,
        })
    }

    /// Records one frame. The frame uniforms must already be written.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, inputs: &FrameInputs) {
        let (width, height) = (self.targets.width, self.targets.height);
        let images = VisbufferImages { visibility: &self.visibility_view, depth: &self.depth_view };
        self.raster.record(encoder, timer.as_deref_mut(), inputs.scene, images);
        if let Some(motion) = &self.surface_motion {
            motion.record(encoder, timer.as_deref_mut(), inputs.scene, &self.depth_view);
        }
        if let Some(shadows) = &self.shadows {
            shadows.record(encoder, timer.as_deref_mut(), inputs.scene, (width, height));
        }
        self.shade.record(encoder, timer.as_deref_mut(), inputs, (width, height));
        if let Some(denoiser) = &self.denoiser {
            denoiser.record(encoder, timer.as_deref_mut(), inputs);
        }
        if let Some(transparent) = &self.transparent {
            transparent.record(encoder, timer.as_deref_mut(), inputs, ShadedImage { hdr: &self.hdr_view, depth: &self.depth_view });
        }
        self.post.record(encoder, timer, inputs.scene);
    }
}
