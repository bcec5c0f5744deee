//! The denoiser's variance estimate for short histories. See `variance.wgsl`.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::passes::builder::ComputeStep;
use crate::Result;

pub struct Variance {
    step: ComputeStep,
    /// By the frame's parity: it reads that half of the history.
    bind_groups: [wgpu::BindGroup; 2],
}

impl Variance {
    /// Reads its half of `history`, `light[0]` and `guides`; writes `light[1]`.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        history: &[wgpu::Buffer; 2],
        light: [&wgpu::Buffer; 2],
        guides: &wgpu::Buffer,
    ) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = bindings::layout(
            device,
            "denoise_variance",
            &[
                bindings::storage_read(0, compute),       // this frame's history
                bindings::storage_read(1, compute),       // integrated light and variance
                bindings::storage_read_write(2, compute), // estimated light and variance
                bindings::storage_read(3, compute),       // the pixels' surfaces
            ],
        );
        let shader = ShaderDesc::new("passes/denoise/variance.wgsl");
        let step = ComputeStep::new(device, &shader, "denoise_variance", &[&scene.bind_group_layout, &layout], &[])?;
        let bind_groups = [0, 1].map(|parity| {
            bindings::bind_group(
                device,
                "denoise_variance",
                &layout,
                vec![
                    history[parity].as_entire_binding(),
                    light[0].as_entire_binding(),
                    light[1].as_entire_binding(),
                    guides.as_entire_binding(),
                ],
            )
        });
        Ok(Self { step, bind_groups })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        scene: &wgpu::BindGroup,
        parity: usize,
        workgroups: (u32, u32),
    ) {
        self.step.record(encoder, timer, &[scene, &self.bind_groups[parity]], workgroups);
    }
}
