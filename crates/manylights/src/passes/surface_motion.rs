//! Surface motion (`surface_motion.wgsl`): where animated instances' surfaces were a frame before, per
//! pixel, for the reuse of what pixels kept — `restir`'s reservoirs and the denoiser's history follow
//! a moving surface rather than start afresh on it.
//!
//! Shader: `surface_motion.wgsl`. Inputs: the scene (group 0), the draws' previous transforms and the
//! frame's depth, read-only as attachment and texture (group 1). Output: `GpuScene`'s surface motions
//! (group 0), one record per pixel covered by a moving surface, stamped with the frame. Dispatch: the
//! animated instances' opaque draws, front to back; nothing when none moves.

use std::collections::HashMap;

use super::builder::{depth_test, Fragment, Raster};
use crate::gpu::scene::RasterState;
use crate::gpu::{bindings, shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

pub struct SurfaceMotion {
    pipelines: HashMap<RasterState, wgpu::RenderPipeline>,
    bind_group: wgpu::BindGroup,
}

impl SurfaceMotion {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, depth: &wgpu::TextureView) -> Result<Self> {
        let device = &ctx.device;
        let layout = bindings::layout(
            device,
            "surface_motion",
            &[
                bindings::storage_read(0, wgpu::ShaderStages::VERTEX),
                bindings::texture(1, wgpu::ShaderStages::FRAGMENT, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2),
                bindings::storage_read(2, wgpu::ShaderStages::VERTEX),
            ],
        );
        let bind_group = bindings::bind_group(
            device,
            "surface_motion",
            &layout,
            vec![
                scene.previous_transforms.as_entire_binding(),
                wgpu::BindingResource::TextureView(depth),
                scene.previous_positions.as_entire_binding(),
            ],
        );
        let module = shaders::create_module(device, &ShaderDesc::new("passes/surface_motion.wgsl"))?;
        let pipeline_layout = bindings::pipeline_layout(device, "surface_motion", &[&scene.bind_group_layout, &layout]);
        // The surface depth holds, drawn again by another vertex shader: equal to rounding, so pulled
        // a few units nearer (reverse Z: greater) and tested GREATER_EQUAL, without writing.
        let depth = wgpu::DepthStencilState {
            bias: wgpu::DepthBiasState { constant: 8, slope_scale: 1.0, clamp: 0.0 },
            ..depth_test(false, wgpu::CompareFunction::GreaterEqual)
        };
        let raster = Raster {
            label: "surface_motion",
            layout: &pipeline_layout,
            vertex_module: &module,
            vertex_entry: "surface_motion_vertex",
            depth,
        };
        let pipelines = raster.per_state(device, RasterState::all(), |state| {
            let entry = if state.alpha_mask { "surface_motion_masked" } else { "surface_motion" };
            Some(Fragment { module: &module, entry, constants: &[], targets: &[] })
        });
        Ok(Self { pipelines, bind_group })
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, scene: &GpuScene, depth: &wgpu::TextureView) {
        let moving = &scene.frame_draws.moving;
        if moving.commands.is_empty() {
            return;
        }
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("surface_motion"),
            color_attachments: &[],
            // Read-only: the same depth is read as a texture.
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment { view: depth, depth_ops: None, stencil_ops: None }),
            timestamp_writes: timer.map(|t| t.render_pass("surface_motion")),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(1, &self.bind_group, &[]);
        super::draw_ordered(&mut pass, scene, moving, &scene.draw_commands, &self.pipelines);
    }
}
