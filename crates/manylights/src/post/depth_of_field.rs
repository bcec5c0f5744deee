//! Depth of field: `depth_of_field_tiles` (largest circle of confusion per tile) then
//! `depth_of_field` (the gather). See `depth_of_field.wgsl`.

use super::{tile_image, EffectImages, TiledGather};
use crate::gpu::{bindings, GpuContext, GpuScene};
use crate::Result;

pub fn new(
    ctx: &GpuContext,
    scene: &GpuScene,
    uniforms: &wgpu::Buffer,
    EffectImages { depth, input, output }: EffectImages,
    size: (u32, u32),
) -> Result<TiledGather> {
    let c = wgpu::ShaderStages::COMPUTE;
    let unfilterable = wgpu::TextureSampleType::Float { filterable: false };
    let d2 = wgpu::TextureViewDimension::D2;
    let tiles = tile_image(&ctx.device, "depth of field tiles", wgpu::TextureFormat::R32Float, size);
    let view = wgpu::BindingResource::TextureView;
    // Keep in sync with `depth_of_field.wgsl`: each entry point binds its own of group 1's slots.
    TiledGather::new(
        ctx,
        scene,
        "post/depth_of_field.wgsl",
        size,
        (
            "depth_of_field_tiles",
            vec![
                (bindings::uniform(0, c), uniforms.as_entire_binding()),
                (bindings::texture(1, c, wgpu::TextureSampleType::Depth, d2), view(depth)),
                (bindings::storage_texture_write(4, c, wgpu::TextureFormat::R32Float), view(&tiles)),
            ],
        ),
        (
            "depth_of_field",
            vec![
                (bindings::uniform(0, c), uniforms.as_entire_binding()),
                (bindings::texture(1, c, wgpu::TextureSampleType::Depth, d2), view(depth)),
                (bindings::texture(2, c, unfilterable, d2), view(input)),
                (bindings::texture(3, c, unfilterable, d2), view(&tiles)),
                (bindings::storage_texture_write(5, c, super::POST_FORMAT), view(output)),
            ],
        ),
    )
}
