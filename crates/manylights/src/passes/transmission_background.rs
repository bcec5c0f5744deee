//! The image of the opaque surfaces that transmissive surfaces see through
//! (`transmission_background.wgsl`): the shaded HDR image copied into a half-float mip chain, each
//! level the 2×2 mean of the one above, which the transmissive and transparent passes sample where
//! refracted rays leave (`shading/transmitted_screen.wgsl`).

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuTimer};
use crate::Result;

/// Filterable, and as bright as a shaded image gets (clamped at the largest half float).
pub const BACKGROUND_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

pub struct TransmissionBackground {
    copy: wgpu::ComputePipeline,
    downsample: wgpu::ComputePipeline,
    /// One a level, from the HDR image into level 0 on.
    steps: Vec<(wgpu::BindGroup, (u32, u32))>,
    /// Every level, for the transmissive and transparent passes to sample, and their sampler:
    /// trilinear, so rough surfaces blend between the chain's levels.
    pub view: wgpu::TextureView,
    pub sampler: wgpu::Sampler,
}

impl TransmissionBackground {
    /// The chain for `hdr`, the frame's shaded image, down to a single texel.
    pub fn new(ctx: &GpuContext, hdr: &wgpu::Texture) -> Result<Self> {
        let device = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        // Keep in sync with `transmission_background.wgsl`.
        let layout = bindings::layout(
            device,
            "transmission_background",
            &[
                bindings::texture(0, c, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2),
                bindings::storage_texture_write(1, c, BACKGROUND_FORMAT),
            ],
        );
        let shader = ShaderDesc::new("passes/transmission_background.wgsl");
        let copy = bindings::compute_pipeline(device, "transmission_background_copy", &shader, &[&layout])?;
        let downsample = bindings::compute_pipeline(device, "transmission_background_downsample", &shader, &[&layout])?;
        let (width, height) = (hdr.width(), hdr.height());
        let levels = u32::BITS - width.max(height).leading_zeros();
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("transmission background"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: BACKGROUND_FORMAT,
            usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let level_view = |level: u32| {
            texture.create_view(&wgpu::TextureViewDescriptor { base_mip_level: level, mip_level_count: Some(1), ..Default::default() })
        };
        let level_views: Vec<_> = (0..levels).map(level_view).collect();
        let hdr_view = hdr.create_view(&Default::default());
        let steps = (0..levels)
            .map(|level| {
                let source = if level == 0 { &hdr_view } else { &level_views[level as usize - 1] };
                let bind_group = bindings::bind_group(
                    device,
                    "transmission_background",
                    &layout,
                    vec![wgpu::BindingResource::TextureView(source), wgpu::BindingResource::TextureView(&level_views[level as usize])],
                );
                (bind_group, ((width >> level).max(1), (height >> level).max(1)))
            })
            .collect();
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("transmission background"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        Ok(Self { copy, downsample, steps, view: texture.create_view(&Default::default()), sampler })
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        // One pass: wgpu orders each dispatch's reads after the previous dispatches' writes.
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("transmission_background"),
            timestamp_writes: timer.map(|t| t.compute_pass("transmission_background")),
        });
        for (level, (bind_group, (width, height))) in self.steps.iter().enumerate() {
            pass.set_pipeline(if level == 0 { &self.copy } else { &self.downsample });
            pass.set_bind_group(0, bind_group, &[]);
            let (x, y) = super::dispatch_size(*width, *height);
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}
