//! The denoiser's variance estimate for short histories. See `variance.wgsl`.

use super::ParityStep;
use crate::gpu::{bindings, GpuContext, GpuScene};
use crate::Result;

/// Reads the frame's half of `history`, `light[0]` and `guides`; writes `light[1]`.
pub fn step(
    ctx: &GpuContext,
    scene: &GpuScene,
    history: &[wgpu::Buffer; 2],
    light: [&wgpu::Buffer; 2],
    guides: &wgpu::Buffer,
) -> Result<ParityStep> {
    let compute = wgpu::ShaderStages::COMPUTE;
    ParityStep::new(
        ctx,
        scene,
        ("passes/denoise/variance.wgsl", "denoise_variance"),
        &[
            bindings::storage_read(0, compute),       // this frame's history
            bindings::storage_read(1, compute),       // integrated light and variance
            bindings::storage_read_write(2, compute), // estimated light and variance
            bindings::storage_read(3, compute),       // the pixels' surfaces
        ],
        |parity| {
            vec![
                history[parity].as_entire_binding(),
                light[0].as_entire_binding(),
                light[1].as_entire_binding(),
                guides.as_entire_binding(),
            ]
        },
    )
}
