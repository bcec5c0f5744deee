//! The post chain's last pass (`tonemap.wgsl`): exposure, bloom's blend, vignetting, tonemapping and
//! sRGB encoding into the 8-bit output.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::passes::builder::ComputeStep;
use crate::Result;

/// Storage textures cannot be sRGB, so the shader encodes sRGB itself into a plain RGBA8 texture.
pub const LDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

pub struct Tonemap {
    step: ComputeStep,
    bind_group: wgpu::BindGroup,
}

/// What the tonemap reads besides the image: the top bloom level when bloom is on, and the measured
/// exposure, used with auto exposure.
pub struct TonemapInputs<'a> {
    pub color: &'a wgpu::TextureView,
    pub bloom: Option<&'a wgpu::TextureView>,
    pub exposure_state: &'a wgpu::Buffer,
    pub auto_exposure: bool,
    pub ldr: &'a wgpu::TextureView,
}

impl Tonemap {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, uniforms: &wgpu::Buffer, inputs: TonemapInputs) -> Result<Self> {
        let device = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        let unfilterable = wgpu::TextureSampleType::Float { filterable: false };
        let d2 = wgpu::TextureViewDimension::D2;
        // Keep in sync with `tonemap.wgsl`.
        let layout = bindings::layout(
            device,
            "tonemap",
            &[
                bindings::uniform(0, c),
                bindings::texture(1, c, unfilterable, d2),
                bindings::texture(2, c, unfilterable, d2),
                bindings::storage_read(3, c),
                bindings::storage_texture_write(4, c, LDR_FORMAT),
            ],
        );
        let flag = |on: bool| f64::from(u8::from(on));
        let constants = [("BLOOM", flag(inputs.bloom.is_some())), ("AUTO_EXPOSURE", flag(inputs.auto_exposure))];
        let step =
            ComputeStep::new(device, &ShaderDesc::new("post/tonemap.wgsl"), "tonemap", &[&scene.bind_group_layout, &layout], &constants)?;
        // Without bloom the shader does not read its binding: the image stands in.
        let bind_group = bindings::bind_group(
            device,
            "tonemap",
            &layout,
            vec![
                uniforms.as_entire_binding(),
                wgpu::BindingResource::TextureView(inputs.color),
                wgpu::BindingResource::TextureView(inputs.bloom.unwrap_or(inputs.color)),
                inputs.exposure_state.as_entire_binding(),
                wgpu::BindingResource::TextureView(inputs.ldr),
            ],
        );
        Ok(Self { step, bind_group })
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, scene: &GpuScene, (width, height): (u32, u32)) {
        self.step.record(encoder, timer, &[&scene.bind_group, &self.bind_group], crate::passes::dispatch_size(width, height));
    }
}
