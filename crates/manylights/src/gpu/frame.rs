//! Per-frame constants: camera matrices, viewport, sun, ambient and the tonemapper.

use crate::{config::Tonemapper, scene::Camera};

/// Keep in sync with `FrameUniforms` in `shading/types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FrameUniforms {
    pub clip_from_world: [[f32; 4]; 4],
    pub view_from_clip: [[f32; 4]; 4],
    pub world_from_view: [[f32; 4]; 4],
    pub viewport: [f32; 4],
    pub sun_direction: [f32; 4],
    pub sun_radiance: [f32; 4],
    pub ambient: [f32; 4],
    /// Instances of light and decal groups (`accel::structure`), set by the renderer.
    pub light_instance_count: u32,
    pub exposure: f32,
    pub tonemapper: u32,
    pub decal_instance_count: u32,
}

/// The scene-wide lighting a frame needs, kept by `GpuScene` from the CPU scene.
#[derive(Clone, Copy, Debug)]
pub struct SceneLighting {
    pub sun: Option<crate::scene::Sun>,
    pub ambient: glam::Vec3,
    pub exposure: f32,
}

impl FrameUniforms {
    pub fn new(camera: &Camera, width: u32, height: u32, lighting: &SceneLighting, tonemapper: Tonemapper) -> Self {
        let clip_from_view = camera.clip_from_view(width as f32 / height as f32);
        let clip_from_world = clip_from_view * camera.world_from_view.inverse();
        // Invert in f64: reverse-Z projections lose visible precision when inverted in f32.
        let view_from_clip = clip_from_view.as_dmat4().inverse().as_mat4();
        let (sun_direction, sun_radiance) = match lighting.sun {
            Some(sun) => (sun.direction.normalize().extend(1.0), (sun.color * sun.illuminance).extend(0.0)),
            None => (glam::Vec4::ZERO, glam::Vec4::ZERO),
        };
        Self {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            view_from_clip: view_from_clip.to_cols_array_2d(),
            world_from_view: camera.world_from_view.to_cols_array_2d(),
            viewport: [width as f32, height as f32, 1.0 / width as f32, 1.0 / height as f32],
            sun_direction: sun_direction.to_array(),
            sun_radiance: sun_radiance.to_array(),
            ambient: lighting.ambient.extend(0.0).to_array(),
            light_instance_count: 0,
            exposure: lighting.exposure,
            tonemapper: tonemapper as u32,
            decal_instance_count: 0,
        }
    }
}
