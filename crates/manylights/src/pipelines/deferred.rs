//! The deferred frame: surfaces and materials rasterised into a G-buffer (about the paper's 112 bits a
//! pixel, `passes/gbuffer.wgsl`), then decals and lights applied per pixel in compute by the same
//! shading core as the other pipelines, then tonemapping. With `--decal-method deferred-decals`, the
//! decals' boxes are rasterised into the G-buffer before lighting instead (Kim 2012).
//!
//! ```text
//! light / decal structures ─▶ (tlas/blas builds, when groups move or change; clustered lists)
//! GpuScene ─▶ gbuffer_raster ─▶ albedo, normal, roughness-metallic, material (not cleared)
//!                               + depth (cleared to 0)
//!                                   │
//!                                   ├─▶ surface_motion, when kept state follows animated instances ─▶ surface motions
//!                                   ├─▶ (deferred decals only) copy normals ─▶ deferred_decals:
//!                                   │     decal boxes blended into albedo, normal, roughness-metallic
//!                                   ▼
//!             deferred_shade (decals, lights) ─▶ hdr (Rgba32Float)
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
    deferred_decals::DeferredDecals,
    deferred_shade::{DeferredShade, DeferredShadeImages},
    gbuffer_raster::{GBufferRaster, GBUFFER_FORMATS, GBUFFER_TARGETS},
    ray_shadows::RayShadows,
    transparent_shade::TransparentShade,
};
use crate::post::{PostChain, PostImages};
use crate::{
    passes::{FrameInputs, ShadedImage},
    pipelines::{FrameSetup, FrameTargets},
    settings::DecalMethod,
    Result,
};

pub struct DeferredPipeline {
    pub targets: FrameTargets,
    gbuffer: [wgpu::TextureView; GBUFFER_TARGETS],
    depth_view: wgpu::TextureView,
    hdr_view: wgpu::TextureView,
    raster: GBufferRaster,
    /// With deferred decals: the pass, the G-buffer's normals and the copy of them the pass reads.
    decals: Option<(DeferredDecals, wgpu::Texture, wgpu::Texture)>,
    /// Present when the sun casts ray-traced shadows.
    shadows: Option<RayShadows>,
    shade: DeferredShade,
    /// Present when animated instances' motion is tracked (`plan::FramePlan::tracks_surface_motion`).
    surface_motion: Option<SurfaceMotion>,
    /// Present when `restir`'s lighting is denoised (`plan::FramePlan::denoises`).
    pub(super) denoiser: Option<Denoiser>,
    /// Present when the scene has blended or transmissive draws.
    pub(super) transparent: Option<TransparentShade>,
    /// Depth of field, motion blur, exposure, bloom, vignette and tonemapping (`post/`).
    pub post: PostChain,
}

impl DeferredPipeline {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, setup: FrameSetup) -> Result<Self> {
        let FrameSetup { methods, post, structures, size: (width, height), .. } = setup;
        let targets = FrameTargets::new(&ctx.device, width, height);
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        use wgpu::TextureUsages as U;
        let labels = ["gbuffer albedo", "gbuffer normal", "gbuffer roughness-metallic", "gbuffer material"];
        let textures: [wgpu::Texture; GBUFFER_TARGETS] = std::array::from_fn(|i| {
            super::target(
                &ctx.device,
                labels[i],
                width,
                height,
                GBUFFER_FORMATS[i],
                U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
            )
        });
        let gbuffer = textures.each_ref().map(view);
        let (depth_view, hdr_view) = (view(&targets.depth), view(&targets.hdr));
        let decals = match methods.decals {
            DecalMethod::DeferredDecals => {
                let copy =
                    super::target(&ctx.device, "surface normals", width, height, GBUFFER_FORMATS[1], U::COPY_DST | U::TEXTURE_BINDING);
                Some((DeferredDecals::new(ctx, scene, structures.decals, &depth_view, &view(&copy))?, textures[1].clone(), copy))
            }
            _ => None,
        };
        let shadows = setup
            .traced_shadows()
            .map(|mode| RayShadows::new(ctx, scene, mode, setup.methods.ray_trace_module(), &depth_view, (width, height)))
            .transpose()?;
        Ok(Self {
            raster: GBufferRaster::new(ctx, scene, methods)?,
            decals,
            shade: DeferredShade::new(
                ctx,
                scene,
                methods,
                structures,
                shadows.as_ref(),
                DeferredShadeImages { depth: &depth_view, gbuffer: &gbuffer, hdr: &hdr_view },
            )?,
            shadows,
            surface_motion: setup.surface_motion.then(|| SurfaceMotion::new(ctx, scene, &depth_view)).transpose()?,
            denoiser: methods.denoised.then(|| Denoiser::new(ctx, scene, &depth_view, &targets.hdr, (width, height))).transpose()?,
            transparent: TransparentShade::new(ctx, scene, methods, structures, (&targets.hdr, &targets.depth))?,
            post: PostChain::new(ctx, scene, post, PostImages { depth: &targets.depth, hdr: &targets.hdr, ldr: &targets.ldr })?,
            targets,
            gbuffer,
            depth_view,
            hdr_view,
        })
    }

    /// Records one frame. The frame uniforms must already be written.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, inputs: &FrameInputs) {
        let (width, height) = (self.targets.width, self.targets.height);
        self.raster.record(encoder, timer.as_deref_mut(), inputs.scene, &self.gbuffer, &self.depth_view);
        if let Some(motion) = &self.surface_motion {
            motion.record(encoder, timer.as_deref_mut(), inputs.scene, &self.depth_view);
        }
        if let Some((decals, normals, copy)) = &self.decals {
            encoder.copy_texture_to_texture(normals.as_image_copy(), copy.as_image_copy(), normals.size());
            decals.record(encoder, timer.as_deref_mut(), inputs.scene, inputs.decals, &self.gbuffer, &self.depth_view);
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
