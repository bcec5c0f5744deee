//! Entry grids: where a point query starts in a group's BVH. A uniform grid over the group's bounds
//! names, per cell, the deepest node whose subtree holds every leaf whose box reaches the cell, and
//! the node after that subtree, where the query stops. A query then skips the levels above that node
//! — for small volumes, most of the tree: a cell reached by one leaf starts at that leaf, a cell
//! reached by none ends the query at once — and still finds exactly what a query from the root finds.
//!
//! Built on the CPU with the group's BVH (`BvhBuild::CpuOnce`); groups rebuilt on the GPU start at
//! their root. `structure.rs` stores the cells after the primitive indices and the grid's placement in
//! a header node before the group's root (flagged in the instances' `blas_root`);
//! `volume_query.wgsl` looks the cell up as [`EntryGrid::start`] does here.

use glam::{UVec3, Vec3};

use super::{Aabb, Bvh, END};

/// Groups with fewer primitives are queried from the root: their trees are a few levels deep.
pub const MIN_PRIMITIVES: usize = 16;
/// Cells per primitive the grids aim at, and the most a structure's grids hold together (16 MiB of
/// cells). Finer cells start more queries at a leaf or end them at once: 28k small lights shade in
/// 0.244, 0.228, 0.213, 0.200, 0.195 and 0.188 ms with 2, 4, 8, 16, 32 and 64 cells per light on the
/// H100, while ≈ 1 m decals, which overlap every cell anyway, shade alike (BENCHMARKS.md).
const CELLS_PER_PRIMITIVE: f64 = 32.0;
const MAX_CELLS: f64 = (1 << 21) as f64;

/// Cells per primitive for the grids of a structure whose CPU-built groups hold `primitives` in all:
/// [`CELLS_PER_PRIMITIVE`], fewer where the grids would exceed [`MAX_CELLS`] together (a million
/// volumes get two each, however they are grouped).
pub fn cells_per_primitive(primitives: usize) -> f64 {
    (MAX_CELLS / primitives.max(1) as f64).min(CELLS_PER_PRIMITIVE)
}
/// Cells per axis fit 10 bits each in the header node's `skip` (`structure.rs`, `entry_grid_header`).
pub const MAX_CELLS_PER_AXIS: u32 = 1023;

#[derive(Clone, Debug, PartialEq)]
pub struct EntryGrid {
    /// The grid's corner: the group's bounds' minimum.
    pub min: Vec3,
    /// Cells per unit length along each axis (0 along an axis the bounds are flat in).
    pub cells_per_unit: Vec3,
    pub dims: UVec3,
    /// Per cell, x fastest: (the node to start at, the node to stop at), node indices of the BVH;
    /// ([`END`], [`END`]) where no leaf reaches the cell.
    pub cells: Vec<[u32; 2]>,
}

impl EntryGrid {
    /// The grid for `bvh`, built over `aabbs`, with about `cells_per_primitive` cells per primitive
    /// ([`cells_per_primitive`]), or `None` when it has fewer than [`MIN_PRIMITIVES`] primitives or
    /// its bounds are not finite.
    pub fn build(bvh: &Bvh, aabbs: &[Aabb], cells_per_primitive: f64) -> Option<EntryGrid> {
        if bvh.primitive_indices.len() < MIN_PRIMITIVES {
            return None;
        }
        let bounds = bvh.nodes[0].bounds();
        let extent = bounds.max - bounds.min;
        if !(extent.is_finite() && bounds.min.is_finite()) {
            return None;
        }
        let dims = grid_dims(extent, (bvh.primitive_indices.len() as f64 * cells_per_primitive).min(MAX_CELLS));
        let cells_per_unit = Vec3::select(extent.cmpgt(Vec3::ZERO), dims.as_vec3() / extent, Vec3::ZERO);
        let cell_size = Vec3::select(extent.cmpgt(Vec3::ZERO), extent / dims.as_vec3(), Vec3::ZERO);
        // Cells are widened before they are matched with boxes, so a point whose cell index rounds
        // into a neighbouring cell is still covered there: by a thousandth of a cell, and by about
        // 80 float steps of the coordinates' magnitude, which bounds the rounding of the lookup.
        let magnitude = bounds.min.abs().max(bounds.max.abs());
        let margin = cell_size * 1e-3 + magnitude * 1e-5;
        let mut cells = Vec::with_capacity((dims.x * dims.y * dims.z) as usize);
        for z in 0..dims.z {
            for y in 0..dims.y {
                for x in 0..dims.x {
                    let corner = bounds.min + UVec3::new(x, y, z).as_vec3() * cell_size;
                    let cell = Aabb::new(corner - margin, corner + cell_size + margin);
                    cells.push(entry_for(bvh, aabbs, &cell));
                }
            }
        }
        Some(EntryGrid { min: bounds.min, cells_per_unit, dims, cells })
    }

