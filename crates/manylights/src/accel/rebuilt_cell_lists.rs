//! Cell lists built on the GPU (`rebuilt_cell_lists.wgsl`): for the one placed group of lights or
//! decals short of the density where subgroups share leaves out, what `cell_lists.rs` gives crowded
//! decals built once — a uniform grid over the group whose cells list every volume that may reach
//! them — in place of the group's BVH (and, rebuilt every frame, its entry grid and leaf-order copy):
//! every frame where the group is rebuilt every frame, else once. A point query reads its cell's list
//! (`shading/enumerate/lights_cells.wgsl`, `decals_cells.wgsl`) instead of walking. Rebuilt every
//! frame, the LBVH takes more dependent passes than the lists' four, and its entry grid is coarser
//! than a CPU-built one; built once, the lists still shade faster than a walk of the CPU-built BVH
//! (benchmarks/LOG.md, topic 1).
//!
//! The grid's placement is fixed when the structure is built, from the volumes' boxes then: the
//! coarsest cells, from 1.5 typical volume sizes down, whose lists stay short, coarser still where a
//! volume would visit too many cells for a thread. Cells on the grid's faces reach out to infinity,
//! so a volume outside the grid is listed where the points outside it look. The lists' total length
//! is known only on the GPU: they hold [`RebuiltCellLists::capacity`] entries (as many as the
//! volumes' boxes visit), each frame records what it needed, and the renderer grows them and renders
//! again when a frame needed more, as for the clustered lists (`Renderer::render_frames`).

use glam::{UVec3, Vec3};
use wgpu::util::DeviceExt;

use super::{entry_grid::MAX_CELLS_PER_AXIS, Aabb, BvhNode};
use crate::{
    gpu::{bindings, readback, shaders::ShaderDesc, GpuContext, GpuTimer},
    Error, Result,
};

/// Each finer grid tried has cells this much smaller than the one before, from the plan's coarsest
/// (`plan::ListCells`), [`FINER_GRIDS`] of them in all. Every frame's scans visit every cell: for
/// 28k small lights over Sponza, cells of 1.5 edges rebuilt in a third of the time of cells of 0.625
/// and shaded 3 % slower; for lights reaching ten times as many points, the lists of such coarse
/// cells grow long (benchmarks/LOG.md, topic 1).
const FINER: f32 = 0.8;
const FINER_GRIDS: i32 = 5;
/// The longest mean list, over the cells that list anything, of a grid chosen for its coarseness.
const MAX_MEAN_LIST: f64 = 12.0;
/// The most cells one volume may visit, where the lists are rebuilt every frame: a thread visits them
/// all, twice a frame.
const MAX_CELLS_PER_VOLUME: u64 = 512;
/// The most cells one volume may visit, where the lists are built once: a volume far larger than the
/// others then coarsens everyone's cells less (4,096 cells take 16 times the others' cell edge, 512
/// only 8 times).
const MAX_CELLS_PER_VOLUME_ONCE: u64 = 4096;
/// The most cells a grid has (8 bytes of ranges each).
const MAX_CELLS: u64 = 1 << 22;
/// The most entries the lists may start with at load (8 bytes each), where the device binds as many.
const MAX_ENTRIES: u64 = 1 << 24;
/// Each try over a limit coarsens the cells by this much.
const COARSER: f32 = 1.25;
const MAX_TRIES: usize = 16;
/// Threads per workgroup of the per-volume passes (`VOLUME_THREADS` in the WGSL).
const VOLUME_THREADS: u32 = 64;
/// Cells per workgroup of the scans (`BLOCK_CELLS` in the WGSL).
const BLOCK_CELLS: u32 = 1024;
/// Bytes of one list entry: (instance, item), as the clustered lists'.
const ENTRY_BYTES: u64 = 8;
const PASSES: [&str; 4] = ["cell_lists_count", "cell_lists_scan_blocks", "cell_lists_scan_offsets", "cell_lists_fill"];

