//! Entry grids: where a point query starts in a group's BVH. A uniform grid over the group's bounds
//! names, per cell, the subtrees that hold every leaf whose box reaches the cell: the deepest node
//! whose subtree holds them all, or, where those leaves lie in a few separate parts of the tree, up to
//! [`MAX_COVER`] smaller subtrees (the cell's *cover*), each with the node after it, where its walk
//! stops. A query then skips the levels above them and the parts of the tree between them — for
//! small volumes, most of the tree: a cell reached by one leaf starts at that leaf, a cell reached by
//! a few walks just those, a cell reached by none ends the query at once — and still finds exactly
//! what a query from the root finds.
//!
//! Built on the CPU with the group's BVH (`BvhBuild::CpuOnce`); groups rebuilt on the GPU get a
//! coarser grid of single subtrees, rebuilt after each build (`rebuilt_grid.rs`). `structure.rs` stores the cells after the primitive indices and the grid's placement in
//! a header node before the group's root (flagged in the instances' `blas_root`);
//! `volume_query.wgsl` looks the cell up and walks its cover as [`EntryGrid::cover`] says here.

use std::collections::HashMap;

use glam::{UVec3, Vec3};

use super::{Aabb, Bvh, END};

/// Groups with fewer primitives are queried from the root: their trees are a few levels deep.
pub const MIN_PRIMITIVES: usize = 16;
/// Cells per primitive the grids aim at, the fewest a structure's grids get, and the most they hold
/// together (16 MiB of cells). Finer cells start more queries at a leaf or end them at once: small
/// lights shade faster with every doubling of cells per light up to 64, while ≈ 1 m decals, which
/// overlap every cell anyway, shade alike. A few sparse volumes get far more cells each, so that 100
/// small decals do not leave cells a metre wide, where many fragments walk a subtree to find nothing
/// (benchmarks/LOG.md, topics 3 and 4).
const CELLS_PER_PRIMITIVE: f64 = 64.0;
const MIN_CELLS: f64 = (1 << 18) as f64;
const MAX_CELLS: f64 = (1 << 21) as f64;

/// Most words of covers a structure's grids hold together (32 MiB). 100k ≈ 1 m decals over Sponza
/// take 6.4M: a million cells name covers, 333k of them different.
const MAX_COVER_WORDS: f64 = (1 << 23) as f64;

/// What a structure's grids may hold, per primitive of the group a grid is built for: a share of
/// [`MAX_CELLS`] cells and of [`MAX_COVER_WORDS`].
#[derive(Clone, Copy, Debug)]
pub struct GridBudget {
    pub cells_per_primitive: f64,
    pub cover_words_per_primitive: f64,
    /// Nodes the build may visit per cell on average before it gives up on the grid.
    pub visits_per_cell: usize,
}

impl GridBudget {
    /// For a structure whose CPU-built groups hold `primitives` in all: [`CELLS_PER_PRIMITIVE`] cells
    /// each, more where the grids would hold fewer than [`MIN_CELLS`] together, fewer where they
    /// would exceed [`MAX_CELLS`] (a million volumes get two each, however they are grouped), and an
    /// equal share of the cover words.
    pub fn for_structure(primitives: usize) -> Self {
        let primitives = primitives.max(1) as f64;
        GridBudget {
            cells_per_primitive: (primitives * CELLS_PER_PRIMITIVE).clamp(MIN_CELLS, MAX_CELLS) / primitives,
            cover_words_per_primitive: MAX_COVER_WORDS / primitives,
            visits_per_cell: MAX_VISITS_PER_CELL,
        }
    }
}
/// Cells per axis fit 10 bits each in the header node's `skip` (`structure.rs`, `GroupGrid::gpu_words`).
pub const MAX_CELLS_PER_AXIS: u32 = 1023;

/// Nodes the grid's build may visit per cell, on average, before it gives up on the grid (see
/// [`EntryGrid::build`]): over Sponza, 100 small decals visit 10 per cell, 100k ≈ 1 m decals 54, 1M
/// 0.3 m decals 34, 28k lights of ≈ 1.7 m 108. 300k lights scattered over the one-metre Box visit
/// more than 256 per cell over 2M cells: tens of seconds of building, for cells so crowded that
/// their queries would start high in the tree anyway.
const MAX_VISITS_PER_CELL: usize = 256;

