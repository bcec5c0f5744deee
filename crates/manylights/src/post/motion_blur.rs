//! Motion blur: `motion_blur_tiles` (longest blur per tile) then `motion_blur` (McGuire's
//! reconstruction filter). See `motion_blur.wgsl`; velocities come from `velocity.rs`.

use super::{tile_image, velocity::VELOCITY_FORMAT, EffectImages, TiledGather};
use crate::gpu::{bindings, GpuContext, GpuScene};
use crate::Result;

pub fn new(
    ctx: &GpuContext,
    scene: &GpuScene,
    uniforms: &wgpu::Buffer,
    EffectImages { depth, input, output }: EffectImages,
    velocity: &wgpu::TextureView,
    size: (u32, u32),
) -> Result<TiledGather> {
    let c = wgpu::ShaderStages::COMPUTE;
    let unfilterable = wgpu::TextureSampleType::Float { filterable: false };
    let d2 = wgpu::TextureViewDimension::D2;
    let tiles = tile_image(&ctx.device, "motion blur tiles", VELOCITY_FORMAT, size);
    let view = wgpu::BindingResource::TextureView;
    // Keep in sync with `motion_blur.wgsl`: each entry point binds its own of group 1's slots.
    TiledGather::new(
        ctx,
        scene,
        "post/motion_blur.wgsl",
        size,
        (
            "motion_blur_tiles",
            vec![
                (bindings::uniform(0, c), uniforms.as_entire_binding()),
                (bindings::texture(2, c, unfilterable, d2), view(velocity)),
                (bindings::storage_texture_write(5, c, VELOCITY_FORMAT), view(&tiles)),
            ],
        ),
        (
            "motion_blur",
            vec![
                (bindings::uniform(0, c), uniforms.as_entire_binding()),
                (bindings::texture(1, c, wgpu::TextureSampleType::Depth, d2), view(depth)),
                (bindings::texture(2, c, unfilterable, d2), view(velocity)),
                (bindings::texture(3, c, unfilterable, d2), view(input)),
                (bindings::texture(4, c, unfilterable, d2), view(&tiles)),
                (bindings::storage_texture_write(6, c, super::POST_FORMAT), view(output)),
            ],
        ),
    )
}
