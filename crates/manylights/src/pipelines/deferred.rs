//! The deferred frame: surfaces and materials rasterised into a G-buffer (about the paper's 112 bits a
//! pixel, `passes/gbuffer.wgsl`), then decals and lights applied per pixel in compute by the same
//! shading core as the other pipelines, then tonemapping.
//!
//! ```text
//! light / decal structures ─▶ (tlas/blas builds, when groups move or change)
//! GpuScene ─▶ gbuffer_raster ─▶ albedo, normal, roughness-metallic, emission (not cleared)
//!                               + depth (cleared to 0)
//!                                   │
//!                                   ▼
//!             deferred_shade (decals, lights) ─▶ hdr (Rgba32Float)
//!                                   │
//!                                   ▼
//!             tonemap ─▶ ldr (Rgba8Unorm, sRGB-encoded)
//! ```

use crate::accel::VolumeStructure;
use crate::gpu::{GpuContext, GpuScene, GpuTimer};
use crate::passes::{
    deferred_shade::DeferredShade,
    gbuffer_raster::{GBufferRaster, GBUFFER_FORMATS},
    tonemap::Tonemap,
};
use crate::{
    pipelines::{DecalMethod, FrameTargets, LightMethod},
    Result,
};

pub struct DeferredPipeline {
    pub targets: FrameTargets,
    gbuffer: [wgpu::TextureView; 4],
    depth_view: wgpu::TextureView,
    raster: GBufferRaster,
    shade: DeferredShade,
    tonemap: Tonemap,
}

impl DeferredPipeline {
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        methods: (LightMethod, DecalMethod),
        structures: (&VolumeStructure, &VolumeStructure),
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let targets = FrameTargets::new(&ctx.device, width, height);
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let labels = ["gbuffer albedo", "gbuffer normal", "gbuffer roughness-metallic", "gbuffer emission"];
        let gbuffer = std::array::from_fn(|i| view(&super::target(&ctx.device, labels[i], width, height, GBUFFER_FORMATS[i], usage)));
        let (depth_view, hdr_view, ldr_view) = (view(&targets.depth), view(&targets.hdr), view(&targets.ldr));
        Ok(Self {
            raster: GBufferRaster::new(ctx, scene)?,
            shade: DeferredShade::new(ctx, scene, methods, structures, (&depth_view, &gbuffer), &hdr_view)?,
            tonemap: Tonemap::new(ctx, scene, &hdr_view, &ldr_view)?,
            targets,
            gbuffer,
            depth_view,
        })
    }

    /// Records one frame seen from `eye`. The frame uniforms must already be written.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, scene: &GpuScene, eye: glam::Vec3) {
        let (width, height) = (self.targets.width, self.targets.height);
        self.raster.record(encoder, timer.as_deref_mut(), scene, eye, &self.gbuffer, &self.depth_view);
        self.shade.record(encoder, timer.as_deref_mut(), scene, width, height);
        self.tonemap.record(encoder, timer, width, height);
    }
}