/// Most subtrees a cell's cover names. Each one spares the walk the nodes above and beside it, and
/// costs a (start, stop) pair in the grid's covers.
pub const MAX_COVER: usize = 16;
/// Set in a cell's second word when it names a cover of several subtrees: bits 27–30 hold their
/// count − 1, bits 0–26 where its (start, stop) pairs begin in [`EntryGrid::covers`]. Keep in sync
/// with `ENTRY_CELL_COVER` in `accel/bvh_types.wgsl`.
pub const CELL_COVER: u32 = 1 << 31;
const CELL_COVER_COUNT_SHIFT: u32 = 27;
/// Primitive words a structure's grids can name covers within.
pub const CELL_COVER_OFFSET_MASK: u32 = (1 << CELL_COVER_COUNT_SHIFT) - 1;

#[derive(Clone, Debug, PartialEq)]
pub struct EntryGrid {
    /// The grid's corner: the group's bounds' minimum.
    pub min: Vec3,
    /// Cells per unit length along each axis (0 along an axis the bounds are flat in).
    pub cells_per_unit: Vec3,
    pub dims: UVec3,
    /// Per cell, x fastest: (the node to start at, the node to stop at), node indices of the BVH;
    /// ([`END`], [`END`]) where no leaf reaches the cell; (the first subtree's root, [`CELL_COVER`] |
    /// its count and place in `covers`) where the cell names a cover of several subtrees.
    pub cells: Vec<[u32; 2]>,
    /// The covers' (start, stop) pairs, in node order within each cover; cells with the same cover
    /// share it.
    pub covers: Vec<u32>,
}

impl EntryGrid {
    /// The grid for `bvh`, built over `aabbs`, within `budget` for its primitives: covers of up to
    /// [`MAX_COVER`] subtrees, or half as many until they fit (one: the lowest common ancestors
    /// alone). `None` when it has fewer than [`MIN_PRIMITIVES`] primitives, its bounds are not
    /// finite, or its volumes crowd so densely that building it would visit more than
    /// `budget.visits_per_cell` nodes per cell ([`MAX_VISITS_PER_CELL`]; queries then start at the
    /// root, as they would from its cells anyway).
    pub fn build(bvh: &Bvh, aabbs: &[Aabb], budget: GridBudget) -> Option<EntryGrid> {
        if bvh.primitive_indices.len() < MIN_PRIMITIVES {
            return None;
        }
        let bounds = bvh.nodes[0].bounds();
        let extent = bounds.max - bounds.min;
        if !(extent.is_finite() && bounds.min.is_finite()) {
            return None;
        }
        let primitives = bvh.primitive_indices.len() as f64;
        let dims = grid_dims(extent, (primitives * budget.cells_per_primitive).min(MAX_CELLS));
        let cells_per_unit = Vec3::select(extent.cmpgt(Vec3::ZERO), dims.as_vec3() / extent, Vec3::ZERO);
        let cell_size = Vec3::select(extent.cmpgt(Vec3::ZERO), extent / dims.as_vec3(), Vec3::ZERO);
        // Cells are widened before they are matched with boxes, so a point whose cell index rounds
        // into a neighbouring cell is still covered there: by a thousandth of a cell, and by about
        // 80 float steps of the coordinates' magnitude, which bounds the rounding of the lookup.
        let magnitude = bounds.min.abs().max(bounds.max.abs());
        let margin = cell_size * 1e-3 + magnitude * 1e-5;
        let cell_box = |x: u32, y: u32, z: u32| {
            let corner = bounds.min + UVec3::new(x, y, z).as_vec3() * cell_size;
            Aabb::new(corner - margin, corner + cell_size + margin)
        };
        let cover_words = (primitives * budget.cover_words_per_primitive).min(f64::from(CELL_COVER_OFFSET_MASK));
        // Each try walks every cell's part of the tree again; grids over budget at 16 are rare (100k
        // ≈ 1 m decals take 6.4M of the 8M words, 1M 5 cm decals 1.7M).
        let mut max_cover = MAX_COVER;
        loop {
            // A sixteenth of the cells' allowance up front, then each cell's as it comes: a grid of
            // dense volumes runs out after that sixteenth, whichever cells come first.
            let mut visits = ((dims.x * dims.y * dims.z) as usize / 16 + 1).saturating_mul(budget.visits_per_cell);
            let (cells, covers) = cells_and_covers(bvh, aabbs, dims, &cell_box, max_cover, (&mut visits, budget.visits_per_cell));
            if visits == 0 {
                // Volumes this dense reach most of the tree from every cell: a grid would start
                // queries near the root anyway, after seconds of building.
                log::info!("no entry grid for {} volumes: their cells reach too much of the tree", bvh.primitive_indices.len());
                return None;
            }
            if covers.len() as f64 <= cover_words || max_cover == 1 {
                return Some(EntryGrid { min: bounds.min, cells_per_unit, dims, cells, covers });
            }
            max_cover /= 2;
        }
    }

