//! Cell lists: for a group of crowded volumes, a uniform grid over the group's bounds whose cells list
//! every volume that may reach them, so a point query reads its cell's list instead of walking the
//! group's BVH. Where decals crowd (100k of about a metre over Sponza: 23 boxes hold a surface point),
//! the walk is a long chain of dependent loads — nodes, then each leaf's decals, round after round — and
//! took half of what the decals cost; a cell's list is one range, shared out among a subgroup's lanes
//! in a few rounds (`shading/enumerate/decals_bvh_cells.wgsl`). The lists hold every volume
//! whose box meets the cell and whose exact shape may (a caller's conservative test), so the query
//! still finds every volume holding the point, and the caller's tight test decides.
//!
//! Built on the CPU with the group's BVH, in place of its entry grid (`entry_grid.rs`), for a structure
//! of one group placed once whose queries share leaves out (`VolumeStructure::cell_lists`), where the
//! lists fit a budget of words: cells five eighths of the volumes' typical size, coarsened until
//! they fit. `structure.rs` stores the cells and lists after the primitive indices and the grid's
//! placement in the header node before the group's root, which shading reads from the lone instance's
//! uniform; walks of other passes ignore the lists and start at the root.

use glam::{UVec3, Vec3};

use super::entry_grid::MAX_CELLS_PER_AXIS;
use super::Aabb;

/// Cell edge as a share of the volumes' median box edge. Finer cells list fewer volumes, but a
/// subgroup's lanes then fall in more cells, each taken in turn. For 100k ≈ 1 m decals over Sponza
/// (boxes of about 2 m), cells of 0.5 to 1 times that edge all shade much faster than the walk, and
/// five eighths fastest (benchmarks/LOG.md, topic 2).
const CELL_EDGE_PER_VOLUME: f32 = 0.625;
/// Lists longer than this on average, over the cells that list anything, take more rounds than the
/// walk they replace: such groups keep their entry grid.
const MAX_MEAN_LIST: f64 = 128.0;
/// Cells a try may visit per word of its budget (each volume visits the cells its box meets, which
/// its own test may reject): large, thin, tilted volumes among small ones would otherwise make a
/// build visit millions of cells each. 100k decals over Sponza visit about 3 per word.
const MAX_VISITS_PER_WORD: usize = 16;
/// Each try over the budget coarsens the cells by this much.
const COARSER: f32 = 1.25;
const MAX_TRIES: usize = 12;
/// Most words of cells and lists a structure's groups hold together (32 MiB), shared out by their
/// volumes: 100k ≈ 1 m decals over Sponza take 1.1M, 5.9M with cells of a quarter of their median
/// box edge.
pub const MAX_LIST_WORDS: usize = 1 << 23;

/// A sorted list's entries hold their rank from this bit up (`decals_bvh_cells.wgsl`: a decal's layer
/// with its index, so a kept decal is told hidden or not without reading its record). Keep in sync
/// with `cell_entry_decal` and `cell_entry_layer` there.
pub const RANK_SHIFT: u32 = 30;
pub const MAX_RANK: u32 = 3;

#[derive(Clone, Debug, PartialEq)]
pub struct CellLists {
    /// The grid's corner: the group's bounds' minimum.
    pub min: Vec3,
    /// Cells per unit length along each axis (0 along an axis the bounds are flat in).
    pub cells_per_unit: Vec3,
    pub dims: UVec3,
    /// Where each cell's list begins in `items`, x fastest, and one more: where the last one ends.
    pub starts: Vec<u32>,
    /// The volumes each cell lists, by their position in the group's items: ascending within a cell,
    /// or as [`Self::sort_lists_by_rank`] orders them.
    pub items: Vec<u32>,
    /// Each entry's rank, for lists sorted by rank; else empty.
    pub ranks: Vec<u32>,
}

