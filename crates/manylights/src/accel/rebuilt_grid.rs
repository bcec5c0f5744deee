//! Entry grids for groups rebuilt on the GPU every frame (`rebuilt_grid.wgsl`): what `entry_grid.rs`
//! gives CPU-built groups, built anew after each LBVH build. A uniform grid over the group's bounds
//! names, per cell, the deepest node whose subtree holds every leaf whose box reaches the cell; a
//! query walking alone starts there instead of at the root, and a cell no leaf reaches ends it at once.
//! The LBVH stores a subtree within the nodes before its `skip` (`lbvh.wgsl`), so a walk from a cell's
//! node ends at its `skip` as walks of CPU-built groups end at theirs; queries walked by a whole
//! subgroup merge their lanes' cells into one range of nodes, which that order does not allow, and
//! start at the root (`ENTRY_GRID_REBUILT` in `accel/volume_query.wgsl`).
//!
//! The grid's placement is fixed when the structure is built, from the group's bounds then; cells on
//! the grid's faces reach out to infinity, so volumes that later move outside it stay exact.

use glam::{UVec3, Vec3};

use super::{entry_grid, Aabb, BvhNode};
use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuTimer};
use crate::Result;
use wgpu::util::DeviceExt;

/// Set in a rebuilt group's grid header's `skip`, above the cells per axis (`entry_grid_dims`). Keep
/// in sync with `ENTRY_GRID_REBUILT` in `accel/bvh_types.wgsl`.
pub const ENTRY_GRID_REBUILT: u32 = 1 << 30;

/// Cells per item, and the fewest and most cells a group's grid gets. Every frame's pass visits each
/// cell's part of the tree, so rebuilt grids are far coarser than CPU-built ones: 32 cells per item
/// shaded 28k small lights about 2 % faster than 8 but took twice as long to rebuild
/// (benchmarks/LOG.md, topic 1).
const CELLS_PER_ITEM: f64 = 8.0;
const MIN_CELLS: f64 = (1 << 12) as f64;
const MAX_CELLS: f64 = (1 << 20) as f64;

const WORKGROUP: u32 = 256;

/// Where a rebuilt group's grid lies and how it is divided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridPlacement {
    pub min: Vec3,
    pub cells_per_unit: Vec3,
    pub dims: UVec3,
}

impl GridPlacement {
    /// The grid over a group of `items` volumes within `bounds`; `None` for groups too small to need
    /// one ([`entry_grid::MIN_PRIMITIVES`]) or bounds that are not finite.
    pub fn for_group(bounds: &Aabb, items: usize) -> Option<Self> {
        let extent = bounds.max - bounds.min;
        if items < entry_grid::MIN_PRIMITIVES || !(extent.is_finite() && bounds.min.is_finite()) {
            return None;
        }
        let dims = entry_grid::grid_dims(extent, (items as f64 * CELLS_PER_ITEM).clamp(MIN_CELLS, MAX_CELLS));
        let cells_per_unit = Vec3::select(extent.cmpgt(Vec3::ZERO), dims.as_vec3() / extent, Vec3::ZERO);
        Some(Self { min: bounds.min, cells_per_unit, dims })
    }

    pub fn cells(&self) -> u32 {
        self.dims.x * self.dims.y * self.dims.z
    }

    /// The header node queries read before the group's root, its cells from word `first_cell` of the
    /// primitive array (`entry_grid_cell` in `accel/bvh_types.wgsl`).
    pub fn header(&self, first_cell: u32) -> BvhNode {
        let dims = self.dims.x | self.dims.y << 10 | self.dims.z << 20;
        BvhNode { min: self.min.to_array(), entry: first_cell, max: self.cells_per_unit.to_array(), skip: dims | ENTRY_GRID_REBUILT }
    }
}

/// One group's grid to rebuild: its placement, its first cell word, and its BVH's nodes.
#[derive(Clone, Copy, Debug)]
pub struct RebuiltGroup {
    pub placement: GridPlacement,
    pub first_cell: u32,
    pub root: u32,
    /// One past the group's last node: the stop of a cell whose subtree ends the group's BVH.
    pub node_end: u32,
}

/// Keep in sync with `GridParams` in `rebuilt_grid.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GridParams {
    min: [f32; 3],
    root: u32,
    cell_size: [f32; 3],
    first_cell: u32,
    dims: [u32; 3],
    node_end: u32,
    margin: [f32; 3],
    _pad: u32,
}

