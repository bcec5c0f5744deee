//! Per-frame constants: camera matrices, viewport, sun, environment lighting and the tonemapper.

use super::{cluster_grid::ClusterGrid, environment::EnvironmentLighting};
use crate::{
    scene::{Aabb, Camera, Projection},
    settings::{RaySettings, Tonemapper, MAX_PARTICLE_CASCADES},
};

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
    /// The environment's irradiance harmonics and flags ([`EnvironmentLighting::uniforms`]).
    pub environment_irradiance: [[f32; 4]; 9],
    pub environment: [f32; 4],
    /// Instances of light and decal groups (`accel::structure`), set by the renderer.
    pub light_instance_count: u32,
    pub exposure: f32,
    pub tonemapper: u32,
    pub decal_instance_count: u32,
    /// The clustered method's froxel grid (`accel/cluster_grid.wgsl`): tile columns, rows, depth
    /// slices, tile size in pixels.
    pub cluster_grid: [u32; 4],
    /// Its depth slicing: near plane, slices per doubling of view depth; the camera's near plane.
    pub cluster_depth: [f32; 4],
    /// The particle grid (`particles/`), set by the renderer: voxels per axis of each cascade and
    /// the number of cascades (0 when no grid lights the scene); the filter (`ParticleFilter` as
    /// u32) and samples per shading point; the inverse of the splat's texture scale; each cascade's
    /// corner and voxel edge.
    pub particle_volume: [u32; 4],
    pub particle_filter: [u32; 4],
    pub particle_texture_unscale: [f32; 4],
    pub particle_cascades: [[f32; 4]; MAX_PARTICLE_CASCADES as usize],
    /// Ray-traced effects ([`ray_uniforms`]), set by the renderer: sun shadow mode,
    /// shadow rays per pixel, reflection bounces; the sun's angular radius, the reflection roughness
    /// threshold, a pixel's spread angle and its width at the camera.
    pub ray_options: [u32; 4],
    pub ray_settings: [f32; 4],
    /// The debug view (`settings::DebugView`) and the count its heat map tops out at; zero: none.
    pub debug_view: [u32; 4],
    /// Direct lighting's sampling (`shading/direct/restir.wgsl`): x the frame's number, which seeds
    /// each frame's samples; y samples per shading point; z the half of the reservoirs the frame
    /// writes; w what is reused (`RestirReuse`, 0: nothing).
    pub direct_lighting: [u32; 4],
    /// The previous frame's camera, for reprojection.
    pub previous_clip_from_world: [[f32; 4]; 4],
}

/// What a frame needs of the scene besides its buffers, kept by `GpuScene` from the CPU scene.
#[derive(Clone, Copy, Debug)]
pub struct SceneConstants {
    pub sun: Option<crate::scene::Sun>,
    pub environment: EnvironmentLighting,
    /// Bounds of the geometry: the clustered grid's depth slices end at its far side.
    pub bounds: Aabb,
}

impl FrameUniforms {
    /// `exposure` is the fixed scale before tonemapping (1 under auto exposure, whose meter scales).
    pub fn new(camera: &Camera, width: u32, height: u32, scene: &SceneConstants, exposure: f32, tonemapper: Tonemapper) -> Self {
        let clip_from_view = camera.clip_from_view(width as f32 / height as f32);
        let clip_from_world = camera.clip_from_world(width, height);
        // Invert in f64: reverse-Z projections lose visible precision when inverted in f32.
        let view_from_clip = clip_from_view.as_dmat4().inverse().as_mat4();
        let (sun_direction, sun_radiance) = match scene.sun {
            Some(sun) => (sun.direction.normalize().extend(1.0), (sun.color * sun.illuminance).extend(0.0)),
            None => (glam::Vec4::ZERO, glam::Vec4::ZERO),
        };
        let (environment_irradiance, environment) = scene.environment.uniforms();
        Self {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            view_from_clip: view_from_clip.to_cols_array_2d(),
            world_from_view: camera.world_from_view.to_cols_array_2d(),
            viewport: [width as f32, height as f32, 1.0 / width as f32, 1.0 / height as f32],
            sun_direction: sun_direction.to_array(),
            sun_radiance: sun_radiance.to_array(),
            environment_irradiance,
            environment,
            light_instance_count: 0,
            exposure,
            tonemapper: tonemapper as u32,
            decal_instance_count: 0,
            cluster_grid: ClusterGrid::for_resolution(width, height).uniform(),
            cluster_depth: ClusterGrid::depth_slicing(camera, &scene.bounds),
            particle_volume: [0; 4],
            particle_filter: [0; 4],
            particle_texture_unscale: [1.0; 4],
            particle_cascades: [[0.0; 4]; MAX_PARTICLE_CASCADES as usize],
            ray_options: [0; 4],
            ray_settings: [0.0; 4],
            debug_view: [0; 4],
            direct_lighting: [0; 4],
            previous_clip_from_world: clip_from_world.to_cols_array_2d(),
        }
    }
}

/// The frame uniforms' `ray_options` and `ray_settings` (`shading/types.wgsl`), for a camera
/// rendering `height` pixel rows.
pub fn ray_uniforms(rays: &RaySettings, camera: &Camera, height: u32) -> ([u32; 4], [f32; 4]) {
    // A pixel's cone: its width at the camera (orthographic) and its spread angle (perspective).
    let (spread, width) = match camera.projection {
        Projection::Perspective { yfov, .. } => (2.0 * (yfov * 0.5).tan() / height as f32, 0.0),
        Projection::Orthographic { ymag, .. } => (0.0, 2.0 * ymag / height as f32),
    };
    let options = [rays.sun_shadows as u32, rays.shadow_rays, rays.reflection_bounces, rays.light_shadow_rays];
    (options, [(rays.sun_angle_degrees * 0.5).to_radians(), rays.reflection_roughness, spread, width])
}
