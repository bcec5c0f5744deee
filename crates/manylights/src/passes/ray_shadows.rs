//! Ray-traced sun shadows from the depth buffer, before shading (`ray_shadows.wgsl`), and for soft
//! shadows their spatial filter (`shadow_filter.rs`). The shading passes read the resulting mask
//! (`shading/sun_shadow_mask.wgsl`); every pipeline records this after its depth is written.

use super::builder::ComputeStep;
use super::shadow_filter::{ShadowFilter, ShadowFilterImages};
use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::settings::SunShadows;
use crate::Result;

/// Per pixel, the fraction of the sun visible (0 to 1) and the mean distance to the blockers rays met.
pub const MASK_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Float;

pub struct RayShadows {
    step: ComputeStep,
    bind_group: wgpu::BindGroup,
    /// Soft shadows only: smooths `traced` into the mask the shading reads.
    filter: Option<ShadowFilter>,
    /// What shading reads: the filter's output, or the traced mask itself.
    mask_view: wgpu::TextureView,
}

impl RayShadows {
    /// The passes for `mode` (not `Off`) over `depth`, with their masks, tracing through `trace`
    /// (`ShadingMethods::ray_trace_module`).
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        mode: SunShadows,
        trace: &'static str,
        depth: &wgpu::TextureView,
        (width, height): (u32, u32),
    ) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = bindings::layout(
            device,
            "ray_shadows",
            &[
                bindings::texture(0, compute, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2), // depth
                bindings::storage_texture_write(1, compute, MASK_FORMAT),                                      // sun visibility
            ],
        );
        let shader = ShaderDesc::new("passes/ray_shadows.wgsl").with("RAY_TRACE", trace);
        let step = ComputeStep::new(device, &shader, "ray_shadows", &[&scene.bind_group_layout, &layout], &[])?;
        let traced = mask(device, "sun visibility (traced)", width, height);
        let traced_view = traced.create_view(&Default::default());
        let bind_group = bindings::bind_group(
            device,
            "ray_shadows",
            &layout,
            vec![wgpu::BindingResource::TextureView(depth), wgpu::BindingResource::TextureView(&traced_view)],
        );
        let (filter, mask_view) = match mode {
            SunShadows::Soft => {
                let filtered = mask(device, "sun visibility (filtered)", width, height);
                let filtered_view = filtered.create_view(&Default::default());
                (
                    Some(ShadowFilter::new(ctx, scene, ShadowFilterImages { depth, traced: &traced_view, filtered: &filtered_view })?),
                    filtered_view,
                )
            }
            _ => (None, traced_view),
        };
        Ok(Self { step, bind_group, filter, mask_view })
    }

    /// The mask the shading passes read.
    pub fn mask_view(&self) -> &wgpu::TextureView {
        &self.mask_view
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        scene: &GpuScene,
        (width, height): (u32, u32),
    ) {
        self.step.record(encoder, timer.as_deref_mut(), &[&scene.bind_group, &self.bind_group], super::dispatch_size(width, height));
        if let Some(filter) = &self.filter {
            filter.record(encoder, timer, scene, (width, height));
        }
    }
}

/// The shading passes' binding of the mask and the value of their `SUN_SHADOW_MASK` constant: the
/// shadow passes' mask, or — without sun shadows — a 1×1 stand-in the shader never reads.
pub fn shading_mask_binding(device: &wgpu::Device, shadows: Option<&RayShadows>) -> (wgpu::TextureView, f64) {
    match shadows {
        Some(shadows) => (shadows.mask_view().clone(), 1.0),
        None => (mask(device, "no sun shadows", 1, 1).create_view(&Default::default()), 0.0),
    }
}

/// The layout entry of the mask in a shading pass's group.
pub fn shading_mask_entry(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    bindings::texture(binding, visibility, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2)
}

fn mask(device: &wgpu::Device, label: &str, width: u32, height: u32) -> wgpu::Texture {
    crate::gpu::textures::target(
        device,
        label,
        width,
        height,
        MASK_FORMAT,
        wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
    )
}
