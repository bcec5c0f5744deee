//! The forward pipeline's depth prepass (`depth_prepass.wgsl`): depth only, indexed draws in the
//! visibility raster's order, so that `forward_shade` shades each pixel once.

use std::collections::HashMap;

use super::visbuffer_raster::DEPTH_FORMAT;
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
        let pipelines = RasterState::all()
            .map(|state| {
                let pipeline = ctx.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("depth_prepass"),
                    layout: Some(&layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("forward_vertex"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: state.primitive(),
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(true),
                        // Reverse Z: nearer is greater.
                        depth_compare: Some(wgpu::CompareFunction::Greater),
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    // Opaque draws write depth without a fragment stage.
                    fragment: state.alpha_mask.then(|| wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("depth_prepass_masked"),
                        compilation_options: Default::default(),
                        targets: &[],
                    }),
                    multiview_mask: None,
                    cache: None,
                });
                (state, pipeline)
            })
            .collect();
        Ok(Self { pipelines })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        scene: &GpuScene,
        eye: glam::Vec3,
        depth: &wgpu::TextureView,
    ) {
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
        super::draw_scene(&mut pass, scene, eye, &self.pipelines);
    }
}
