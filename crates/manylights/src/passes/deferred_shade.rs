//! Deferred lighting in compute (`deferred_shade.wgsl`): G-buffer and depth in, decals and lights
//! through the shading core, HDR radiance out.

use super::{builder::ComputeStep, FrameInputs, Structures};
use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::passes::ray_shadows::{self, RayShadows};
use crate::passes::visbuffer_shade::HDR_FORMAT;
use crate::plan::ShadingMethods;
use crate::Result;

/// The shader for a set of shading methods.
pub fn shader(methods: ShadingMethods) -> ShaderDesc {
    super::shading_core_shader("passes/deferred_shade.wgsl", methods, crate::plan::ShadingStage::Compute)
}

pub struct DeferredShade {
    step: ComputeStep,
    bind_group: wgpu::BindGroup,
}

/// The images the pass reads and writes: the depth and the G-buffer it lights, the HDR image.
pub struct DeferredShadeImages<'a> {
    pub depth: &'a wgpu::TextureView,
    pub gbuffer: &'a [wgpu::TextureView; super::gbuffer_raster::GBUFFER_TARGETS],
    pub hdr: &'a wgpu::TextureView,
}

impl DeferredShade {
    /// The light and decal structures are bound as groups 2 and 3, whichever the methods; `shadows`
    /// are the sun's ray-traced shadows, if the frame has them.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        methods: ShadingMethods,
        structures: Structures,
        shadows: Option<&RayShadows>,
        images: DeferredShadeImages,
    ) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let texture = |binding, sample_type| bindings::texture(binding, compute, sample_type, wgpu::TextureViewDimension::D2);
        let float = wgpu::TextureSampleType::Float { filterable: false };
        // Group 1 of `deferred_shade.wgsl`; group 0 is the scene.
        let layout = bindings::layout(
            device,
            "deferred_shade",
            &[
                texture(0, wgpu::TextureSampleType::Depth),
                texture(1, float),                         // albedo
                texture(2, float),                         // normal
                texture(3, float),                         // roughness, metallic
                texture(4, wgpu::TextureSampleType::Uint), // emission, specular, clear coat
                bindings::storage_texture_write(5, compute, HDR_FORMAT),
                ray_shadows::shading_mask_entry(6, compute), // sun visibility
            ],
        );
        let layouts = [&scene.bind_group_layout, &layout, &structures.lights.bind_group_layout, &structures.decals.bind_group_layout];
        let (mask, has_mask) = ray_shadows::shading_mask_binding(device, shadows);
        let constants = [
            &[("SUN_SHADOW_MASK", has_mask), methods.debug_views_constant(), methods.denoised_constant()][..],
            &methods.material_constants(),
        ]
        .concat();
        let step = ComputeStep::new(device, &shader(methods), "deferred_shade", &layouts, &constants)?;
        let mut views = vec![wgpu::BindingResource::TextureView(images.depth)];
        views.extend(images.gbuffer.iter().map(wgpu::BindingResource::TextureView));
        views.push(wgpu::BindingResource::TextureView(images.hdr));
        views.push(wgpu::BindingResource::TextureView(&mask));
        let bind_group = bindings::bind_group(device, "deferred_shade", &layout, views);
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
