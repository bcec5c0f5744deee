//! Visibility-buffer raster: depth and a visibility id (draw and triangle) per pixel. See
//! `visbuffer_raster.wgsl`: indexed draws where the device has `primitive_index`, pulled vertices
//! otherwise.

use std::collections::HashMap;

use super::builder::{nearest_depth, Fragment, Raster};
use crate::gpu::scene::RasterState;
use crate::gpu::{bindings, shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

pub const VISIBILITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

pub struct VisbufferRaster {
    pipelines: HashMap<RasterState, wgpu::RenderPipeline>,
    indexed: bool,
}

/// The images the raster writes: the visibility ids and the depth.
pub struct VisbufferImages<'a> {
    pub visibility: &'a wgpu::TextureView,
    pub depth: &'a wgpu::TextureView,
}

impl VisbufferRaster {
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Result<Self> {
        // Indexed draws transform shared vertices once, a faster raster (benchmarks/LOG.md, topic 5).
        let indexed = ctx.features.contains(wgpu::Features::PRIMITIVE_INDEX);
        let entry = if indexed { "passes/visbuffer_raster_indexed.wgsl" } else { "passes/visbuffer_raster_pulled.wgsl" };
        let module = shaders::create_module(&ctx.device, &ShaderDesc::new(entry))?;
        let layout = bindings::pipeline_layout(&ctx.device, "visbuffer_raster", &[&scene.bind_group_layout]);
        let raster = Raster {
            label: "visbuffer_raster",
            layout: &layout,
            vertex_module: &module,
            vertex_entry: "visbuffer_vertex",
            depth: nearest_depth(),
        };
        let targets = [Some(VISIBILITY_FORMAT.into())];
        let pipelines = raster.per_state(&ctx.device, RasterState::all(), |state| {
            let entry = if state.alpha_mask { "visbuffer_masked" } else { "visbuffer_opaque" };
            Some(Fragment { module: &module, entry, constants: &[], targets: &targets })
        });
        Ok(Self { pipelines, indexed })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        scene: &GpuScene,
        VisbufferImages { visibility, depth }: VisbufferImages,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("visbuffer_raster"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: visibility,
                depth_slice: None,
                resolve_target: None,
                // Not cleared: shading reads ids only where depth says a triangle was drawn, and a
                // clear costs a sizeable share of this output-bound pass.
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.map(|t| t.render_pass("visbuffer_raster")),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        if self.indexed {
            super::draw_scene(&mut pass, scene, &self.pipelines);
            return;
        }
        // Pulled vertices: a call per draw, each vertex_index a corner of its range of the indices.
        pass.set_bind_group(0, &scene.bind_group, &[]);
        let draws = &scene.frame_draws.opaque;
        for &(state, first, count) in &draws.runs {
            pass.set_pipeline(&self.pipelines[&state]);
            for &c in &draws.commands[first as usize..(first + count) as usize] {
                let command = &scene.draw_commands[c as usize];
                pass.draw(0..command.index_count, command.draw_index..command.draw_index + 1);
            }
        }
    }
}
