//! Depth of field: `depth_of_field_tiles` (largest circle of confusion per tile) then
//! `depth_of_field` (the gather). See `depth_of_field.wgsl`.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

pub struct DepthOfFieldPass {
    tiles_pipeline: wgpu::ComputePipeline,
    tiles_bind_group: wgpu::BindGroup,
    gather_pipeline: wgpu::ComputePipeline,
    gather_bind_group: wgpu::BindGroup,
    tile_count: (u32, u32),
}

impl DepthOfFieldPass {
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        uniforms: &wgpu::Buffer,
        (depth, input, output): (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView),
        (width, height): (u32, u32),
    ) -> Result<Self> {
        let device = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        let unfilterable = wgpu::TextureSampleType::Float { filterable: false };
        let d2 = wgpu::TextureViewDimension::D2;
        let tile_count = super::tile_count(width, height);
        let tiles = crate::pipelines::target(
            device,
            "depth of field tiles",
            tile_count.0,
            tile_count.1,
            wgpu::TextureFormat::R32Float,
            wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let tiles_view = tiles.create_view(&Default::default());
        // Keep in sync with `depth_of_field.wgsl`: each entry point binds its own of group 1's slots.
        let tiles_layout = bindings::layout(
            device,
            "depth_of_field_tiles",
            &[
                bindings::uniform(0, c),
                bindings::texture(1, c, wgpu::TextureSampleType::Depth, d2),
                bindings::storage_texture_write(4, c, wgpu::TextureFormat::R32Float),
            ],
        );
        let gather_layout = bindings::layout(
            device,
            "depth_of_field",
            &[
                bindings::uniform(0, c),
                bindings::texture(1, c, wgpu::TextureSampleType::Depth, d2),
                bindings::texture(2, c, unfilterable, d2),
                bindings::texture(3, c, unfilterable, d2),
                bindings::storage_texture_write(5, c, super::POST_FORMAT),
            ],
        );
        let shader = ShaderDesc::new("post/depth_of_field.wgsl");
        let tiles_pipeline =
            bindings::compute_pipeline(device, "depth_of_field_tiles", &shader, &[&scene.bind_group_layout, &tiles_layout])?;
        let gather_pipeline = bindings::compute_pipeline(device, "depth_of_field", &shader, &[&scene.bind_group_layout, &gather_layout])?;
        let view = wgpu::BindingResource::TextureView;
        let tiles_bind_group = super::bind_group_at(
            device,
            "depth_of_field_tiles",
            &tiles_layout,
            vec![(0, uniforms.as_entire_binding()), (1, view(depth)), (4, view(&tiles_view))],
        );
        let gather_bind_group = super::bind_group_at(
            device,
            "depth_of_field",
            &gather_layout,
            vec![(0, uniforms.as_entire_binding()), (1, view(depth)), (2, view(input)), (3, view(&tiles_view)), (5, view(output))],
        );
        Ok(Self { tiles_pipeline, tiles_bind_group, gather_pipeline, gather_bind_group, tile_count })
    }

    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        scene: &GpuScene,
        (width, height): (u32, u32),
    ) {
        let tiles = crate::passes::dispatch_size(self.tile_count.0, self.tile_count.1);
        let pixels = crate::passes::dispatch_size(width, height);
        for (name, pipeline, bind_group, (x, y)) in [
            ("depth_of_field_tiles", &self.tiles_pipeline, &self.tiles_bind_group, tiles),
            ("depth_of_field", &self.gather_pipeline, &self.gather_bind_group, pixels),
        ] {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(name),
                timestamp_writes: timer.as_deref_mut().map(|t| t.compute_pass(name)),
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &scene.bind_group, &[]);
            pass.set_bind_group(1, bind_group, &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}
