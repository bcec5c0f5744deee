//! Transmissive surfaces that do not blend, in compute (`transmissive_shade.wgsl`): the
//! visibility-buffer raster over the transmissive draws (`VisbufferRaster::record_transmissive`)
//! leaves each pixel its nearest transmissive triangle in front of the opaque surfaces, writing its
//! depth, and a compute pass shades those pixels over the HDR image, seeing through to the opaque
//! image's mip chain (`transmission_background`). Every pipeline runs it after its opaque surfaces,
//! before the blended ones: a shading loop in fragments costs many times what it costs in compute.

use super::transmission_background::TransmissionBackground;
use super::visbuffer_raster::{VisbufferImages, VisbufferRaster, VISIBILITY_FORMAT};
use super::{builder::ComputeStep, visbuffer_shade::HDR_FORMAT, FrameInputs, Structures};
use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::plan::ShadingMethods;
use crate::Result;

/// The shader for a set of shading methods (transmission on: light behind the surfaces comes from
/// the background's mip chain).
pub fn shader(methods: ShadingMethods) -> ShaderDesc {
    super::shading_core_shader("passes/transmissive_shade.wgsl", methods, crate::plan::ShadingStage::Compute)
        .with("TRANSMITTED_LIGHT", "shading/transmitted_screen.wgsl")
}

pub struct TransmissiveShade {
    raster: VisbufferRaster,
    /// The nearest transmissive triangle's visibility id per pixel, or `NO_VISIBILITY_ID`.
    ids: wgpu::TextureView,
    step: ComputeStep,
    bind_group: wgpu::BindGroup,
    size: (u32, u32),
}

impl TransmissiveShade {
    /// The pass over `hdr`, the frame's shaded image, seeing through `background`; the light and
    /// decal structures are bound as groups 2 and 3.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        methods: ShadingMethods,
        structures: Structures,
        hdr: &wgpu::Texture,
        background: &TransmissionBackground,
    ) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let size = (hdr.width(), hdr.height());
        let ids = crate::gpu::textures::target(
            device,
            "transmissive ids",
            size.0,
            size.1,
            VISIBILITY_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        )
        .create_view(&Default::default());
        // Group 1 of `transmissive_shade.wgsl`; bindings 0 and 1 are `transmitted_screen.wgsl`'s.
        let layout = bindings::layout(
            device,
            "transmissive_shade",
            &[
                bindings::texture(0, compute, wgpu::TextureSampleType::Float { filterable: true }, wgpu::TextureViewDimension::D2),
                bindings::sampler(1, compute),
                bindings::texture(2, compute, wgpu::TextureSampleType::Uint, wgpu::TextureViewDimension::D2),
                bindings::storage_texture_write(3, compute, HDR_FORMAT),
            ],
        );
        let layouts = [&scene.bind_group_layout, &layout, &structures.lights.bind_group_layout, &structures.decals.bind_group_layout];
        let transmission = ShadingMethods { transmission: true, ..methods };
        let constants = [&[transmission.debug_views_constant(), ("TRANSMISSION", 1.0)][..], &transmission.material_constants()].concat();
        let step = ComputeStep::new(device, &shader(transmission), "transmissive_shade", &layouts, &constants)?;
        let hdr_view = hdr.create_view(&Default::default());
        let bind_group = bindings::bind_group(
            device,
            "transmissive_shade",
            &layout,
            vec![
                wgpu::BindingResource::TextureView(&background.view),
                wgpu::BindingResource::Sampler(&background.sampler),
                wgpu::BindingResource::TextureView(&ids),
                wgpu::BindingResource::TextureView(&hdr_view),
            ],
        );
        Ok(Self { raster: VisbufferRaster::new(ctx, scene)?, ids, step, bind_group, size })
    }

    /// Rasters the transmissive draws' ids over `depth` (writing theirs), then shades them.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        inputs: &FrameInputs,
        depth: &wgpu::TextureView,
    ) {
        let images = VisbufferImages { visibility: &self.ids, depth };
        self.raster.record_transmissive(encoder, timer.as_deref_mut(), inputs.scene, images);
        let groups = [&inputs.scene.bind_group, &self.bind_group, &inputs.lights.bind_group, &inputs.decals.bind_group];
        self.step.record(encoder, timer, &groups, super::dispatch_size(self.size.0, self.size.1));
    }
}