    /// The cell of `p` (clamped into the grid): the CPU twin of the WGSL lookup.
    pub fn cell_of(&self, p: Vec3) -> usize {
        let last = (self.dims - UVec3::ONE).as_vec3();
        let cell = ((p - self.min) * self.cells_per_unit).floor().clamp(Vec3::ZERO, last).as_uvec3();
        ((cell.z * self.dims.y + cell.y) * self.dims.x + cell.x) as usize
    }

    /// (start, stop) of a query at `p`.
    pub fn start(&self, p: Vec3) -> [u32; 2] {
        self.cells[self.cell_of(p)]
    }

    /// `dims` packed as the GPU reads them: 10 bits per axis, x lowest.
    pub fn packed_dims(&self) -> u32 {
        self.dims.x | self.dims.y << 10 | self.dims.z << 20
    }
}

/// Cells per axis, proportional to the extent, about `target` in all; flat axes get one.
fn grid_dims(extent: Vec3, target: f64) -> UVec3 {
    let axes: Vec<f64> = extent.to_array().iter().map(|&e| f64::from(e)).filter(|&e| e > 0.0).collect();
    if axes.is_empty() {
        return UVec3::ONE;
    }
    // Cells of edge `edge` along the non-flat axes: their counts multiply to about `target`.
    let volume: f64 = axes.iter().product();
    let edge = (volume / target).powf(1.0 / axes.len() as f64);
    let per_axis = |e: f32| if e > 0.0 { (f64::from(e) / edge).round().clamp(1.0, f64::from(MAX_CELLS_PER_AXIS)) as u32 } else { 1 };
    UVec3::new(per_axis(extent.x), per_axis(extent.y), per_axis(extent.z))
}

fn overlaps(a: &Aabb, b: &Aabb) -> bool {
    a.min.cmple(b.max).all() && b.min.cmple(a.max).all()
}

/// The lowest node whose subtree holds every primitive whose box reaches the cell, and the node
/// after its subtree; ([`END`], [`END`]) when no primitive reaches it.
fn entry_for(bvh: &Bvh, aabbs: &[Aabb], cell: &Aabb) -> [u32; 2] {
    match lowest_common_ancestor(bvh, aabbs, 0, cell) {
        Some(n) => [n, bvh.nodes[n as usize].skip],
        None => [END, END],
    }
}