/// A volume's bounds in its group's space, each containing it: a sphere, a box, and an oriented box.
/// Keep in sync with `ListBounds` in `rebuilt_cell_lists.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ListBounds {
    /// xyz centre, w radius.
    pub sphere: [f32; 4],
    pub low: [f32; 4],
    pub high: [f32; 4],
    /// Rows of the affine map from group space into the oriented box's unit cube [-0.5, 0.5]³; zero
    /// rows where the sphere and box are bound enough (lights).
    pub unit_from_group: [[f32; 4]; 3],
}

impl ListBounds {
    /// A light's: its range sphere, widened by a few ulps as `light_aabb` widens its box, and its box.
    pub fn of_light(position: Vec3, range: f32, aabb: Aabb) -> Self {
        let pad = 4.0 * f32::EPSILON * (position.abs().max_element() + range);
        Self {
            sphere: position.extend(range + pad).into(),
            low: aabb.min.extend(0.0).into(),
            high: aabb.max.extend(0.0).into(),
            unit_from_group: [[0.0; 4]; 3],
        }
    }

    /// A decal's, from its box's AABB and the rows of its map into its unit cube (`GpuDecal`): the
    /// sphere through the AABB's corners, widened by a few ulps, the AABB and the oriented box.
    pub fn of_decal(aabb: &Aabb, decal_from_group: [[f32; 4]; 3]) -> Self {
        let (centre, half) = ((aabb.min + aabb.max) * 0.5, (aabb.max - aabb.min) * 0.5);
        let radius = half.length() * (1.0 + 4.0 * f32::EPSILON) + 4.0 * f32::EPSILON * centre.abs().max_element();
        Self {
            sphere: centre.extend(radius).into(),
            low: aabb.min.extend(0.0).into(),
            high: aabb.max.extend(0.0).into(),
            unit_from_group: decal_from_group,
        }
    }
}

/// What a grid may take: cells a volume visits, and bytes of a binding.
#[derive(Clone, Copy)]
struct Limits {
    cells_per_volume: u64,
    binding_bytes: u64,
}

/// Where a group's grid lies and how it is divided, chosen at load from its volumes' boxes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ListPlacement {
    pub min: Vec3,
    pub cells_per_unit: Vec3,
    pub cell_size: Vec3,
    pub dims: UVec3,
    /// Cells the volumes' boxes visit, in all: the most entries their lists can need at load.
    pub visits: u64,
}

impl ListPlacement {
    /// The grid over `boxes`: the coarsest whose lists stay short ([`MAX_MEAN_LIST`]) of cells
    /// from `coarsest_edge` median box edges down ([`FINER`]), or the finest within the limits;
    /// where even the coarsest passes them (volumes of very unequal sizes), coarser still. `None`
    /// for bounds that are not finite, where the volumes' [`ListBounds`] pass `max_binding_bytes`,
    /// or where no grid keeps the largest volume's cells (fewer where the lists are rebuilt
    /// `every_frame`), the cells and the lists within their limits: the cells' ranges and the
    /// entries each within `max_binding_bytes`.
    pub fn for_boxes(boxes: &[Aabb], coarsest_edge: f32, every_frame: bool, max_binding_bytes: u64) -> Option<Self> {
        let bounds = boxes.iter().fold(Aabb::EMPTY, |b, x| b.union(*x));
        let extent = bounds.max - bounds.min;
        if boxes.is_empty() || !(extent.is_finite() && bounds.min.is_finite()) || extent.max_element() <= 0.0 {
            return None;
        }
        if boxes.len() as u64 * std::mem::size_of::<ListBounds>() as u64 > max_binding_bytes {
            log::info!("no cell lists for {} volumes: their bounds pass the device's storage binding limit", boxes.len());
            return None;
        }
        let mut edges: Vec<f32> = boxes.iter().map(|b| (b.max - b.min).max_element()).collect();
        edges.sort_unstable_by(f32::total_cmp);
        let edge_of = |share: f32| (edges[edges.len() / 2] * share).max(extent.max_element() / MAX_CELLS_PER_AXIS as f32);
        let limits = Limits {
            cells_per_volume: if every_frame { MAX_CELLS_PER_VOLUME } else { MAX_CELLS_PER_VOLUME_ONCE },
            binding_bytes: max_binding_bytes,
        };
        let mut chosen = None;
        for share in (0..FINER_GRIDS).map(|k| coarsest_edge * FINER.powi(k)) {
            // Finer cells only take more cells and entries: once one grid passes the limits, the
            // finer ones do too.
            let Some((placement, mean)) = Self::fit(bounds, boxes, edge_of(share), limits) else { break };
            chosen = Some((placement, mean));
            if mean <= MAX_MEAN_LIST {
                break;
            }
        }
        let mut edge = edge_of(coarsest_edge);
        for _ in 0..MAX_TRIES {
            if chosen.is_some() {
                break;
            }
            edge *= COARSER;
            chosen = Self::fit(bounds, boxes, edge, limits);
        }
        let Some((placement, mean)) = chosen else {
            log::info!("no GPU cell lists for {} volumes: no grid keeps each volume's cells and the lists in bounds", boxes.len());
            return None;
        };
        let dims = placement.dims;
        log::info!(
            "GPU cell lists for {} volumes: {}×{}×{} cells, at most {} entries, {mean:.1} a listing cell",
            boxes.len(),
            dims.x,
            dims.y,
            dims.z,
            placement.visits
        );
        Some(placement)
    }

