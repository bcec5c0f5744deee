//! The forward pipeline's depth prepass (`depth_prepass.wgsl`): depth only, indexed draws in the
//! visibility raster's order, so that `forward_shade` shades each pixel once.

use std::collections::HashMap;

use super::builder::{nearest_depth, Fragment, Raster};
use crate::gpu::scene::RasterState;
use crate::gpu::{bindings, shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

pub struct DepthPrepass {
    pipelines: HashMap<RasterState, wgpu::RenderPipeline>,
}

impl DepthPrepass {
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Result<Self> {
        let module = shaders::create_module(&ctx.device, &ShaderDesc::new("passes/depth_prepass.wgsl"))?;
        let layout = bindings::pipeline_layout(&ctx.device, "depth_prepass", &[&scene.bind_group_layout]);
        let raster = Raster {
            label: "depth_prepass",
            layout: &layout,
            vertex_module: &module,
            vertex_entry: "forward_vertex",
            depth: nearest_depth(),
        };
        // Opaque draws write depth without a fragment stage.
        let masked = Fragment { module: &module, entry: "depth_prepass_masked", constants: &[], targets: &[] };
        let pipelines = raster.per_state(&ctx.device, RasterState::all(), |state| state.alpha_mask.then_some(masked));
        Ok(Self { pipelines })
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, scene: &GpuScene, depth: &wgpu::TextureView) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("depth_prepass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.map(|t| t.render_pass("depth_prepass")),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        super::draw_scene(&mut pass, scene, &self.pipelines);
    }
}