    /// The cell of `p` (clamped into the grid): the CPU twin of the WGSL lookup.
    pub fn cell_of(&self, p: Vec3) -> usize {
        let last = (self.dims - UVec3::ONE).as_vec3();
        let cell = ((p - self.min) * self.cells_per_unit).floor().clamp(Vec3::ZERO, last).as_uvec3();
        ((cell.z * self.dims.y + cell.y) * self.dims.x + cell.x) as usize
    }

    /// The (start, stop) pairs of the subtrees a query at `p` walks, in node order.
    pub fn cover(&self, p: Vec3) -> Vec<[u32; 2]> {
        match self.cells[self.cell_of(p)] {
            [start, _] if start == END => Vec::new(),
            [start, stop] if stop & CELL_COVER == 0 => vec![[start, stop]],
            [_, cover] => {
                let count = ((cover & !CELL_COVER) >> CELL_COVER_COUNT_SHIFT) as usize + 1;
                let offset = (cover & CELL_COVER_OFFSET_MASK) as usize;
                self.covers[offset..offset + 2 * count].chunks(2).map(|pair| [pair[0], pair[1]]).collect()
            }
        }
    }

    /// Words of the primitive array the grid takes on the GPU: its cells, then its covers.
    pub fn gpu_len(&self) -> usize {
        2 * self.cells.len() + self.covers.len()
    }

    /// The grid as the GPU reads it from word `first_word` of the primitive array: the cells, then the
    /// covers, with node indices moved by `node_base` ([`END`] stays) and each cover's place by where
    /// the covers land. The covers must end within the 27 bits of a cell's offset.
    pub fn gpu_words(&self, node_base: u32, first_word: u32) -> Vec<u32> {
        let node = |n: u32| if n == END { n } else { n + node_base };
        let covers_at = first_word + 2 * self.cells.len() as u32;
        assert!(covers_at as usize + self.covers.len() <= CELL_COVER_OFFSET_MASK as usize, "covers past the 27 bits of a cell's offset");
        let cells = self.cells.iter().flat_map(|&[start, stop]| {
            let stop = if start != END && stop & CELL_COVER != 0 {
                (stop & !CELL_COVER_OFFSET_MASK) | ((stop & CELL_COVER_OFFSET_MASK) + covers_at)
            } else {
                node(stop)
            };
            [node(start), stop]
        });
        cells.chain(self.covers.iter().map(|&n| node(n))).collect()
    }

    /// `dims` packed as the GPU reads them: 10 bits per axis, x lowest.
    pub fn packed_dims(&self) -> u32 {
        self.dims.x | self.dims.y << 10 | self.dims.z << 20
    }
}

