//! Adds the denoised light to the HDR image, in compute. The image is copied first and read from the
//! copy: a pass cannot read and write one f32 image portably. See `compose.wgsl`.

use crate::gpu::{bindings, shaders::ShaderDesc, textures::target, GpuContext, GpuScene, GpuTimer};
use crate::passes::{builder::ComputeStep, visbuffer_shade::HDR_FORMAT};
use crate::Result;

pub struct Compose {
    step: ComputeStep,
    bind_group: wgpu::BindGroup,
    /// The HDR image as shading left it.
    shaded: wgpu::Texture,
}

impl Compose {
    /// Reads `denoised`, the filters' result, the scene's samples' albedos and a copy of `hdr`;
    /// writes `hdr`.
    pub fn new(ctx: &GpuContext, scene: &GpuScene, denoised: &wgpu::Buffer, hdr: &wgpu::Texture) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = bindings::layout(
            device,
            "denoise_compose",
            &[
                bindings::storage_read(0, compute), // denoised light
                bindings::texture(1, compute, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2), // shaded
                bindings::storage_texture_write(2, compute, HDR_FORMAT), // HDR output
            ],
        );
        let shader = ShaderDesc::new("passes/denoise/compose.wgsl");
        let step = ComputeStep::new(device, &shader, "denoise_compose", &[&scene.bind_group_layout, &layout], &[])?;
        let usage = wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING;
        let shaded = target(device, "shaded hdr", hdr.width(), hdr.height(), HDR_FORMAT, usage);
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let bind_group = bindings::bind_group(
            device,
            "denoise_compose",
            &layout,
            vec![
                denoised.as_entire_binding(),
                wgpu::BindingResource::TextureView(&view(&shaded)),
                wgpu::BindingResource::TextureView(&view(hdr)),
            ],
        );
        Ok(Self { step, bind_group, shaded })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        scene: &wgpu::BindGroup,
        hdr: &wgpu::Texture,
        workgroups: (u32, u32),
    ) {
        encoder.copy_texture_to_texture(hdr.as_image_copy(), self.shaded.as_image_copy(), hdr.size());
        self.step.record(encoder, timer, &[scene, &self.bind_group], workgroups);
    }
}
