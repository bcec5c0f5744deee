//! Visibility-buffer resolve and shading in compute. See `visbuffer_shade.wgsl`.

use super::{builder::ComputeStep, FrameInputs, Structures};
use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::passes::ray_shadows::{self, RayShadows};
use crate::plan::ShadingMethods;
use crate::Result;

/// f32 rather than f16: methods are compared in linear HDR to 1e-3, finer than f16 steps above 1.
pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The shader for a set of shading methods.
pub fn shader(methods: ShadingMethods) -> ShaderDesc {
    super::shading_core_shader("passes/visbuffer_shade.wgsl", methods, crate::plan::ShadingStage::Compute)
}

pub struct VisbufferShade {
    step: ComputeStep,
    bind_group: wgpu::BindGroup,
}

/// The images the pass reads and writes.
pub struct VisbufferShadeImages<'a> {
    pub visibility: &'a wgpu::TextureView,
    pub depth: &'a wgpu::TextureView,
    pub hdr: &'a wgpu::TextureView,
}

impl VisbufferShade {
    /// The light and decal structures are bound as groups 2 and 3, whichever the methods; `shadows`
    /// are the sun's ray-traced shadows, if the frame has them.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        methods: ShadingMethods,
        structures: Structures,
        shadows: Option<&RayShadows>,
        images: VisbufferShadeImages,
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
                bindings::texture(2, compute, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2), // depth
                ray_shadows::shading_mask_entry(3, compute),                                                  // sun visibility
            ],
        );
        let layouts = [&scene.bind_group_layout, &layout, &structures.lights.bind_group_layout, &structures.decals.bind_group_layout];
        let (mask, has_mask) = ray_shadows::shading_mask_binding(device, shadows);
        let constants = [
            &[("SUN_SHADOW_MASK", has_mask), methods.debug_views_constant(), methods.denoised_constant()][..],
            &methods.material_constants(),
        ]
        .concat();
        let step = ComputeStep::new(device, &shader(methods), "visbuffer_shade", &layouts, &constants)?;
        let bind_group = bindings::bind_group(
            device,
            "visbuffer_shade",
            &layout,
            vec![
                wgpu::BindingResource::TextureView(images.visibility),
                wgpu::BindingResource::TextureView(images.hdr),
                wgpu::BindingResource::TextureView(images.depth),
                wgpu::BindingResource::TextureView(&mask),
            ],
        );
        Ok(Self { step, bind_group })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        inputs: &FrameInputs,
        (width, height): (u32, u32),
    ) {
        let groups = [&inputs.scene.bind_group, &self.bind_group, &inputs.lights.bind_group, &inputs.decals.bind_group];
        self.step.record(encoder, timer, &groups, super::dispatch_size(width, height));
    }
}
