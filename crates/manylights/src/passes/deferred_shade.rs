//! Deferred lighting in compute (`deferred_shade.wgsl`): G-buffer and depth in, decals and lights
//! through the shading core, HDR radiance out.

use super::FrameInputs;
use crate::accel::VolumeStructure;
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
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl DeferredShade {
    /// The light and decal structures are bound as groups 2 and 3, whichever the methods; `shadows`
    /// are the sun's ray-traced shadows, if the frame has them.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        methods: ShadingMethods,
        (lights, decals): (&VolumeStructure, &VolumeStructure),
        shadows: Option<&RayShadows>,
        (depth, gbuffer): (&wgpu::TextureView, &[wgpu::TextureView; 4]),
        hdr: &wgpu::TextureView,
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
                texture(1, float), // albedo
                texture(2, float), // normal
                texture(3, float), // roughness, metallic
                texture(4, float), // emission
                bindings::storage_texture_write(5, compute, HDR_FORMAT),
                ray_shadows::shading_mask_entry(6, compute), // sun visibility
            ],
        );
        let layouts = [&scene.bind_group_layout, &layout, &lights.bind_group_layout, &decals.bind_group_layout];
        let (mask, has_mask) = ray_shadows::shading_mask_binding(device, shadows);
        let constants = [("SUN_SHADOW_MASK", has_mask), methods.debug_views_constant()];
        let pipeline = bindings::compute_pipeline_with_constants(device, "deferred_shade", &shader(methods), &layouts, &constants)?;
        let mut views = vec![wgpu::BindingResource::TextureView(depth)];
        views.extend(gbuffer.iter().map(wgpu::BindingResource::TextureView));
        views.push(wgpu::BindingResource::TextureView(hdr));
        views.push(wgpu::BindingResource::TextureView(&mask));
        let bind_group = bindings::bind_group(device, "deferred_shade", &layout, views);
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
            label: Some("deferred_shade"),
            timestamp_writes: timer.map(|t| t.compute_pass("deferred_shade")),
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
