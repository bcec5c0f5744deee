//! The forward frame: a depth prepass, then every visible fragment shaded in the fragment stage by the
//! same shading core as the visibility buffer's compute resolve, then tonemapping. On our benchmark
//! GPUs (H100/H200 through Vulkan) fragment shading is many times slower than the compute resolve;
//! this pipeline is there to compare, as the paper's table does, and for surfaces only a forward
//! pass can draw.
//!
//! ```text
//! light / decal structures ─▶ (tlas/blas builds, when groups move or change)
//! GpuScene ─▶ depth_prepass ─▶ depth (cleared to 0)
//!                                   │
//!                                   ▼
//!             forward_shade (EQUAL depth; material, decals, lights; then sky) ─▶ hdr (Rgba32Float)
//!                                   │
//!                                   ▼
//!             transparent_shade (BLEND draws, back to front) ─▶ blended over hdr
//!                                   │
//!                                   ▼
//!             tonemap ─▶ ldr (Rgba8Unorm, sRGB-encoded)
//! ```

use crate::accel::VolumeStructure;
use crate::gpu::{GpuContext, GpuScene, GpuTimer};
use crate::passes::{depth_prepass::DepthPrepass, forward_shade::ForwardShade, tonemap::Tonemap, transparent_shade::TransparentShade};
use crate::{
    pipelines::{FrameInputs, FrameTargets, ShadingMethods},
    Result,
};

pub struct ForwardPipeline {
    pub targets: FrameTargets,
    depth_view: wgpu::TextureView,
    hdr_view: wgpu::TextureView,
    prepass: DepthPrepass,
    shade: ForwardShade,
    /// Present when the scene has transparent draws.
    transparent: Option<TransparentShade>,
    tonemap: Tonemap,
}

impl ForwardPipeline {
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        methods: ShadingMethods,
        structures: (&VolumeStructure, &VolumeStructure),
        width: u32,
        height: u32,
    ) -> Result<Self> {
        let targets = FrameTargets::new(&ctx.device, width, height);
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let (depth_view, hdr_view, ldr_view) = (view(&targets.depth), view(&targets.hdr), view(&targets.ldr));
        Ok(Self {
            prepass: DepthPrepass::new(ctx, scene)?,
            shade: ForwardShade::new(ctx, scene, methods, structures)?,
            transparent: TransparentShade::new(ctx, scene, methods, structures)?,
            tonemap: Tonemap::new(ctx, scene, &hdr_view, &ldr_view)?,
            targets,
            depth_view,
            hdr_view,
        })
    }

    /// Records one frame. The frame uniforms must already be written.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, inputs: &FrameInputs) {
        self.prepass.record(encoder, timer.as_deref_mut(), inputs.scene, inputs.eye, &self.depth_view);
        self.shade.record(encoder, timer.as_deref_mut(), inputs, (&self.hdr_view, &self.depth_view));
        if let Some(transparent) = &self.transparent {
            transparent.record(encoder, timer.as_deref_mut(), inputs, (&self.hdr_view, &self.depth_view));
        }
        self.tonemap.record(encoder, timer, self.targets.width, self.targets.height);
    }
}
