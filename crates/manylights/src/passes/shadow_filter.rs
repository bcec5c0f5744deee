//! The depth-aware spatial filter of soft sun shadows. See `shadow_filter.wgsl`.

use super::builder::ComputeStep;
use super::ray_shadows::MASK_FORMAT;
use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

pub struct ShadowFilter {
    step: ComputeStep,
    bind_group: wgpu::BindGroup,
}

/// The images the filter reads and writes: the frame's depth, the traced mask, the filtered one.
pub struct ShadowFilterImages<'a> {
    pub depth: &'a wgpu::TextureView,
    pub traced: &'a wgpu::TextureView,
    pub filtered: &'a wgpu::TextureView,
}

impl ShadowFilter {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, ShadowFilterImages { depth, traced, filtered }: ShadowFilterImages) -> Result<Self> {
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
        let shader = ShaderDesc::new("passes/shadow_filter.wgsl");
        let step = ComputeStep::new(device, &shader, "shadow_filter", &[&scene.bind_group_layout, &layout], &[])?;
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
        Ok(Self { step, bind_group })
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, scene: &GpuScene, (width, height): (u32, u32)) {
        self.step.record(encoder, timer, &[&scene.bind_group, &self.bind_group], super::dispatch_size(width, height));
    }
}