    /// The grid of cells of about `edge` over `bounds`, and its lists' mean length over the cells
    /// that list anything (counting every cell a volume's box meets); `None` past the limits.
    fn fit(bounds: Aabb, boxes: &[Aabb], edge: f32, limits: Limits) -> Option<(Self, f64)> {
        let dims = ((bounds.max - bounds.min) / edge).ceil().max(Vec3::ONE).min(Vec3::splat(MAX_CELLS_PER_AXIS as f32)).as_uvec3();
        let placement = Self::new(bounds, dims);
        let max_entries = MAX_ENTRIES.min(limits.binding_bytes / ENTRY_BYTES);
        if u64::from(placement.cells()) > MAX_CELLS.min(limits.binding_bytes / 8) {
            return None;
        }
        let mut counts = vec![0u32; placement.cells() as usize];
        let mut visits = 0u64;
        let margin = placement.margin();
        for b in boxes {
            let (first, last) = (placement.cell_of(b.min - margin), placement.cell_of(b.max + margin));
            let cells = (last - first + UVec3::ONE).as_u64vec3().element_product();
            visits += cells;
            if cells > limits.cells_per_volume || visits > max_entries {
                return None;
            }
            for z in first.z..=last.z {
                for y in first.y..=last.y {
                    for x in first.x..=last.x {
                        counts[((z * dims.y + y) * dims.x + x) as usize] += 1;
                    }
                }
            }
        }
        let listing = counts.iter().filter(|&&c| c > 0).count().max(1);
        Some((Self { visits, ..placement }, visits as f64 / listing as f64))
    }

    fn new(bounds: Aabb, dims: UVec3) -> Self {
        let extent = bounds.max - bounds.min;
        let flat = extent.cmpgt(Vec3::ZERO);
        Self {
            min: bounds.min,
            cells_per_unit: Vec3::select(flat, dims.as_vec3() / extent, Vec3::ZERO),
            cell_size: Vec3::select(flat, extent / dims.as_vec3(), Vec3::ZERO),
            dims,
            visits: 0,
        }
    }

    pub fn cells(&self) -> u32 {
        self.dims.x * self.dims.y * self.dims.z
    }

    /// How far each cell is widened, so that a point whose cell index rounds into a neighbour is
    /// still listed there (as `entry_grid.rs` widens its cells).
    fn margin(&self) -> Vec3 {
        let far = self.min + self.cell_size * self.dims.as_vec3();
        self.cell_size * 1e-3 + self.min.abs().max(far.abs()) * 1e-5
    }