/// The pass that rebuilds every rebuilt group's grid of a structure, after the groups' builds.
pub struct RebuiltGrids {
    pipeline: wgpu::ComputePipeline,
    /// Per group: its bind group and cell count.
    grids: Vec<(wgpu::BindGroup, u32)>,
    scope: &'static str,
}

impl RebuiltGrids {
    /// The pass over `groups`, reading the structure's `nodes` and writing their cells into
    /// `primitives`, timed as `scope`.
    pub fn new(
        ctx: &GpuContext,
        scope: &'static str,
        nodes: &wgpu::Buffer,
        primitives: &wgpu::Buffer,
        groups: &[RebuiltGroup],
    ) -> Result<Self> {
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        // Keep in sync with the bindings of `rebuilt_grid.wgsl`.
        let layout = bindings::layout(
            device,
            "rebuilt grid",
            &[bindings::uniform(0, compute), bindings::storage_read(1, compute), bindings::storage_read_write(2, compute)],
        );
        let grids = groups
            .iter()
            .map(|group| {
                let p = group.placement;
                let cell_size = Vec3::select(p.cells_per_unit.cmpgt(Vec3::ZERO), Vec3::ONE / p.cells_per_unit, Vec3::ZERO);
                let far = p.min + cell_size * p.dims.as_vec3();
                // Cells are widened as CPU grids' are (`EntryGrid::build`), so a point whose cell index
                // rounds into a neighbour is still covered there.
                let margin = cell_size * 1e-3 + p.min.abs().max(far.abs()) * 1e-5;
                let params = GridParams {
                    min: p.min.to_array(),
                    root: group.root,
                    cell_size: cell_size.to_array(),
                    first_cell: group.first_cell,
                    dims: p.dims.to_array(),
                    node_end: group.node_end,
                    margin: margin.to_array(),
                    _pad: 0,
                };
                let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("rebuilt grid params"),
                    contents: bytemuck::bytes_of(&params),
                    usage: wgpu::BufferUsages::UNIFORM,
                });
                let bind_group = bindings::bind_group(
                    device,
                    "rebuilt grid",
                    &layout,
                    [&params, nodes, primitives].iter().map(|b| b.as_entire_binding()).collect(),
                );
                (bind_group, p.cells())
            })
            .collect();
        let pipeline = bindings::compute_pipeline(device, "rebuilt_grid", &ShaderDesc::new("accel/rebuilt_grid.wgsl"), &[&layout])?;
        Ok(Self { pipeline, grids, scope })
    }

    /// Records every group's cells: after the builds, before anything queries the groups.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.scope),
            timestamp_writes: timer.map(|t| t.compute_pass(self.scope)),
        });
        pass.set_pipeline(&self.pipeline);
        for (bind_group, cells) in &self.grids {
            pass.set_bind_group(0, bind_group, &[]);
            pass.dispatch_workgroups(cells.div_ceil(WORKGROUP), 1, 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placements_fit_their_groups_and_mark_their_headers() {
        let room = Aabb::new(Vec3::new(-15.0, 0.0, -7.0), Vec3::new(15.0, 12.0, 7.0));
        assert_eq!(GridPlacement::for_group(&room, entry_grid::MIN_PRIMITIVES - 1), None, "small groups start at their root");
        let infinite = Aabb::new(Vec3::splat(f32::NEG_INFINITY), Vec3::ZERO);
        assert_eq!(GridPlacement::for_group(&infinite, 1000), None);
        for items in [16, 28_000, 1 << 20] {
            let grid = GridPlacement::for_group(&room, items).unwrap();
            let cells = f64::from(grid.cells());
            // Cubic cells: the counts per axis round, so allow a factor either side of the aim.
            assert!((MIN_CELLS / 2.0..=MAX_CELLS * 2.0).contains(&cells), "{items} items: {cells} cells");
            assert!(
                (grid.min - room.min).length() == 0.0
                    && (grid.cells_per_unit * (room.max - room.min) - grid.dims.as_vec3()).abs().max_element() < 1e-3
            );
            let header = grid.header(77);
            assert_eq!((header.entry, header.skip & ENTRY_GRID_REBUILT), (77, ENTRY_GRID_REBUILT));
            assert_eq!(header.skip & !ENTRY_GRID_REBUILT, grid.dims.x | grid.dims.y << 10 | grid.dims.z << 20);
        }
        // A flat group gets one cell across its flat axis.
        let floor = Aabb::new(Vec3::new(-15.0, 0.0, -7.0), Vec3::new(15.0, 0.0, 7.0));
        let grid = GridPlacement::for_group(&floor, 28_000).unwrap();
        assert_eq!((grid.dims.y, grid.cells_per_unit.y), (1, 0.0));
    }
}