/// Of the leaves under node `n` with a primitive whose box reaches the cell: their lowest common
/// ancestor, if any. Visits the nodes whose boxes reach the cell, as a box query would.
fn lowest_common_ancestor(bvh: &Bvh, aabbs: &[Aabb], n: u32, cell: &Aabb) -> Option<u32> {
    let node = &bvh.nodes[n as usize];
    if !overlaps(&node.bounds(), cell) {
        return None;
    }
    let Some((first, second)) = bvh.children(node) else {
        let primitives = &bvh.primitive_indices[node.leaf_range()];
        return primitives.iter().any(|&i| overlaps(&aabbs[i as usize], cell)).then_some(n);
    };
    match (lowest_common_ancestor(bvh, aabbs, first, cell), lowest_common_ancestor(bvh, aabbs, second, cell)) {
        (Some(_), Some(_)) => Some(n),
        (one, None) | (None, one) => one,
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    use super::*;
    use crate::accel::bvh::tests::{brute_force, random_boxes, random_points};

    fn query_from_grid(bvh: &Bvh, grid: &EntryGrid, boxes: &[Aabb], p: Vec3) -> Vec<u32> {
        let mut found = Vec::new();
        bvh.query_point_between(boxes, p, grid.start(p), |i| found.push(i));
        found.sort_unstable();
        found
    }

    /// Random sets mixing flat, point, duplicate and 1e-30 to 1e30 boxes, at random points and points
    /// on (and one float step beside) the boxes' faces: the query from the cell finds exactly the
    /// boxes holding the point, each once.
    #[test]
    fn queries_from_the_grid_find_exactly_the_boxes_holding_the_point() {
        let mut rng = Pcg64::seed_from_u64(0xce11);
        for &(size, sets, points) in &[(16, 60, 300), (100, 60, 500), (1000, 20, 1000), (20_000, 3, 3000)] {
            for _ in 0..sets {
                let boxes = random_boxes(&mut rng, size);
                let bvh = Bvh::build(&boxes).unwrap();
                let Some(grid) = EntryGrid::build(&bvh, &boxes, CELLS_PER_PRIMITIVE) else {
                    // Only non-finite bounds (boxes spanning ±1e30 along an axis overflow the extent) go without.
                    assert!(!(bvh.nodes[0].bounds().max - bvh.nodes[0].bounds().min).is_finite());
                    continue;
                };
                assert_eq!(grid.cells.len(), grid.dims.element_product() as usize);
                for p in random_points(&mut rng, &boxes, points) {
                    assert_eq!(query_from_grid(&bvh, &grid, &boxes, p), brute_force(&boxes, p), "at {p:?} ({size} boxes)");
                }
            }
        }
    }

    /// Small boxes scattered far apart, as lights over a scene: most cells are reached by no box or
    /// one leaf, so queries start at a leaf or end at once.
    #[test]
    fn sparse_small_boxes_start_at_leaves() {
        let mut rng = Pcg64::seed_from_u64(7);
        let boxes: Vec<Aabb> = (0..5000)
            .map(|_| {
                let c = Vec3::new(rng.random_range(0.0..100.0), rng.random_range(0.0..10.0), rng.random_range(0.0..50.0)) + 5000.0;
                Aabb::new(c - 0.2, c + 0.2)
            })
            .collect();
        let bvh = Bvh::build(&boxes).unwrap();
        let grid = EntryGrid::build(&bvh, &boxes, CELLS_PER_PRIMITIVE).unwrap();
        let cells = grid.cells.len() as f64;
        let aim = 5000.0 * CELLS_PER_PRIMITIVE;
        assert!((aim / 2.0..=aim * 2.0).contains(&cells), "{cells} cells for 5000 boxes");
        let empty = grid.cells.iter().filter(|c| c[0] == END).count() as f64;
        let leaves = grid.cells.iter().filter(|c| c[0] != END && bvh.nodes[c[0] as usize].is_leaf()).count() as f64;
        assert!(empty / cells > 0.3 && (empty + leaves) / cells > 0.6, "{empty} empty and {leaves} leaf cells of {cells}");
        for p in random_points(&mut rng, &boxes, 5000) {
            assert_eq!(query_from_grid(&bvh, &grid, &boxes, p), brute_force(&boxes, p), "at {p:?}");
        }
    }

    #[test]
    fn a_structures_grids_share_a_budget_of_cells() {
        assert_eq!(cells_per_primitive(28_000), CELLS_PER_PRIMITIVE);
        assert_eq!(cells_per_primitive(1 << 20), 2.0);
        assert_eq!(cells_per_primitive(0), CELLS_PER_PRIMITIVE);
        // 2,000 groups of 500 volumes: each grid's share, not each grid's own cap.
        assert!(cells_per_primitive(1_000_000) * 1_000_000.0 <= MAX_CELLS);
    }

    #[test]
    fn small_or_unbounded_sets_have_no_grid() {
        let boxes: Vec<Aabb> = (0..MIN_PRIMITIVES - 1).map(|i| Aabb::new(Vec3::splat(i as f32), Vec3::splat(i as f32 + 0.5))).collect();
        assert!(EntryGrid::build(&Bvh::build(&boxes).unwrap(), &boxes, CELLS_PER_PRIMITIVE).is_none());
        let mut flat: Vec<Aabb> = (0..100).map(|i| Aabb::new(Vec3::new(i as f32, 0.0, 0.0), Vec3::new(i as f32 + 0.5, 0.0, 1.0))).collect();
        let grid = EntryGrid::build(&Bvh::build(&flat).unwrap(), &flat, CELLS_PER_PRIMITIVE).unwrap();
        assert_eq!(grid.dims.y, 1, "flat along y: one cell");
        flat.push(Aabb::new(Vec3::splat(-3e38), Vec3::splat(3e38)));
        assert!(EntryGrid::build(&Bvh::build(&flat).unwrap(), &flat, CELLS_PER_PRIMITIVE).is_none(), "an extent that overflows");
    }
}
