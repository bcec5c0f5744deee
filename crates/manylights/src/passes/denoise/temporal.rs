//! The denoiser's temporal accumulation. See `temporal.wgsl`.

use super::ParityStep;
use crate::gpu::{bindings, GpuContext, GpuScene};
use crate::Result;

/// Reads the frame's `depth`, the scene's samples and the other half of `history` than the frame's
/// parity; writes the parity's half, `integrated` and `guides`.
pub fn step(
    ctx: &GpuContext,
    scene: &GpuScene,
    depth: &wgpu::TextureView,
    history: &[wgpu::Buffer; 2],
    integrated: &wgpu::Buffer,
    guides: &wgpu::Buffer,
) -> Result<ParityStep> {
    let compute = wgpu::ShaderStages::COMPUTE;
    ParityStep::new(
        ctx,
        scene,
        ("passes/denoise/temporal.wgsl", "denoise_temporal"),
        &[
            bindings::texture(0, compute, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2), // depth
            bindings::storage_read(1, compute),                                                            // the previous frame's history
            bindings::storage_read_write(2, compute),                                                      // this frame's history
            bindings::storage_read_write(3, compute),                                                      // integrated light and variance
            bindings::storage_read_write(4, compute), // the pixels' surfaces, for the spatial passes
        ],
        |parity| {
            vec![
                wgpu::BindingResource::TextureView(depth),
                history[1 - parity].as_entire_binding(),
                history[parity].as_entire_binding(),
                integrated.as_entire_binding(),
                guides.as_entire_binding(),
            ]
        },
    )
}
