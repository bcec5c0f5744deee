//! The deferred pipeline's geometry pass (`gbuffer_raster.wgsl`): surfaces and materials into the
//! G-buffer (`gbuffer.wgsl` lists its layout), depth tested and written, draws in the usual order.

use std::collections::HashMap;

use super::builder::{nearest_depth, Fragment, Raster};
use crate::gpu::scene::RasterState;
use crate::gpu::{bindings, shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

/// Keep in sync with `gbuffer.wgsl`: albedo, normal, roughness-metallic (the three deferred decals
/// blend into) and the rest of the material, packed.
pub const GBUFFER_FORMATS: [wgpu::TextureFormat; GBUFFER_TARGETS] =
    [wgpu::TextureFormat::Rgba8UnormSrgb, wgpu::TextureFormat::Rg16Float, wgpu::TextureFormat::Rg8Unorm, wgpu::TextureFormat::Rgba32Uint];

pub const GBUFFER_TARGETS: usize = 4;

pub struct GBufferRaster {
    pipelines: HashMap<RasterState, wgpu::RenderPipeline>,
}

impl GBufferRaster {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, methods: crate::plan::ShadingMethods) -> Result<Self> {
        let module = shaders::create_module(&ctx.device, &ShaderDesc::new("passes/gbuffer_raster.wgsl"))?;
        let layout = bindings::pipeline_layout(&ctx.device, "gbuffer_raster", &[&scene.bind_group_layout]);
        let targets = GBUFFER_FORMATS.map(|format| Some(wgpu::ColorTargetState::from(format)));
        let raster = Raster {
            label: "gbuffer_raster",
            layout: &layout,
            vertex_module: &module,
            vertex_entry: "forward_vertex",
            depth: nearest_depth(),
        };
        let constants = methods.material_constants();
        let pipelines = raster.per_state(&ctx.device, RasterState::all(), |state| {
            let entry = if state.alpha_mask { "gbuffer_masked" } else { "gbuffer_opaque" };
            Some(Fragment { module: &module, entry, constants: &constants, targets: &targets })
        });
        Ok(Self { pipelines })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        scene: &GpuScene,
        gbuffer: &[wgpu::TextureView; GBUFFER_TARGETS],
        depth: &wgpu::TextureView,
    ) {
        // Not cleared: the lighting pass reads the G-buffer only where depth says something was drawn.
        let attachments = gbuffer.each_ref().map(|view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gbuffer_raster"),
            color_attachments: &attachments,
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.map(|t| t.render_pass("gbuffer_raster")),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        super::draw_scene(&mut pass, scene, &self.pipelines);
    }
}
