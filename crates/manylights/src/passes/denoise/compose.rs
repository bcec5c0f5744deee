//! Adds the denoised light to the HDR image: one triangle over it, blended additively (the HDR image
//! is f32, written by compute or fragments before, so it is blended into rather than read).
//! See `compose.wgsl`.

use crate::gpu::{bindings, shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::passes::visbuffer_shade::HDR_FORMAT;
use crate::Result;

pub struct Compose {
    pipeline: wgpu::RenderPipeline,
    bind_group: wgpu::BindGroup,
}

impl Compose {
    /// Reads `denoised`, the filters' result, and the scene's samples' albedos.
    pub fn new(ctx: &GpuContext, scene: &GpuScene, denoised: &wgpu::Buffer) -> Result<Self> {
        let device = &ctx.device;
        let layout = bindings::layout(device, "denoise_compose", &[bindings::storage_read(0, wgpu::ShaderStages::FRAGMENT)]);
        let shader = ShaderDesc::new("passes/denoise/compose.wgsl");
        let module = shaders::create_module(device, &shader)?;
        let add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        // The HDR image's alpha stays 1.
        let keep = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Zero,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("denoise_compose"),
            layout: Some(&bindings::pipeline_layout(device, "denoise_compose", &[&scene.bind_group_layout, &layout])),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("denoise_compose_vertex"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("denoise_compose"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: HDR_FORMAT,
                    blend: Some(wgpu::BlendState { color: add, alpha: keep }),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let bind_group = bindings::bind_group(device, "denoise_compose", &layout, vec![denoised.as_entire_binding()]);
        Ok(Self { pipeline, bind_group })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        scene: &wgpu::BindGroup,
        hdr: &wgpu::TextureView,
    ) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("denoise_compose"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: hdr,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: timer.map(|t| t.render_pass("denoise_compose")),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, scene, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}
