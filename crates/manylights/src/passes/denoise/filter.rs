//! The denoiser's à-trous filter, `FILTER_STEPS` dispatches in one pass. See `filter.wgsl`.

use wgpu::util::DeviceExt;

use super::FILTER_STEPS;
use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

pub struct Filter {
    pipeline: wgpu::ComputePipeline,
    /// By step: step k reads `light[(k + 1) % 2]` and writes the other.
    bind_groups: Vec<wgpu::BindGroup>,
}

impl Filter {
    /// Reads `guides` and the variance estimate's `light[1]`; ping-pongs
    /// between the two.
    pub fn new(ctx: &GpuContext, scene: &GpuScene, light: &[wgpu::Buffer; 2], guides: &wgpu::Buffer) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = bindings::layout(
            device,
            "denoise_filter",
            &[
                bindings::storage_read(0, compute),       // light in
                bindings::storage_read_write(1, compute), // light out
                bindings::uniform(2, compute),            // the step
                bindings::storage_read(3, compute),       // the pixels' surfaces
            ],
        );
        let shader = ShaderDesc::new("passes/denoise/filter.wgsl");
        let pipeline = bindings::compute_pipeline(device, "denoise_filter", &shader, &[&scene.bind_group_layout, &layout])?;
        let steps: Vec<wgpu::Buffer> = (0..FILTER_STEPS)
            .map(|k| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("denoise_filter step"),
                    contents: bytemuck::cast_slice(&[1u32 << k, 0, 0, 0]),
                    usage: wgpu::BufferUsages::UNIFORM,
                })
            })
            .collect();
        let bind_groups = (0..FILTER_STEPS as usize)
            .map(|k| {
                bindings::bind_group(
                    device,
                    "denoise_filter",
                    &layout,
                    vec![
                        light[(k + 1) % 2].as_entire_binding(),
                        light[k % 2].as_entire_binding(),
                        steps[k].as_entire_binding(),
                        guides.as_entire_binding(),
                    ],
                )
            })
            .collect();
        Ok(Self { pipeline, bind_groups })
    }

    /// The buffer of `light` the last step writes.
    pub fn result<'a>(&self, light: &'a [wgpu::Buffer; 2]) -> &'a wgpu::Buffer {
        &light[(FILTER_STEPS as usize - 1) % 2]
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        scene: &wgpu::BindGroup,
        workgroups: (u32, u32),
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("denoise_filter"),
            timestamp_writes: timer.map(|t| t.compute_pass("denoise_filter")),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, scene, &[]);
        for group in &self.bind_groups {
            pass.set_bind_group(1, group, &[]);
            pass.dispatch_workgroups(workgroups.0, workgroups.1, 1);
        }
    }
}
