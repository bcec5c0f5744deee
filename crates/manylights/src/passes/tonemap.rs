//! Exposure, tonemapping and sRGB encoding into the 8-bit output. See `tonemap.wgsl`.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

/// Storage textures cannot be sRGB, so the shader encodes sRGB itself into a plain RGBA8 texture.
pub const LDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

pub struct Tonemap {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl Tonemap {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, hdr: &wgpu::TextureView, ldr: &wgpu::TextureView) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        // Keep in sync with `tonemap.wgsl`.
        let layout = bindings::layout(
            device,
            "tonemap",
            &[
                bindings::uniform(0, compute), // frame uniforms (exposure, tonemapper, viewport)
                bindings::texture(1, compute, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2), // HDR input
                bindings::storage_texture_write(2, compute, LDR_FORMAT), // LDR output
            ],
        );
        let pipeline = bindings::compute_pipeline(device, "tonemap", &ShaderDesc::new("passes/tonemap.wgsl"), &[&layout])?;
        let bind_group = bindings::bind_group(
            device,
            "tonemap",
            &layout,
            vec![
                scene.frame_uniforms.as_entire_binding(),
                wgpu::BindingResource::TextureView(hdr),
                wgpu::BindingResource::TextureView(ldr),
            ],
        );
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
