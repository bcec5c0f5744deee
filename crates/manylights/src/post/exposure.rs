//! Auto exposure: `exposure_histogram` then `exposure_average`. See `exposure.wgsl`.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

const HISTOGRAM_BINS: u64 = 128;

pub struct AutoExposurePass {
    histogram_pipeline: wgpu::ComputePipeline,
    average_pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl AutoExposurePass {
    /// Measures `input` into `state` (`post::PostChain::exposure_state`), which the tonemap reads.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        uniforms: &wgpu::Buffer,
        input: &wgpu::TextureView,
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
            ],
        );
        let shader = ShaderDesc::new("post/exposure.wgsl");
        let layouts = [&scene.bind_group_layout, &layout];
        let histogram_pipeline = bindings::compute_pipeline(device, "exposure_histogram", &shader, &layouts)?;
        let average_pipeline = bindings::compute_pipeline(device, "exposure_average", &shader, &layouts)?;
        // Zeroed at creation; `exposure_average` clears it after reading.
        let histogram = device.create_buffer(&wgpu::BufferDescriptor {
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
                histogram.as_entire_binding(),
                state.as_entire_binding(),
            ],
        );
        Ok(Self { histogram_pipeline, average_pipeline, bind_group })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        scene: &GpuScene,
        (width, height): (u32, u32),
    ) {
        let pixels = crate::passes::dispatch_size(width, height);
        for (name, pipeline, (x, y)) in
            [("exposure_histogram", &self.histogram_pipeline, pixels), ("exposure_average", &self.average_pipeline, (1, 1))]
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(name),
                timestamp_writes: timer.as_deref_mut().map(|t| t.compute_pass(name)),
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &scene.bind_group, &[]);
            pass.set_bind_group(1, &self.bind_group, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}
