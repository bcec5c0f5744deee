//! Visibility-buffer resolve and shading in compute. See `visbuffer_shade.wgsl`.

use crate::gpu::{shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::pipelines::LightMethod;
use crate::Result;

pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

pub struct VisbufferShade {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl VisbufferShade {
    /// Keep the layout in sync with group 1 of `visbuffer_shade.wgsl`.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        method: LightMethod,
        visibility: &wgpu::TextureView,
        hdr: &wgpu::TextureView,
    ) -> Result<Self> {
        let device = &ctx.device;
        let shader = ShaderDesc::new("passes/visbuffer_shade.wgsl").with("LIGHT_ENUMERATION", method.enumeration_module());
        let module = shaders::create_module(device, &shader)?;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("visbuffer_shade"),
            entries: &[
                // 0: visibility buffer
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Uint,
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                // 1: HDR output
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::StorageTexture {
                        access: wgpu::StorageTextureAccess::WriteOnly,
                        format: HDR_FORMAT,
                        view_dimension: wgpu::TextureViewDimension::D2,
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("visbuffer_shade"),
            bind_group_layouts: &[Some(&scene.bind_group_layout), Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("visbuffer_shade"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("visbuffer_shade"),
            compilation_options: Default::default(),
            cache: None,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("visbuffer_shade"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(visibility) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(hdr) },
            ],
        });
        Ok(Self { pipeline, bind_group })
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, scene: &GpuScene, width: u32, height: u32) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("visbuffer_shade"),
            timestamp_writes: timer.map(|t| t.compute_pass("visbuffer_shade")),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &scene.bind_group, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        let (x, y) = super::dispatch_size(width, height);
        pass.dispatch_workgroups(x, y, 1);
    }
}