/// Cells per axis, proportional to the extent, about `target` in all; flat axes get one.
pub(super) fn grid_dims(extent: Vec3, target: f64) -> UVec3 {
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

/// Every cell's words (x fastest) and the covers they name, with covers of up to `max_cover` subtrees;
/// `cell_box` gives a cell's box from its coordinates.
fn cells_and_covers(
    bvh: &Bvh,
    aabbs: &[Aabb],
    dims: UVec3,
    cell_box: &dyn Fn(u32, u32, u32) -> Aabb,
    max_cover: usize,
    (visits, visits_per_cell): (&mut usize, usize),
) -> (Vec<[u32; 2]>, Vec<u32>) {
    let mut cells = Vec::with_capacity((dims.x * dims.y * dims.z) as usize);
    let mut covers = Vec::new();
    let mut shared: HashMap<Vec<u32>, u32> = HashMap::new();
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                *visits = visits.saturating_add(visits_per_cell);
                let pairs: Vec<u32> =
                    cover(bvh, aabbs, &cell_box(x, y, z), max_cover, visits).into_iter().flat_map(|n| [n, subtree_end(bvh, n)]).collect();
                if *visits == 0 {
                    return (cells, covers);
                }
                cells.push(match pairs.len() {
                    0 => [END, END],
                    2 => [pairs[0], pairs[1]],
                    len => {
                        let first = pairs[0];
                        let offset = *shared.entry(pairs).or_insert_with_key(|pairs| {
                            covers.extend_from_slice(pairs);
                            (covers.len() - pairs.len()) as u32
                        });
                        [first, CELL_COVER | ((len / 2 - 1) as u32) << CELL_COVER_COUNT_SHIFT | offset]
                    }
                });
            }
        }
    }
    (cells, covers)
}

/// The subtrees that hold every leaf with a primitive whose box reaches the cell, in node order: none,
/// the leaves' lowest common ancestor, or — expanding the largest subtree into its children's, as long
/// as there are at most `max_cover` — the separate parts of the tree they lie in.
fn cover(bvh: &Bvh, aabbs: &[Aabb], cell: &Aabb, max_cover: usize, visits: &mut usize) -> Vec<u32> {
    let mut reached = Vec::new();
    let Some(root) = reached_tree(bvh, aabbs, 0, cell, &mut reached, visits) else { return Vec::new() };
    // Entries of `reached`: one per subtree root, in node order; expanded while they fit.
    let mut parts = vec![root];
    while parts.len() < max_cover {
        let span = |r: &Reached| subtree_end(bvh, r.node) - r.node;
        let widest = (0..parts.len()).filter(|&i| reached[parts[i]].children.is_some()).max_by_key(|&i| span(&reached[parts[i]]));
        let Some(i) = widest else { break };
        let (first, second) = reached[parts[i]].children.expect("filtered on children");
        parts.splice(i..=i, [first, second]);
    }
    parts.into_iter().map(|i| reached[i].node).collect()
}

/// The node after `n`'s subtree, where a walk of it stops: its `skip`, or the node count for a subtree
/// ending the tree, as END would read as CELL_COVER (the walk reaches END first either way).
fn subtree_end(bvh: &Bvh, n: u32) -> u32 {
    bvh.nodes[n as usize].skip.min(bvh.nodes.len() as u32)
}

/// A node of the BVH whose subtree holds leaves reaching a cell, with the same for its children when
/// both hold some (a chain of nodes with one such child is skipped down to where it branches).
struct Reached {
    node: u32,
    children: Option<(usize, usize)>,
}

