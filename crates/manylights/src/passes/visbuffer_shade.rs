//! Visibility-buffer resolve and shading in compute. See `visbuffer_shade.wgsl`.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::pipelines::LightMethod;
use crate::Result;

pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

pub struct VisbufferShade {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl VisbufferShade {
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        method: LightMethod,
        visibility: &wgpu::TextureView,
        hdr: &wgpu::TextureView,
    ) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        // Group 1 of `visbuffer_shade.wgsl`; group 0 is the scene.
        let layout = bindings::layout(
            device,
            "visbuffer_shade",
            &[
                bindings::texture(0, compute, wgpu::TextureSampleType::Uint, wgpu::TextureViewDimension::D2), // visibility ids
                bindings::storage_texture_write(1, compute, HDR_FORMAT),                                      // HDR output
            ],
        );
        let shader = ShaderDesc::new("passes/visbuffer_shade.wgsl").with("LIGHT_ENUMERATION", method.enumeration_module());
        let pipeline = bindings::compute_pipeline(device, "visbuffer_shade", &shader, &[&scene.bind_group_layout, &layout])?;
        let bind_group = bindings::bind_group(
            device,
            "visbuffer_shade",
            &layout,
            vec![wgpu::BindingResource::TextureView(visibility), wgpu::BindingResource::TextureView(hdr)],
        );
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