    /// The cell holding `p`, clamped into the grid: the CPU twin of `cell_list_index` in
    /// `accel/bvh_types.wgsl`.
    pub fn cell_of(&self, p: Vec3) -> UVec3 {
        ((p - self.min) * self.cells_per_unit).floor().clamp(Vec3::ZERO, (self.dims - UVec3::ONE).as_vec3()).as_uvec3()
    }

    /// The header queries read (`cell_list_index` in `accel/bvh_types.wgsl`): the grid's corner
    /// (`min`), cells per unit length (`max`) and cells per axis, 10 bits each, x lowest (`skip`).
    pub fn header(&self) -> BvhNode {
        let dims = self.dims.x | self.dims.y << 10 | self.dims.z << 20;
        BvhNode { min: self.min.to_array(), entry: 0, max: self.cells_per_unit.to_array(), skip: dims }
    }
}

/// Keep in sync with `CellListParams` in `rebuilt_cell_lists.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CellListParams {
    min: [f32; 3],
    item_count: u32,
    cell_size: [f32; 3],
    first_item: u32,
    cells_per_unit: [f32; 3],
    capacity: u32,
    dims: [u32; 3],
    block_count: u32,
    margin: [f32; 3],
    row_threads: u32,
}

/// One group's cell lists and the passes that build them, every frame or once.
pub struct RebuiltCellLists {
    /// Per cell, (first entry, length): bound to shading.
    pub ranges: wgpu::Buffer,
    /// (instance, item) pairs: bound to shading; replaced when grown.
    pub entries: wgpu::Buffer,
    label: &'static str,
    scope: &'static str,
    placement: ListPlacement,
    item_count: u32,
    first_item: u32,
    capacity: u32,
    max_capacity: u32,
    /// Rebuilt every frame; else built once, and again when they grow.
    every_frame: bool,
    /// A build was recorded since the last `fitted`.
    recorded: bool,
    /// A build held every entry (`fitted`): lists built once need no other.
    built: bool,
    pipelines: Vec<wgpu::ComputePipeline>,
    layout: wgpu::BindGroupLayout,
    bind_group: wgpu::BindGroup,
    params: wgpu::Buffer,
    bounds: wgpu::Buffer,
    counts: wgpu::Buffer,
    cursors: wgpu::Buffer,
    block_sums: wgpu::Buffer,
    status: wgpu::Buffer,
    status_readback: wgpu::Buffer,
}

