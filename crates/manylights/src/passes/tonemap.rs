//! Exposure, tonemapping and sRGB encoding into the 8-bit output. See `tonemap.wgsl`.

use crate::gpu::{shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

/// Storage textures cannot be sRGB, so the shader encodes sRGB itself into a plain RGBA8 texture.
pub const LDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

pub struct Tonemap {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl Tonemap {
    /// Keep the layout in sync with `tonemap.wgsl`.
    pub fn new(ctx: &GpuContext, scene: &GpuScene, hdr: &wgpu::TextureView, ldr: &wgpu::TextureView) -> Result<Self> {
        let device = &ctx.device;
        let module = shaders::create_module(device, &ShaderDesc::new("passes/tonemap.wgsl"))?;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tonemap"),
            entries: &[
                // 0: frame uniforms (exposure, tonemapper, viewport)
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: compute,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                // 1: HDR input
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: compute,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                // 2: LDR output
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: compute,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: LDR_FORMAT,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("tonemap"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("tonemap"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("tonemap"),
            compilation_options: Default::default(),
            cache: None,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tonemap"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: scene.frame_uniforms.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(hdr) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(ldr) },
            ],
        });
        Ok(Self { pipeline, bind_group })
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, width: u32, height: u32) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("tonemap"),
            timestamp_writes: timer.map(|t| t.compute_pass("tonemap")),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        let (x, y) = super::dispatch_size(width, height);
        pass.dispatch_workgroups(x, y, 1);
    }
}
