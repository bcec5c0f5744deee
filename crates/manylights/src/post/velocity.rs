//! Per-pixel velocity for motion blur: `velocity` (compute, the camera's motion at every pixel) then
//! `velocity_raster` (the animated instances, from their previous transforms). See `velocity.wgsl`.

use std::collections::HashMap;

use crate::gpu::scene::RasterState;
use crate::gpu::{bindings, shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::passes::builder::{depth_test, ComputeStep, Fragment, Raster};
use crate::Result;

/// Pixels moved since the previous frame, x right and y down.
pub const VELOCITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

/// The frame's depth, which the velocities are reconstructed from, and the velocity image.
#[derive(Clone, Copy)]
pub struct VelocityImages<'a> {
    pub depth: &'a wgpu::TextureView,
    pub velocity: &'a wgpu::TextureView,
}

pub struct Velocity {
    camera_step: ComputeStep,
    camera_bind_group: wgpu::BindGroup,
    raster_pipelines: HashMap<RasterState, wgpu::RenderPipeline>,
    raster_bind_group: wgpu::BindGroup,
}

impl Velocity {
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        uniforms: &wgpu::Buffer,
        VelocityImages { depth, velocity }: VelocityImages,
    ) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = bindings::layout(
            device,
            "velocity",
            &[
                bindings::uniform(0, compute),
                bindings::texture(1, compute, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2),
                bindings::storage_texture_write(2, compute, VELOCITY_FORMAT),
            ],
        );
        let camera_step =
            ComputeStep::new(device, &ShaderDesc::new("post/velocity.wgsl"), "velocity", &[&scene.bind_group_layout, &layout], &[])?;
        let camera_bind_group = bindings::bind_group(
            device,
            "velocity",
            &layout,
            vec![uniforms.as_entire_binding(), wgpu::BindingResource::TextureView(depth), wgpu::BindingResource::TextureView(velocity)],
        );

        let vertex = wgpu::ShaderStages::VERTEX;
        let raster_layout = bindings::layout(
            device,
            "velocity_raster",
            &[bindings::uniform(0, vertex), bindings::storage_read(1, vertex), bindings::storage_read(2, vertex)],
        );
        let raster_bind_group = bindings::bind_group(
            device,
            "velocity_raster",
            &raster_layout,
            vec![uniforms.as_entire_binding(), scene.previous_transforms.as_entire_binding(), scene.previous_positions.as_entire_binding()],
        );
        let module = shaders::create_module(device, &ShaderDesc::new("post/velocity_raster.wgsl"))?;
        let pipeline_layout = bindings::pipeline_layout(device, "velocity_raster", &[&scene.bind_group_layout, &raster_layout]);
        // The surface depth holds, drawn again by another vertex shader: equal to rounding, so pulled
        // a few units nearer (reverse Z: greater) and tested GREATER_EQUAL, without writing.
        let depth = wgpu::DepthStencilState {
            bias: wgpu::DepthBiasState { constant: 8, slope_scale: 1.0, clamp: 0.0 },
            ..depth_test(false, wgpu::CompareFunction::GreaterEqual)
        };
        let raster =
            Raster { label: "velocity_raster", layout: &pipeline_layout, vertex_module: &module, vertex_entry: "velocity_vertex", depth };
        let targets = [Some(VELOCITY_FORMAT.into())];
        let raster_pipelines = raster.per_state(device, RasterState::all(), |state| {
            let entry = if state.alpha_mask { "velocity_raster_masked" } else { "velocity_raster" };
            Some(Fragment { module: &module, entry, constants: &[], targets: &targets })
        });
        Ok(Self { camera_step, camera_bind_group, raster_pipelines, raster_bind_group })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        scene: &GpuScene,
        VelocityImages { depth, velocity }: VelocityImages,
        (width, height): (u32, u32),
    ) {
        let groups = [&scene.bind_group, &self.camera_bind_group];
        self.camera_step.record(encoder, timer.as_deref_mut(), &groups, crate::passes::dispatch_size(width, height));
        let moving = &scene.frame_draws.moving;
        if moving.commands.is_empty() {
            return;
        }
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("velocity_raster"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: velocity,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                depth_slice: None,
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.map(|t| t.render_pass("velocity_raster")),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(1, &self.raster_bind_group, &[]);
        crate::passes::draw_ordered(&mut pass, scene, moving, &scene.draw_commands, &self.raster_pipelines);
    }
}
