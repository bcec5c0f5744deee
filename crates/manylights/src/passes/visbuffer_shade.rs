//! Visibility-buffer resolve and shading in compute. See `visbuffer_shade.wgsl`.

use super::FrameInputs;
use crate::accel::VolumeStructure;
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
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl VisbufferShade {
    /// The light and decal structures are bound as groups 2 and 3, whichever the methods; `shadows`
    /// are the sun's ray-traced shadows, if the frame has them.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        methods: ShadingMethods,
        (lights, decals): (&VolumeStructure, &VolumeStructure),
        shadows: Option<&RayShadows>,
        (visibility, depth, hdr): (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView),
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
        let layouts = [&scene.bind_group_layout, &layout, &lights.bind_group_layout, &decals.bind_group_layout];
        let (mask, has_mask) = ray_shadows::shading_mask_binding(device, shadows);
        let constants = [("SUN_SHADOW_MASK", has_mask), methods.debug_views_constant()];
        let pipeline = bindings::compute_pipeline_with_constants(device, "visbuffer_shade", &shader(methods), &layouts, &constants)?;
        let bind_group = bindings::bind_group(
            device,
            "visbuffer_shade",
            &layout,
            vec![
                wgpu::BindingResource::TextureView(visibility),
                wgpu::BindingResource::TextureView(hdr),
                wgpu::BindingResource::TextureView(depth),
                wgpu::BindingResource::TextureView(&mask),
            ],
        );
        Ok(Self { pipeline, bind_group })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        inputs: &FrameInputs,
        (width, height): (u32, u32),
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("visbuffer_shade"),
            timestamp_writes: timer.map(|t| t.compute_pass("visbuffer_shade")),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &inputs.scene.bind_group, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.set_bind_group(2, &inputs.lights.bind_group, &[]);
        pass.set_bind_group(3, &inputs.decals.bind_group, &[]);
        let (x, y) = super::dispatch_size(width, height);
        pass.dispatch_workgroups(x, y, 1);
    }
}
