//! The depth-aware spatial filter of soft sun shadows. See `shadow_filter.wgsl`.

use super::ray_shadows::MASK_FORMAT;
use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

pub struct ShadowFilter {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl ShadowFilter {
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::TextureView,
        traced: &wgpu::TextureView,
        filtered: &wgpu::TextureView,
    ) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = bindings::layout(
            device,
            "shadow_filter",
            &[
                bindings::texture(0, compute, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2), // depth
                bindings::texture(1, compute, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2), // traced
                bindings::storage_texture_write(2, compute, MASK_FORMAT), // filtered
            ],
        );
        let pipeline = bindings::compute_pipeline(
            device,
            "shadow_filter",
            &ShaderDesc::new("passes/shadow_filter.wgsl"),
            &[&scene.bind_group_layout, &layout],
        )?;
        let bind_group = bindings::bind_group(
            device,
            "shadow_filter",
            &layout,
            vec![
                wgpu::BindingResource::TextureView(depth),
                wgpu::BindingResource::TextureView(traced),
                wgpu::BindingResource::TextureView(filtered),
            ],
        );
        Ok(Self { pipeline, bind_group })
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, scene: &GpuScene, (width, height): (u32, u32)) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("shadow_filter"),
            timestamp_writes: timer.map(|t| t.compute_pass("shadow_filter")),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &scene.bind_group, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        let (x, y) = super::dispatch_size(width, height);
        pass.dispatch_workgroups(x, y, 1);
    }
}
