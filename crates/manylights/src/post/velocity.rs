//! Per-pixel velocity for motion blur: `velocity` (compute, the camera's motion at every pixel) then
//! `velocity_raster` (the animated instances, from their previous transforms). See `velocity.wgsl`.

use std::collections::HashMap;

use crate::gpu::scene::RasterState;
use crate::gpu::{bindings, shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::passes::visbuffer_raster::DEPTH_FORMAT;
use crate::Result;

/// Pixels moved since the previous frame, x right and y down.
pub const VELOCITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

pub struct Velocity {
    camera_pipeline: wgpu::ComputePipeline,
    camera_bind_group: wgpu::BindGroup,
    raster_pipelines: HashMap<RasterState, wgpu::RenderPipeline>,
    raster_bind_group: wgpu::BindGroup,
}

impl Velocity {
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        uniforms: &wgpu::Buffer,
        depth: &wgpu::TextureView,
        velocity: &wgpu::TextureView,
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
        let camera_pipeline =
            bindings::compute_pipeline(device, "velocity", &ShaderDesc::new("post/velocity.wgsl"), &[&scene.bind_group_layout, &layout])?;
        let camera_bind_group = bindings::bind_group(
            device,
            "velocity",
            &layout,
            vec![uniforms.as_entire_binding(), wgpu::BindingResource::TextureView(depth), wgpu::BindingResource::TextureView(velocity)],
        );

        let vertex = wgpu::ShaderStages::VERTEX;
        let raster_layout = bindings::layout(device, "velocity_raster", &[bindings::uniform(0, vertex), bindings::storage_read(1, vertex)]);
        let raster_bind_group = bindings::bind_group(
            device,
            "velocity_raster",
            &raster_layout,
            vec![uniforms.as_entire_binding(), scene.previous_transforms.as_entire_binding()],
        );
        let module = shaders::create_module(device, &ShaderDesc::new("post/velocity_raster.wgsl"))?;
        let pipeline_layout = bindings::pipeline_layout(device, "velocity_raster", &[&scene.bind_group_layout, &raster_layout]);
        let raster_pipelines = RasterState::all()
            .map(|state| {
                let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some("velocity_raster"),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some("velocity_vertex"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: state.primitive(),
                    // The surface depth holds, drawn again by another vertex shader: equal to rounding,
                    // so pulled a few units nearer (reverse Z: greater) and tested GREATER_EQUAL,
                    // without writing.
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH_FORMAT,
                        depth_write_enabled: Some(false),
                        depth_compare: Some(wgpu::CompareFunction::GreaterEqual),
                        stencil: Default::default(),
                        bias: wgpu::DepthBiasState { constant: 8, slope_scale: 1.0, clamp: 0.0 },
                    }),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some(if state.alpha_mask { "velocity_raster_masked" } else { "velocity_raster" }),
                        compilation_options: Default::default(),
                        targets: &[Some(VELOCITY_FORMAT.into())],
                    }),
                    multiview_mask: None,
                    cache: None,
                });
                (state, pipeline)
            })
            .collect();
        Ok(Self { camera_pipeline, camera_bind_group, raster_pipelines, raster_bind_group })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        scene: &GpuScene,
        eye: glam::Vec3,
        (depth, velocity): (&wgpu::TextureView, &wgpu::TextureView),
        (width, height): (u32, u32),
    ) {
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("velocity"),
                timestamp_writes: timer.as_deref_mut().map(|t| t.compute_pass("velocity")),
            });
            pass.set_pipeline(&self.camera_pipeline);
            pass.set_bind_group(0, &scene.bind_group, &[]);
            pass.set_bind_group(1, &self.camera_bind_group, &[]);
            let (x, y) = crate::passes::dispatch_size(width, height);
            pass.dispatch_workgroups(x, y, 1);
        }
        let moving = scene.moving_draw_order(eye);
        if moving.is_empty() {
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
        crate::passes::draw_commands(&mut pass, scene, &moving, &self.raster_pipelines);
    }
}
