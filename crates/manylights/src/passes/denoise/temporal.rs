//! The denoiser's temporal accumulation. See `temporal.wgsl`.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::passes::builder::ComputeStep;
use crate::Result;

pub struct Temporal {
    step: ComputeStep,
    /// By the frame's parity: it writes that half of the history and reads the other.
    bind_groups: [wgpu::BindGroup; 2],
}

impl Temporal {
    /// Reads the frame's `depth` and the scene's samples; writes a half of `history`, `integrated`
    /// and `guides`.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        depth: &wgpu::TextureView,
        history: &[wgpu::Buffer; 2],
        integrated: &wgpu::Buffer,
        guides: &wgpu::Buffer,
    ) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = bindings::layout(
            device,
            "denoise_temporal",
            &[
                bindings::texture(0, compute, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2), // depth
                bindings::storage_read(1, compute),       // the previous frame's history
                bindings::storage_read_write(2, compute), // this frame's history
                bindings::storage_read_write(3, compute), // integrated light and variance
                bindings::storage_read_write(4, compute), // the pixels' surfaces, for the spatial passes
            ],
        );
        let shader = ShaderDesc::new("passes/denoise/temporal.wgsl");
        let step = ComputeStep::new(device, &shader, "denoise_temporal", &[&scene.bind_group_layout, &layout], &[])?;
        let bind_groups = [0, 1].map(|parity| {
            bindings::bind_group(
                device,
                "denoise_temporal",
                &layout,
                vec![
                    wgpu::BindingResource::TextureView(depth),
                    history[1 - parity].as_entire_binding(),
                    history[parity].as_entire_binding(),
                    integrated.as_entire_binding(),
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
