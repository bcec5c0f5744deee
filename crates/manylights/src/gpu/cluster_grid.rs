//! The clustered method's froxel grid (`accel/cluster_grid.wgsl`): screen tiles and exponential depth
//! slices, described to the shaders by the frame uniforms (`FrameUniforms::cluster_grid`).

use glam::Vec3;

use crate::scene::{Aabb, Camera, Projection};

/// Froxel width and height in pixels, as in Olsson et al.'s tiles.
pub const CLUSTER_TILE_PIXELS: u32 = 32;
/// Depth slices between the near plane and the far side of the scene.
pub const CLUSTER_SLICES: u32 = 32;

/// The froxel grid for an image size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClusterGrid {
    pub tiles_x: u32,
    pub tiles_y: u32,
    pub slices: u32,
}

impl ClusterGrid {
    pub fn for_resolution(width: u32, height: u32) -> Self {
        Self { tiles_x: width.div_ceil(CLUSTER_TILE_PIXELS), tiles_y: height.div_ceil(CLUSTER_TILE_PIXELS), slices: CLUSTER_SLICES }
    }

    pub fn froxels(&self) -> u32 {
        self.tiles_x * self.tiles_y * self.slices
    }

    /// `FrameUniforms::cluster_grid`.
    pub fn uniform(&self) -> [u32; 4] {
        [self.tiles_x, self.tiles_y, self.slices, CLUSTER_TILE_PIXELS]
    }

    /// `FrameUniforms::cluster_depth`: the near plane of the slicing, slices per doubling of view
    /// depth so that the last slice ends at the far side of `bounds` (points beyond it fall in the last
    /// slice), and the camera's near plane, in front of which no point is visible.
    pub fn depth_slicing(camera: &Camera, bounds: &Aabb) -> [f32; 4] {
        let forward = -camera.world_from_view.z_axis.truncate().normalize();
        let eye = camera.position();
        let far = if bounds.is_valid() {
            let corners = (0..8).map(|i| Vec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), bounds.max, bounds.min));
            corners.map(|c| (c - eye).dot(forward)).fold(0.0, f32::max)
        } else {
            0.0
        };
        let znear = match camera.projection {
            Projection::Perspective { znear, .. } | Projection::Orthographic { znear, .. } => znear,
        };
        let near = znear.max(far * 1e-6).max(1e-6);
        let far = far.max(near * 2.0);
        [near, CLUSTER_SLICES as f32 / (far / near).log2(), znear, 0.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slices_reach_the_far_side_of_the_scene() {
        let camera = Camera::look_at("c", Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, 1.0, 0.1);
        let bounds = Aabb::new(Vec3::splat(-5.0), Vec3::splat(5.0));
        let [near, per_doubling, znear, _] = ClusterGrid::depth_slicing(&camera, &bounds);
        assert_eq!((near, znear), (0.1, 0.1));
        // The far side is 15 units away: 32 slices over log2(150) doublings.
        assert!(((15.0f32 / 0.1).log2() * per_doubling - CLUSTER_SLICES as f32).abs() < 1e-3);
        let grid = ClusterGrid::for_resolution(100, 33);
        assert_eq!((grid.tiles_x, grid.tiles_y, grid.froxels()), (4, 2, 4 * 2 * CLUSTER_SLICES));
    }
}