impl CellLists {
    /// Lists over `boxes` (the group's volumes, by item position), each listed in the cells its box
    /// meets where `may_reach(item, cell)` also holds, within `budget_words` words of cells (two each)
    /// and lists. `None` for a group without finite bounds, one whose lists exceed the budget even
    /// with cells coarsened [`MAX_TRIES`] times, or one whose lists that fit are longer than
    /// [`MAX_MEAN_LIST`] on average.
    pub fn build(boxes: &[Aabb], may_reach: &dyn Fn(usize, &Aabb) -> bool, budget_words: usize) -> Option<CellLists> {
        let bounds = boxes.iter().fold(Aabb::EMPTY, |b, x| b.union(*x));
        let extent = bounds.max - bounds.min;
        if boxes.is_empty() || !(extent.is_finite() && bounds.min.is_finite()) {
            return None;
        }
        if extent.max_element() <= 0.0 {
            log::info!("no cell lists for {} volumes: they have no extent", boxes.len());
            return None;
        }
        let mut edges: Vec<f32> = boxes.iter().map(|b| (b.max - b.min).max_element()).collect();
        edges.sort_unstable_by(f32::total_cmp);
        let mut edge = (edges[edges.len() / 2] * CELL_EDGE_PER_VOLUME).max(extent.max_element() / MAX_CELLS_PER_AXIS as f32);
        for _ in 0..MAX_TRIES {
            let dims = (extent / edge).ceil().max(Vec3::ONE).min(Vec3::splat(MAX_CELLS_PER_AXIS as f32)).as_uvec3();
            let cells = (dims.x * dims.y * dims.z) as usize;
            if 2 * cells <= budget_words {
                if let Some(lists) = Self::fill(boxes, may_reach, bounds, dims, budget_words - 2 * cells) {
                    let listing = lists.starts.windows(2).filter(|w| w[1] > w[0]).count().max(1);
                    let mean = lists.items.len() as f64 / listing as f64;
                    if mean > MAX_MEAN_LIST {
                        log::info!("no cell lists for {} volumes: {mean:.0} a cell, over {MAX_MEAN_LIST}", boxes.len());
                        return None;
                    }
                    log::info!(
                        "cell lists for {} volumes: {}×{}×{} cells of {edge:.3}, {} entries, {:.1} a listing cell",
                        boxes.len(),
                        dims.x,
                        dims.y,
                        dims.z,
                        lists.items.len(),
                        mean
                    );
                    return Some(lists);
                }
            }
            edge *= COARSER;
        }
        log::info!("no cell lists for {} volumes: they exceed {budget_words} words, or visit too many cells", boxes.len());
        None
    }

