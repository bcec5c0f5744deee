//! The renderer: a device, an uploaded scene and a pipeline. `render` draws one frame for a camera;
//! images are read back on request so benchmarks time frames without readback in the way.

use crate::{
    accel::VolumeStructure,
    config::RenderConfig,
    gpu::{readback, FrameUniforms, GpuContext, GpuScene, GpuTimer, PassTimings},
    pipelines::{DecalMethod, FramePipeline, LightMethod},
    scene::{Camera, Scene},
    Result,
};

/// Time between frames rendered back to back: animated groups move by this much per frame.
pub const FRAME_INTERVAL: f32 = 1.0 / 60.0;

pub struct Renderer {
    pub ctx: GpuContext,
    pub scene: GpuScene,
    pub config: RenderConfig,
    pipeline: FramePipeline,
    lights: VolumeStructure,
    decals: VolumeStructure,
    timer: Option<GpuTimer>,
    /// Scene time of the next frame, in seconds: where animated groups are.
    pub time: f32,
}

/// A read-back image, rows top to bottom.
#[derive(Clone, Debug)]
pub struct Image<T> {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<T>,
}

impl Renderer {
    pub fn new(ctx: GpuContext, scene: &Scene, config: RenderConfig) -> Result<Self> {
        config.validate(&ctx)?;
        let gpu_scene = GpuScene::upload(&ctx, scene, config.max_texture_size, config.anisotropy)?;
        // Brute force reads the structures' items and instances only: their BVHs are built once on the
        // CPU, so a GPU rebuild every frame is timed only where a method uses it.
        let build = |uses_bvh: bool, build| if uses_bvh { build } else { crate::accel::BvhBuild::CpuOnce };
        let lights = VolumeStructure::for_lights(
            &ctx,
            &scene.lights,
            &scene.light_groups,
            build(config.light_method == LightMethod::Bvh, config.light_bvh_build),
        )?;
        let decals = VolumeStructure::for_decals(
            &ctx,
            &scene.decals,
            &scene.decal_groups,
            build(config.decal_method == DecalMethod::Bvh, config.decal_bvh_build),
        )?;
        let pipeline = FramePipeline::new(
            &ctx,
            &gpu_scene,
            config.pipeline,
            (config.light_method, config.decal_method),
            (&lights, &decals),
            (config.width, config.height),
        )?;
        let timer = GpuTimer::new(&ctx);
        ctx.check_errors()?;
        Ok(Self { ctx, scene: gpu_scene, config, pipeline, lights, decals, timer, time: 0.0 })
    }

    /// Whether `render` returns per-pass GPU timings.
    pub fn has_timestamps(&self) -> bool {
        self.timer.is_some()
    }

    /// Renders one frame and waits for it; returns per-pass GPU milliseconds (empty without
    /// timestamp support).
    pub fn render(&mut self, camera: &Camera) -> Result<PassTimings> {
        Ok(self.render_frames(camera, 1)?.pop().unwrap_or_default())
    }

    /// Renders `count` frames submitted back to back, as an application's frame loop does, waiting
    /// only when the timer's slots are full and at the end; each frame advances `time` by
    /// [`FRAME_INTERVAL`]. Returns each frame's pass timings.
    pub fn render_frames(&mut self, camera: &Camera, count: u32) -> Result<Vec<PassTimings>> {
        let mut uniforms = FrameUniforms::new(camera, self.config.width, self.config.height, &self.scene.lighting, self.config.tonemapper);
        uniforms.light_instance_count = self.lights.instance_count();
        uniforms.decal_instance_count = self.decals.instance_count();
        self.scene.write_frame(&self.ctx.queue, &uniforms);
        let mut timings = Vec::new();
        for _ in 0..count {
            let mut encoder = self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
            if let Some(timer) = &mut self.timer {
                if timer.is_full() {
                    timings.extend(timer.read(&self.ctx)?);
                }
                timer.begin_frame();
            }
            self.lights.record(&self.ctx, &mut encoder, self.timer.as_mut(), self.time)?;
            self.decals.record(&self.ctx, &mut encoder, self.timer.as_mut(), self.time)?;
            self.pipeline.record(&mut encoder, self.timer.as_mut(), &self.scene, camera.position());
            if let Some(timer) = &self.timer {
                timer.resolve(&mut encoder);
            }
            self.ctx.queue.submit([encoder.finish()]);
            self.time += FRAME_INTERVAL;
        }
        match &mut self.timer {
            Some(timer) => timings.extend(timer.read(&self.ctx)?),
            None => self.ctx.wait_idle()?,
        }
        self.ctx.check_errors()?;
        Ok(timings)
    }

    /// The last frame after tonemapping: RGBA8, sRGB-encoded.
    pub fn read_ldr(&self) -> Result<Image<[u8; 4]>> {
        let bytes = readback::read_texture(&self.ctx, &self.pipeline.targets().ldr, 4)?;
        Ok(self.image(bytemuck::cast_slice(&bytes).to_vec()))
    }

    /// The last frame before exposure and tonemapping: linear RGBA radiance.
    pub fn read_hdr(&self) -> Result<Image<[f32; 4]>> {
        let bytes = readback::read_texture(&self.ctx, &self.pipeline.targets().hdr, 16)?;
        Ok(self.image(bytemuck::pod_collect_to_vec(&bytes)))
    }

    fn image<T>(&self, pixels: Vec<T>) -> Image<T> {
        Image { width: self.config.width, height: self.config.height, pixels }
    }
}
