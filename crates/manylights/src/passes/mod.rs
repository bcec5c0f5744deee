//! Render and compute passes, one file each with its WGSL beside it. A pass is built once (pipelines,
//! layouts, bind groups over its targets) and recorded each frame by `record`, under a timestamp scope
//! named like its file and its WGSL entry point.

pub mod tonemap;
pub mod visbuffer_raster;
pub mod visbuffer_shade;

/// Workgroup edge of the 2D compute passes (`@workgroup_size(8, 8)` in their WGSL).
pub const TILE: u32 = 8;

pub fn dispatch_size(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(TILE), height.div_ceil(TILE))
}