    /// The lists on the grid of `dims` cells over `bounds`, if they take at most `budget` entries and
    /// visit at most [`MAX_VISITS_PER_WORD`] cells per entry of it.
    fn fill(boxes: &[Aabb], may_reach: &dyn Fn(usize, &Aabb) -> bool, bounds: Aabb, dims: UVec3, budget: usize) -> Option<CellLists> {
        let extent = bounds.max - bounds.min;
        let cells_per_unit = Vec3::select(extent.cmpgt(Vec3::ZERO), dims.as_vec3() / extent, Vec3::ZERO);
        let cell_size = Vec3::select(extent.cmpgt(Vec3::ZERO), extent / dims.as_vec3(), Vec3::ZERO);
        // Widened as the entry grids' cells are (`entry_grid.rs`): a point whose cell index rounds
        // into a neighbouring cell is still listed there.
        let magnitude = bounds.min.abs().max(bounds.max.abs());
        let margin = cell_size * 1e-3 + magnitude * 1e-5;
        let last = dims - UVec3::ONE;
        let cell_of = |p: Vec3| ((p - bounds.min) * cells_per_unit).floor().clamp(Vec3::ZERO, last.as_vec3()).as_uvec3();
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut visits = budget.saturating_mul(MAX_VISITS_PER_WORD);
        for (item, b) in boxes.iter().enumerate() {
            let (lo, hi) = (cell_of(b.min - margin), cell_of(b.max + margin));
            let cells = ((hi - lo + UVec3::ONE).as_u64vec3()).element_product();
            visits = visits.checked_sub(usize::try_from(cells).ok()?)?;
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let corner = bounds.min + UVec3::new(x, y, z).as_vec3() * cell_size;
                        let cell = Aabb::new(corner - margin, corner + cell_size + margin);
                        if may_reach(item, &cell) {
                            pairs.push(((z * dims.y + y) * dims.x + x, item as u32));
                        }
                    }
                }
            }
            if pairs.len() > budget {
                return None;
            }
        }
        let cells = (dims.x * dims.y * dims.z) as usize;
        let mut starts = vec![0u32; cells + 1];
        for &(cell, _) in &pairs {
            starts[cell as usize + 1] += 1;
        }
        for i in 0..cells {
            starts[i + 1] += starts[i];
        }
        // Pairs come item by item, so each cell's list fills in ascending item order.
        let mut next = starts.clone();
        let mut items = vec![0u32; pairs.len()];
        for (cell, item) in pairs {
            items[next[cell as usize] as usize] = item;
            next[cell as usize] += 1;
        }
        Some(CellLists { min: bounds.min, cells_per_unit, dims, starts, items, ranks: Vec::new() })
    }

    /// Orders each cell's list by `rank` of its items (up to [`MAX_RANK`]), highest first, and by item
    /// among equal ranks, and gives each entry its rank on the GPU: decals top layer first, the order
    /// in which shading folds layers and skips hidden ones (`decals_bvh_cells.wgsl`).
    pub fn sort_lists_by_rank(&mut self, rank: impl Fn(u32) -> u32) {
        for w in self.starts.windows(2) {
            self.items[w[0] as usize..w[1] as usize].sort_by_key(|&item| std::cmp::Reverse(rank(item)));
        }
        self.ranks = self.items.iter().map(|&item| rank(item).min(MAX_RANK)).collect();
    }

    /// The cell of `p` (clamped into the grid): the CPU twin of the WGSL lookup (`entry_grid_cell`).
    pub fn cell_of(&self, p: Vec3) -> usize {
        let last = (self.dims - UVec3::ONE).as_vec3();
        let cell = ((p - self.min) * self.cells_per_unit).floor().clamp(Vec3::ZERO, last).as_uvec3();
        ((cell.z * self.dims.y + cell.y) * self.dims.x + cell.x) as usize
    }

    /// The items listed for the cell holding `p`.
    pub fn list(&self, p: Vec3) -> &[u32] {
        let cell = self.cell_of(p);
        &self.items[self.starts[cell] as usize..self.starts[cell + 1] as usize]
    }

    /// Words of the primitive array the lists take on the GPU: two per cell, then the lists.
    pub fn gpu_len(&self) -> usize {
        2 * (self.starts.len() - 1) + self.items.len()
    }

    /// The lists as the GPU reads them from word `first_word` of the primitive array: per cell the
    /// words [start, end) of its list, then the lists, each item moved by `item_base` (the group's
    /// first item in the structure), its rank if sorted by rank in the top bits ([`RANK_SHIFT`]).
    /// Items and cells stay below 2²⁷ words (`entry_grid::CELL_COVER_OFFSET_MASK`).
    pub fn gpu_words(&self, item_base: u32, first_word: u32) -> Vec<u32> {
        let lists_at = first_word + 2 * (self.starts.len() - 1) as u32;
        let cells = self.starts.windows(2).flat_map(|w| [lists_at + w[0], lists_at + w[1]]);
        let rank = |entry: usize| self.ranks.get(entry).map_or(0, |&r| r << RANK_SHIFT);
        let entry_word = |(entry, &item): (usize, &u32)| {
            debug_assert!(item + item_base < 1 << RANK_SHIFT, "item {item} + {item_base} reaches the rank's bits");
            (item + item_base) | rank(entry)
        };
        cells.chain(self.items.iter().enumerate().map(entry_word)).collect()
    }

    /// `dims` packed as the GPU reads them: 10 bits per axis, x lowest.
    pub fn packed_dims(&self) -> u32 {
        self.dims.x | self.dims.y << 10 | self.dims.z << 20
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn boxes_around(points: &[Vec3], half: f32) -> Vec<Aabb> {
        points.iter().map(|&p| Aabb::new(p - half, p + half)).collect()
    }

    fn contains(b: &Aabb, p: Vec3) -> bool {
        p.cmpge(b.min).all() && p.cmple(b.max).all()
    }

    /// Every volume holding a point is in the list of the point's cell, for points anywhere in the
    /// bounds, on cell faces and on the volumes' faces.
    #[test]
    fn a_cell_lists_every_volume_that_holds_a_point_in_it() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let centres: Vec<Vec3> = (0..2000).map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * 40.0 - 20.0).collect();
        let boxes = boxes_around(&centres, 1.5);
        let lists = CellLists::build(&boxes, &|_, _| true, 1 << 22).unwrap();
        assert!(lists.dims.min_element() > 10, "{:?}", lists.dims);
        let mut points: Vec<Vec3> = (0..5_000).map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * 44.0 - 22.0).collect();
        points.extend(boxes.iter().take(500).flat_map(|b| [b.min, b.max, Vec3::new(b.min.x, b.max.y, b.min.z)]));
        let cell_face = lists.min + Vec3::ONE / lists.cells_per_unit * 7.0;
        points.push(cell_face);
        for p in points {
            let listed = lists.list(p);
            for (i, b) in boxes.iter().enumerate() {
                if contains(b, p) {
                    assert!(listed.binary_search(&(i as u32)).is_ok(), "volume {i} holds {p} but its cell does not list it");
                }
            }
        }
    }

    /// The caller's test prunes the lists: volumes only listed where it says they may reach.
    #[test]
    fn the_callers_test_keeps_volumes_out_of_cells_they_cannot_reach() {
        // Volume 0, a box of 8 m around the origin, as a sphere of radius 2 in it; forty boxes of a
        // metre beyond it make the cells 0.625 m, so the big box's corner cells are out of its reach.
        let mut centres = vec![Vec3::ZERO];
        centres.extend((0..40).map(|i| Vec3::new(10.0 + i as f32 * 0.5, 0.0, 0.0)));
        let mut boxes = boxes_around(&centres, 0.5);
        boxes[0] = Aabb::new(Vec3::splat(-4.0), Vec3::splat(4.0));
        let all = CellLists::build(&boxes, &|_, _| true, 1 << 20).unwrap();
        let sphere = |item: usize, cell: &Aabb| item != 0 || Vec3::ZERO.max(cell.min).min(cell.max).length() <= 2.0;
        let pruned = CellLists::build(&boxes, &sphere, 1 << 20).unwrap();
        assert!(pruned.items.len() < all.items.len());
        assert_eq!(pruned.list(Vec3::ZERO), &[0]);
        assert!(pruned.list(Vec3::splat(3.5)).is_empty());
        assert_eq!(all.list(Vec3::splat(3.5)), &[0]);
        assert_eq!(pruned.list(Vec3::new(10.0, 0.2, 0.2)), &[1, 2]);
    }

    /// Over budget, the cells coarsen until the lists fit; with no room at all there are none.
    #[test]
    fn lists_over_budget_get_coarser_cells_or_none() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
        let centres: Vec<Vec3> = (0..1000).map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * 20.0).collect();
        let boxes = boxes_around(&centres, 1.0);
        let fine = CellLists::build(&boxes, &|_, _| true, 1 << 24).unwrap();
        let budget = fine.gpu_len() / 3;
        let coarse = CellLists::build(&boxes, &|_, _| true, budget).unwrap();
        assert!(coarse.gpu_len() <= budget, "{} words over a budget of {budget}", coarse.gpu_len());
        assert!(coarse.dims.x < fine.dims.x);
        assert_eq!(CellLists::build(&boxes, &|_, _| true, 10), None);
        // Lists that fit but would be longer than a walk: none.
        let crowded = boxes_around(&vec![Vec3::ZERO; 400], 1.0);
        assert_eq!(CellLists::build(&crowded, &|_, _| true, 1 << 20), None);
        assert_eq!(CellLists::build(&[], &|_, _| true, 1 << 20), None);
        let infinite = [Aabb::new(Vec3::ZERO, Vec3::splat(f32::INFINITY))];
        assert_eq!(CellLists::build(&infinite, &|_, _| true, 1 << 20), None);
    }

    /// A flat group (decals on one plane): one cell across the flat axis, every point still found.
    #[test]
    fn flat_groups_get_one_cell_across() {
        let boxes = vec![
            Aabb::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 1.0, 1.0)),
            Aabb::new(Vec3::new(2.0, 0.0, 1.0), Vec3::new(3.0, 1.0, 1.0)),
        ];
        let lists = CellLists::build(&boxes, &|_, _| true, 1 << 20).unwrap();
        assert_eq!(lists.dims.z, 1);
        assert_eq!(lists.list(Vec3::new(0.5, 0.5, 1.0)), &[0]);
        assert_eq!(lists.list(Vec3::new(2.5, 0.5, 1.0)), &[1]);
    }

    #[test]
    fn gpu_words_name_each_cells_list_and_move_items() {
        let lists = CellLists {
            min: Vec3::ZERO,
            cells_per_unit: Vec3::ONE,
            dims: UVec3::new(3, 1, 1),
            starts: vec![0, 0, 2, 3],
            items: vec![4, 6, 5],
            ranks: Vec::new(),
        };
        assert_eq!(lists.list(Vec3::new(1.5, 0.5, 0.5)), &[4, 6]);
        assert_eq!(lists.gpu_len(), 9);
        assert_eq!(lists.gpu_words(100, 1000), vec![1006, 1006, 1006, 1008, 1008, 1009, 104, 106, 105]);
    }

    #[test]
    fn lists_sorted_by_rank_run_highest_first_in_item_order_and_carry_their_rank() {
        let mut lists = CellLists {
            min: Vec3::ZERO,
            cells_per_unit: Vec3::ONE,
            dims: UVec3::new(2, 1, 1),
            starts: vec![0, 5, 7],
            items: vec![1, 2, 3, 4, 5, 2, 6],
            ranks: Vec::new(),
        };
        let rank = |item: u32| [0, 1, 0, 3, 1, 0, 2][item as usize];
        lists.sort_lists_by_rank(rank);
        assert_eq!(lists.items, vec![3, 1, 4, 2, 5, 6, 2]);
        assert_eq!(lists.ranks, vec![3, 1, 1, 0, 0, 2, 0]);
        let words = lists.gpu_words(10, 0);
        let entries: Vec<(u32, u32)> = words[4..].iter().map(|w| (w & ((1 << RANK_SHIFT) - 1), w >> RANK_SHIFT)).collect();
        assert_eq!(entries, vec![(13, 3), (11, 1), (14, 1), (12, 0), (15, 0), (16, 2), (12, 0)]);
    }
}
