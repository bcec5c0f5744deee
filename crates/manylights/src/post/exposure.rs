//! Auto exposure: `exposure_histogram` then `exposure_average`. See `exposure.wgsl`.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::passes::builder::ComputeStep;
use crate::Result;

/// Surfaces' bins, then the background's (`exposure.wgsl`).
const HISTOGRAM_BINS: u64 = 2 * 128;
/// `exposure_histogram`'s workgroup: 16 × 16 pixels, a lane per bin.
const HISTOGRAM_TILE: u32 = 16;

pub struct AutoExposurePass {
    histogram: ComputeStep,
    average: ComputeStep,
    bind_group: wgpu::BindGroup,
}

impl AutoExposurePass {
    /// Measures `input` into `state` (`post::PostChain::exposure_state`), which the tonemap reads;
    /// `depth` tells surfaces from the background.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        uniforms: &wgpu::Buffer,
        input: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        state: &wgpu::Buffer,
    ) -> Result<Self> {
        let device = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        // Keep in sync with `exposure.wgsl`.
        let layout = bindings::layout(
            device,
            "exposure",
            &[
                bindings::uniform(0, c),
                bindings::texture(1, c, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2),
                bindings::storage_read_write(2, c),
                bindings::storage_read_write(3, c),
                bindings::texture(4, c, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2),
            ],
        );
        let shader = ShaderDesc::new("post/exposure.wgsl");
        let layouts = [&scene.bind_group_layout, &layout];
        let histogram = ComputeStep::new(device, &shader, "exposure_histogram", &layouts, &[])?;
        let average = ComputeStep::new(device, &shader, "exposure_average", &layouts, &[])?;
        // Zeroed at creation; `exposure_average` clears it after reading.
        let histogram_bins = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("exposure histogram"),
            size: HISTOGRAM_BINS * 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let bind_group = bindings::bind_group(
            device,
            "exposure",
            &layout,
            vec![
                uniforms.as_entire_binding(),
                wgpu::BindingResource::TextureView(input),
                histogram_bins.as_entire_binding(),
                state.as_entire_binding(),
                wgpu::BindingResource::TextureView(depth),
            ],
        );
        Ok(Self { histogram, average, bind_group })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        scene: &GpuScene,
        (width, height): (u32, u32),
    ) {
        let groups = [&scene.bind_group, &self.bind_group];
        self.histogram.record(encoder, timer.as_deref_mut(), &groups, (width.div_ceil(HISTOGRAM_TILE), height.div_ceil(HISTOGRAM_TILE)));
        self.average.record(encoder, timer, &groups, (1, 1));
    }
}