impl RebuiltCellLists {
    /// The lists of the group whose volumes have `bounds` (by item), stored from item `first_item` of
    /// the structure, on `placement`'s grid, with room for `capacity` entries at first (the volumes
    /// as placed need at most `placement.visits`); labelled `label`, timed as `scope`.
    pub fn new(
        ctx: &GpuContext,
        label: &'static str,
        scope: &'static str,
        placement: ListPlacement,
        bounds: &[ListBounds],
        first_item: u32,
        capacity: u32,
    ) -> Result<Self> {
        let device = &ctx.device;
        let max_capacity = (ctx.limits.max_storage_buffer_binding_size / ENTRY_BYTES).min(u64::from(u32::MAX)) as u32;
        let cells = u64::from(placement.cells());
        for (what, bytes) in [("cells", cells * 8), ("entries", placement.visits * ENTRY_BYTES)] {
            ctx.check_storage_binding(&format!("{label} cell list {what}"), bytes)
                .map_err(|m| Error::InvalidScene(format!("{m}; use fewer {label}s, or build their BVH once on the CPU")))?;
        }
        let capacity = capacity.clamp(1, max_capacity);
        use wgpu::BufferUsages as U;
        let buffer = |name: &str, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("{label} cell list {name}")),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            })
        };
        let bounds_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(&format!("{label} cell list bounds")),
            contents: bytemuck::cast_slice(bounds),
            usage: U::STORAGE,
        });
        let params = buffer("params", std::mem::size_of::<CellListParams>() as u64, U::UNIFORM | U::COPY_DST);
        // Zeroed at creation; every frame's scan takes the counts and leaves them at zero.
        let counts = buffer("counts", cells * 4, U::STORAGE);
        let cursors = buffer("cursors", cells * 4, U::STORAGE);
        let ranges = buffer("ranges", cells * 8, U::STORAGE | U::COPY_SRC);
        let entries = buffer("entries", u64::from(capacity) * ENTRY_BYTES, U::STORAGE | U::COPY_SRC);
        let block_sums = buffer("block sums", cells.div_ceil(u64::from(BLOCK_CELLS)) * 4, U::STORAGE);
        let status = buffer("status", 8, U::STORAGE | U::COPY_SRC | U::COPY_DST);
        let status_readback = buffer("status readback", 8, U::MAP_READ | U::COPY_DST);

        let compute = wgpu::ShaderStages::COMPUTE;
        // Keep in sync with the bindings of `rebuilt_cell_lists.wgsl`.
        let mut layout_entries = vec![bindings::uniform(0, compute), bindings::storage_read(1, compute)];
        layout_entries.extend((2..=7).map(|b| bindings::storage_read_write(b, compute)));
        let layout = bindings::layout(device, "rebuilt cell lists", &layout_entries);
        let shader = ShaderDesc::new("accel/rebuilt_cell_lists.wgsl");
        let pipelines = PASSES.iter().map(|entry| bindings::compute_pipeline(device, entry, &shader, &[&layout])).collect::<Result<_>>()?;
        let bind_group =
            build_bind_group(ctx, &layout, [&params, &bounds_buffer, &counts, &ranges, &entries, &block_sums, &status, &cursors]);
        let mut lists = Self {
            ranges,
            entries,
            label,
            scope,
            placement,
            item_count: bounds.len() as u32,
            first_item,
            capacity,
            max_capacity,
            every_frame: true,
            recorded: false,
            built: false,
            pipelines,
            layout,
            bind_group,
            params,
            bounds: bounds_buffer,
            counts,
            cursors,
            block_sums,
            status,
            status_readback,
        };
        lists.bind(ctx);
        Ok(lists)
    }

    /// Entries the lists hold now.
    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// The header queries read before looking up a cell.
    pub fn header(&self) -> BvhNode {
        self.placement.header()
    }

    /// Writes the build's parameters and bind group for the current entries buffer.
    fn bind(&mut self, ctx: &GpuContext) {
        let p = &self.placement;
        let params = CellListParams {
            min: p.min.to_array(),
            item_count: self.item_count,
            cell_size: p.cell_size.to_array(),
            first_item: self.first_item,
            cells_per_unit: p.cells_per_unit.to_array(),
            capacity: self.capacity,
            dims: p.dims.to_array(),
            block_count: p.cells().div_ceil(BLOCK_CELLS),
            margin: p.margin().to_array(),
            row_threads: self.dispatch().0 * VOLUME_THREADS,
        };
        ctx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let buffers =
            [&self.params, &self.bounds, &self.counts, &self.ranges, &self.entries, &self.block_sums, &self.status, &self.cursors];
        self.bind_group = build_bind_group(ctx, &self.layout, buffers);
    }

    /// Workgroups of the per-volume passes, as (x, y): rows of at most 65535.
    fn dispatch(&self) -> (u32, u32) {
        let groups = self.item_count.div_ceil(VOLUME_THREADS).max(1);
        let x = groups.min(65535);
        (x, groups.div_ceil(x))
    }

    /// The lists of volumes that stay as placed: built by each `record` until a build has held every
    /// entry (`fitted`), then no more.
    pub fn built_once(self) -> Self {
        Self { every_frame: false, ..self }
    }

    /// Records this frame's build, timed as one scope, where the lists are rebuilt every frame or
    /// not built yet.
    pub fn record(&mut self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        if self.built && !self.every_frame {
            return;
        }
        self.recorded = true;
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.scope),
            timestamp_writes: timer.map(|t| t.compute_pass(self.scope)),
        });
        pass.set_bind_group(0, &self.bind_group, &[]);
        let blocks = self.placement.cells().div_ceil(BLOCK_CELLS);
        let (x, y) = self.dispatch();
        for (entry, pipeline) in PASSES.iter().zip(&self.pipelines) {
            pass.set_pipeline(pipeline);
            match *entry {
                "cell_lists_count" | "cell_lists_fill" => pass.dispatch_workgroups(x, y, 1),
                _ => pass.dispatch_workgroups(blocks, 1, 1),
            }
        }
    }

    /// Whether the lists held every entry the frames since the last call needed; if not, grows them
    /// (the caller renders those frames again, and rebinds `entries`).
    pub fn fitted(&mut self, ctx: &GpuContext) -> Result<bool> {
        let needed = readback::take_most_needed(ctx, &self.status, &self.status_readback)?;
        let recorded = std::mem::take(&mut self.recorded);
        if needed <= self.capacity {
            self.built |= recorded;
            return Ok(true);
        }
        if needed > self.max_capacity {
            return Err(Error::InvalidScene(format!(
                "the {} cell lists need {needed} entries ({} MiB), over this GPU's storage binding limit of {} MiB; \
                 use fewer or smaller {}s, or build their BVH once on the CPU",
                self.label,
                (u64::from(needed) * ENTRY_BYTES) >> 20,
                ctx.limits.max_storage_buffer_binding_size >> 20,
                self.label,
            )));
        }
        self.capacity = readback::grown_capacity(needed, self.max_capacity);
        self.entries = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("{} cell list entries", self.label)),
            size: u64::from(self.capacity) * ENTRY_BYTES,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        self.bind(ctx);
        Ok(false)
    }
}