/// Of the leaves under node `n` with a primitive whose box reaches the cell: the tree of where they
/// branch, pushed onto `reached`, and its root's place there. Visits the nodes whose boxes reach the
/// cell, as a box query would, while `visits` lasts (each takes one; at 0 it finds nothing more).
fn reached_tree(bvh: &Bvh, aabbs: &[Aabb], n: u32, cell: &Aabb, reached: &mut Vec<Reached>, visits: &mut usize) -> Option<usize> {
    if *visits == 0 {
        return None;
    }
    *visits -= 1;
    let node = &bvh.nodes[n as usize];
    if !overlaps(&node.bounds(), cell) {
        return None;
    }
    let Some((first, second)) = bvh.children(node) else {
        let primitives = &bvh.primitive_indices[node.leaf_range()];
        if !primitives.iter().any(|&i| overlaps(&aabbs[i as usize], cell)) {
            return None;
        }
        reached.push(Reached { node: n, children: None });
        return Some(reached.len() - 1);
    };
    match (reached_tree(bvh, aabbs, first, cell, reached, visits), reached_tree(bvh, aabbs, second, cell, reached, visits)) {
        (Some(a), Some(b)) => {
            reached.push(Reached { node: n, children: Some((a, b)) });
            Some(reached.len() - 1)
        }
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
        for part in grid.cover(p) {
            bvh.query_point_between(boxes, p, part, |i| found.push(i));
        }
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
                // With room for covers, and (the smaller sets) with none: each cell its lowest common
                // ancestor. Cells at the rate per box, not the floor small sets get: finer cells of
                // the same lookup, which would make this test four times slower.
                // No limit on the build's visits: huge boxes among small ones crowd many cells.
                let budget =
                    GridBudget { cells_per_primitive: CELLS_PER_PRIMITIVE, visits_per_cell: usize::MAX, ..GridBudget::for_structure(size) };
                let budgets = [budget, GridBudget { cover_words_per_primitive: 0.0, ..budget }];
                for &budget in &budgets[..if size <= 1000 { 2 } else { 1 }] {
                    let Some(grid) = EntryGrid::build(&bvh, &boxes, budget) else {
                        // Only non-finite bounds (boxes spanning ±1e30 along an axis overflow the extent) go without.
                        assert!(!(bvh.nodes[0].bounds().max - bvh.nodes[0].bounds().min).is_finite());
                        continue;
                    };
                    assert_eq!(grid.cells.len(), grid.dims.element_product() as usize);
                    assert!(budget.cover_words_per_primitive > 0.0 || grid.covers.is_empty());
                    for p in random_points(&mut rng, &boxes, points) {
                        assert_eq!(query_from_grid(&bvh, &grid, &boxes, p), brute_force(&boxes, p), "at {p:?} ({size} boxes)");
                    }
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
        let grid = EntryGrid::build(&bvh, &boxes, GridBudget::for_structure(boxes.len())).unwrap();
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

    /// Heavily overlapping boxes in clumps, as decals on walls: cells reached by leaves in separate
    /// parts of the tree name covers, and a walk from them visits fewer nodes than one from the
    /// leaves' lowest common ancestor, finding the same boxes.
    #[test]
    fn covers_walk_fewer_nodes_than_one_subtree() {
        let mut rng = Pcg64::seed_from_u64(11);
        let boxes: Vec<Aabb> = (0..4000)
            .map(|_| {
                let c = Vec3::new(rng.random_range(0.0..40.0), rng.random_range(0.0..10.0), rng.random_range(0.0..20.0));
                Aabb::new(c - 0.5, c + 0.5)
            })
            .collect();
        let bvh = Bvh::build(&boxes).unwrap();
        let with = EntryGrid::build(&bvh, &boxes, GridBudget::for_structure(boxes.len())).unwrap();
        let without =
            EntryGrid::build(&bvh, &boxes, GridBudget { cover_words_per_primitive: 0.0, ..GridBudget::for_structure(boxes.len()) })
                .unwrap();
        assert!(!with.covers.is_empty() && without.covers.is_empty());
        let visits = |grid: &EntryGrid, p: Vec3| -> usize {
            // The GPU walk's visits: every node from each subtree's start until it reaches its stop.
            let mut count = 0;
            for [start, stop] in grid.cover(p) {
                let mut n = start;
                while n != stop && n != END {
                    count += 1;
                    let node = &bvh.nodes[n as usize];
                    n = if node.bounds().contains(p) && !node.is_leaf() { node.entry } else { node.skip };
                }
            }
            count
        };
        let points = random_points(&mut rng, &boxes, 3000);
        let (fewer, more): (usize, usize) =
            points.iter().map(|&p| (visits(&with, p), visits(&without, p))).fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        assert!((fewer as f64) < 0.8 * more as f64, "covers visit {fewer} nodes, single subtrees {more}");
        for &p in &points {
            assert_eq!(query_from_grid(&bvh, &with, &boxes, p), brute_force(&boxes, p), "at {p:?}");
        }

        // A budget just under what covers of 16 take: smaller covers that fit, still exact.
        let words = with.covers.len() as f64 - 1.0;
        let budget = GridBudget { cover_words_per_primitive: words / boxes.len() as f64, ..GridBudget::for_structure(boxes.len()) };
        let smaller = EntryGrid::build(&bvh, &boxes, budget).unwrap();
        let largest = points.iter().map(|&p| smaller.cover(p).len()).max().unwrap();
        assert!(!smaller.covers.is_empty() && smaller.covers.len() as f64 <= words, "{} cover words for {words}", smaller.covers.len());
        assert!((2..MAX_COVER).contains(&largest), "covers of up to {largest} subtrees");
        for &p in &points {
            assert_eq!(query_from_grid(&bvh, &smaller, &boxes, p), brute_force(&boxes, p), "at {p:?}");
        }
    }

    /// The words the GPU reads: node indices moved by the group's base (END kept), the covers placed
    /// after the cells with each cell's offset moved to where they land, and its count intact.
    #[test]
    fn gpu_words_relocate_nodes_and_covers() {
        let three = CELL_COVER | 2 << CELL_COVER_COUNT_SHIFT;
        let grid = EntryGrid {
            min: Vec3::ZERO,
            cells_per_unit: Vec3::ONE,
            dims: UVec3::new(3, 1, 1),
            cells: vec![[END, END], [4, 9], [2, three]],
            covers: vec![2, 3, 5, 7, 8, 11],
        };
        assert_eq!(grid.cover(Vec3::new(0.5, 0.5, 0.5)), Vec::<[u32; 2]>::new());
        assert_eq!(grid.cover(Vec3::new(1.5, 0.5, 0.5)), vec![[4, 9]]);
        assert_eq!(grid.cover(Vec3::new(2.5, 0.5, 0.5)), vec![[2, 3], [5, 7], [8, 11]]);
        let covers_at = 1000 + 6;
        assert_eq!(grid.gpu_words(100, 1000), vec![END, END, 104, 109, 102, three | covers_at, 102, 103, 105, 107, 108, 111]);
    }

    #[test]
    fn volumes_crowded_together_get_no_grid_and_are_refused_quickly() {
        // Thousands of boxes all over the same region: every cell reaches every leaf.
        let mut rng = Pcg64::seed_from_u64(5);
        let boxes: Vec<Aabb> = (0..20_000)
            .map(|_| {
                let c = Vec3::new(rng.random(), rng.random(), rng.random()) * 0.01;
                Aabb::new(c - Vec3::ONE, c + Vec3::ONE)
            })
            .collect();
        let bvh = Bvh::build(&boxes).unwrap();
        let started = std::time::Instant::now();
        assert!(EntryGrid::build(&bvh, &boxes, GridBudget::for_structure(boxes.len())).is_none());
        // Without the limit this grid visits every node from each of its 1.3M cells.
        assert!(started.elapsed().as_secs_f32() < 30.0, "{:?}", started.elapsed());
    }

    #[test]
    fn a_structures_grids_share_a_budget_of_cells_and_covers() {
        assert_eq!(GridBudget::for_structure(28_000).cells_per_primitive, CELLS_PER_PRIMITIVE);
        assert_eq!(GridBudget::for_structure(1 << 20).cells_per_primitive, 2.0);
        // A few sparse volumes share the fewest cells a structure gets.
        assert_eq!(GridBudget::for_structure(100).cells_per_primitive * 100.0, MIN_CELLS);
        assert_eq!(GridBudget::for_structure(0).cells_per_primitive, MIN_CELLS);
        // 2,000 groups of 500 volumes: each grid's share, not each grid's own cap.
        let million = GridBudget::for_structure(1_000_000);
        assert!(million.cells_per_primitive * 1_000_000.0 <= MAX_CELLS);
        assert!(million.cover_words_per_primitive * 1_000_000.0 <= MAX_COVER_WORDS);
    }

    #[test]
    fn small_or_unbounded_sets_have_no_grid() {
        let boxes: Vec<Aabb> = (0..MIN_PRIMITIVES - 1).map(|i| Aabb::new(Vec3::splat(i as f32), Vec3::splat(i as f32 + 0.5))).collect();
        let budget = GridBudget::for_structure(100);
        assert!(EntryGrid::build(&Bvh::build(&boxes).unwrap(), &boxes, budget).is_none());
        let mut flat: Vec<Aabb> = (0..100).map(|i| Aabb::new(Vec3::new(i as f32, 0.0, 0.0), Vec3::new(i as f32 + 0.5, 0.0, 1.0))).collect();
        let grid = EntryGrid::build(&Bvh::build(&flat).unwrap(), &flat, budget).unwrap();
        assert_eq!(grid.dims.y, 1, "flat along y: one cell");
        flat.push(Aabb::new(Vec3::splat(-3e38), Vec3::splat(3e38)));
        assert!(EntryGrid::build(&Bvh::build(&flat).unwrap(), &flat, budget).is_none(), "an extent that overflows");
    }
}
