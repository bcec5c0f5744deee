//! Motion blur: `motion_blur_tiles` (longest blur per tile) then `motion_blur` (McGuire's
//! reconstruction filter). See `motion_blur.wgsl`; velocities come from `velocity.rs`.

use super::velocity::VELOCITY_FORMAT;
use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

pub struct MotionBlurPass {
    tiles_pipeline: wgpu::ComputePipeline,
    tiles_bind_group: wgpu::BindGroup,
    gather_pipeline: wgpu::ComputePipeline,
    gather_bind_group: wgpu::BindGroup,
    tile_count: (u32, u32),
}

impl MotionBlurPass {
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        uniforms: &wgpu::Buffer,
        (depth, velocity, input, output): (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView),
        (width, height): (u32, u32),
    ) -> Result<Self> {
        let device = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        let unfilterable = wgpu::TextureSampleType::Float { filterable: false };
        let d2 = wgpu::TextureViewDimension::D2;
        let tile_count = super::tile_count(width, height);
        let tiles = crate::pipelines::target(
            device,
            "motion blur tiles",
            tile_count.0,
            tile_count.1,
            VELOCITY_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let tiles_view = tiles.create_view(&Default::default());
        // Keep in sync with `motion_blur.wgsl`: each entry point binds its own of group 1's slots.
        let tiles_layout = bindings::layout(
            device,
            "motion_blur_tiles",
            &[bindings::uniform(0, c), bindings::texture(2, c, unfilterable, d2), bindings::storage_texture_write(5, c, VELOCITY_FORMAT)],
        );
        let gather_layout = bindings::layout(
            device,
            "motion_blur",
            &[
                bindings::uniform(0, c),
                bindings::texture(1, c, wgpu::TextureSampleType::Depth, d2),
                bindings::texture(2, c, unfilterable, d2),
                bindings::texture(3, c, unfilterable, d2),
                bindings::texture(4, c, unfilterable, d2),
                bindings::storage_texture_write(6, c, super::POST_FORMAT),
            ],
        );
        let shader = ShaderDesc::new("post/motion_blur.wgsl");
        let tiles_pipeline = bindings::compute_pipeline(device, "motion_blur_tiles", &shader, &[&scene.bind_group_layout, &tiles_layout])?;
        let gather_pipeline = bindings::compute_pipeline(device, "motion_blur", &shader, &[&scene.bind_group_layout, &gather_layout])?;
        let view = wgpu::BindingResource::TextureView;
        let tiles_bind_group = super::bind_group_at(
            device,
            "motion_blur_tiles",
            &tiles_layout,
            vec![(0, uniforms.as_entire_binding()), (2, view(velocity)), (5, view(&tiles_view))],
        );
        let gather_bind_group = super::bind_group_at(
            device,
            "motion_blur",
            &gather_layout,
            vec![
                (0, uniforms.as_entire_binding()),
                (1, view(depth)),
                (2, view(velocity)),
                (3, view(input)),
                (4, view(&tiles_view)),
                (6, view(output)),
            ],
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
            ("motion_blur_tiles", &self.tiles_pipeline, &self.tiles_bind_group, tiles),
            ("motion_blur", &self.gather_pipeline, &self.gather_bind_group, pixels),
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