/// The build's bind group, buffers in `rebuilt_cell_lists.wgsl`'s binding order.
fn build_bind_group(ctx: &GpuContext, layout: &wgpu::BindGroupLayout, buffers: [&wgpu::Buffer; 8]) -> wgpu::BindGroup {
    bindings::bind_group(&ctx.device, "rebuilt cell lists", layout, buffers.iter().map(|b| b.as_entire_binding()).collect())
}

#[cfg(test)]
mod tests {
    use std::mem::{offset_of, size_of};

    use super::*;
    use crate::plan::ListCells;

    #[test]
    fn list_records_match_their_wgsl_layouts() {
        let module = naga::front::wgsl::parse_str(
            &include_str!("rebuilt_cell_lists.wgsl").replace("#include \"accel/workgroup_scan.wgsl\"", include_str!("workgroup_scan.wgsl")),
        )
        .unwrap();
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let span = |name: &str| {
            let (handle, _) = module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name)).unwrap();
            layouter[handle].size as usize
        };
        assert_eq!(span("CellListParams"), size_of::<CellListParams>());
        assert_eq!(span("ListBounds"), size_of::<ListBounds>());
        assert_eq!((offset_of!(CellListParams, dims), offset_of!(CellListParams, row_threads)), (48, 76));
    }

    /// Cells the build visits for a volume with box `b`.
    fn cells_visited(grid: &ListPlacement, b: &Aabb) -> u64 {
        let margin = grid.margin();
        (grid.cell_of(b.max + margin) - grid.cell_of(b.min - margin) + UVec3::ONE).as_u64vec3().element_product()
    }

    fn lattice(count: u32, spacing: f32, half: f32) -> Vec<Aabb> {
        (0..count)
            .map(|i| {
                let c = Vec3::new((i % 10) as f32, ((i / 10) % 10) as f32, (i / 100) as f32) * spacing;
                Aabb::new(c - half, c + half)
            })
            .collect()
    }

    #[test]
    fn placements_take_the_coarsest_cells_whose_lists_stay_short() {
        // Sparse: 0.4 m boxes 3 m apart share no cell even at the coarsest, 1.5 box edges, nor at
        // the plan's finer start.
        let (coarse_edge, fine_edge) = (ListCells::Coarse.coarsest_edge(), ListCells::Fine.coarsest_edge());
        let sparse = lattice(1000, 3.0, 0.2);
        let grid = ListPlacement::for_boxes(&sparse, coarse_edge, true, u64::MAX).unwrap();
        assert_eq!(grid.dims, UVec3::splat((27.4f32 / 0.6).ceil() as u32));
        let fine_start = ListPlacement::for_boxes(&sparse, fine_edge, true, u64::MAX).unwrap();
        assert_eq!(fine_start.dims, UVec3::splat((27.4f32 / 0.2).ceil() as u32));
        assert!(sparse.iter().all(|b| cells_visited(&grid, b) <= 8));
        assert_eq!(grid.visits, sparse.iter().map(|b| cells_visited(&grid, b)).sum::<u64>());
        // A point's cell holds it.
        let p = Vec3::new(3.1, 6.05, 0.3);
        let cell = grid.cell_of(p).as_vec3();
        assert!((grid.min + cell * grid.cell_size).cmple(p).all() && (grid.min + (cell + 1.0) * grid.cell_size).cmpge(p).all());
        // Crowded: 4 m boxes 1 m apart, dozens in every coarse cell: finer cells.
        let crowded = lattice(1000, 1.0, 2.0);
        let fine = ListPlacement::for_boxes(&crowded, coarse_edge, true, u64::MAX).unwrap();
        assert!(fine.dims.x > (13.0f32 / 6.0).ceil() as u32, "{:?}", fine.dims);
        // One volume as large as the scene among small ones: coarser than any share, until it
        // visits few enough cells.
        let mut mixed = sparse.clone();
        mixed.push(Aabb::new(Vec3::ZERO, Vec3::splat(27.0)));
        let coarse = ListPlacement::for_boxes(&mixed, coarse_edge, true, u64::MAX).unwrap();
        assert!(mixed.iter().all(|b| cells_visited(&coarse, b) <= MAX_CELLS_PER_VOLUME));
        assert!(coarse.dims.x < grid.dims.x);
        // Built once, the large volume may visit more cells: the grid coarsens less.
        let once = ListPlacement::for_boxes(&mixed, coarse_edge, false, u64::MAX).unwrap();
        assert!(mixed.iter().all(|b| cells_visited(&once, b) <= MAX_CELLS_PER_VOLUME_ONCE));
        assert!(coarse.dims.x < once.dims.x && once.dims.x < grid.dims.x, "{:?} {:?} {:?}", coarse.dims, once.dims, grid.dims);
        // Flat groups get one cell across, and groups without finite bounds none.
        let flat: Vec<Aabb> = sparse.iter().map(|b| Aabb::new(b.min.with_y(0.0), b.max.with_y(0.0))).collect();
        let flat_grid = ListPlacement::for_boxes(&flat, coarse_edge, true, u64::MAX).unwrap();
        assert_eq!((flat_grid.dims.y, flat_grid.cells_per_unit.y), (1, 0.0));
        assert_eq!(ListPlacement::for_boxes(&[Aabb::new(Vec3::splat(f32::NEG_INFINITY), Vec3::ZERO)], coarse_edge, true, u64::MAX), None);
        assert_eq!(ListPlacement::for_boxes(&[], coarse_edge, true, u64::MAX), None);
        // Lists the device cannot bind are not placed: the group keeps its LBVH.
        assert_eq!(ListPlacement::for_boxes(&sparse, coarse_edge, true, 4096), None);
        // One volume: a cell and an entry of 8 bytes each, bounds of 96.
        assert!(ListPlacement::for_boxes(&sparse[..1], coarse_edge, true, 96).is_some());
        assert_eq!(ListPlacement::for_boxes(&sparse[..1], coarse_edge, true, 95), None);
        let d = grid.dims.x;
        assert_eq!(grid.header().skip, d | d << 10 | d << 20);
    }
}
