//! BVH node layout shared with WGSL, the CPU builder and the CPU point query.
//!
//! The builder is a binned SAH builder for static sets; its output is also the reference a GPU build
//! is checked against ([`Bvh::validate`]), and [`Bvh::query_point`] is the oracle for the GPU query.

use glam::{DVec3, Vec3};

use super::volumes::Aabb;

/// Set in `BvhNode::entry` of a leaf.
pub const LEAF: u32 = 1 << 31;

/// `BvhNode::skip` of the nodes after which the traversal is done.
pub const END: u32 = u32::MAX;

/// A leaf's `entry` keeps its primitive count − 1 in the 7 bits below [`LEAF`] and its first
/// primitive in the 24 bits below those.
const LEAF_COUNT_SHIFT: u32 = 24;
const LEAF_FIRST_MASK: u32 = (1 << LEAF_COUNT_SHIFT) - 1;
/// The most primitives a leaf's `entry` can count.
const MAX_LEAF_COUNT: u32 = 1 << (31 - LEAF_COUNT_SHIFT);

/// The deepest root-to-leaf path [`Bvh::build`] produces, in nodes (a root that is a leaf has depth 1).
/// The traversal needs no stack, so this only bounds the builder's recursion and keeps degenerate
/// inputs from producing list-like trees: the builder forces median splits wherever the SAH's choice
/// could exceed it.
pub const MAX_DEPTH: u32 = 48;

/// The most primitives a leaf can hold, as its 7 bits in `entry` count them: the particle lights'
/// GPU-built leaves use them all (`accel/structure.rs`, `dynamic_group_leaf_size`). The GPU can rely
/// on this bound to size per-leaf work.
pub const MAX_LEAF_SIZE: u32 = MAX_LEAF_COUNT;

/// Leaves of [`Bvh::build`] hold between 1 and this many primitives: nodes of at most 4 are always
/// leaves, and the SAH keeps up to 16 in a leaf when splitting them does not pay.
pub const SAH_MAX_LEAF_SIZE: u32 = 16;

/// Nodes with more primitives than this are split unless the SAH prefers a leaf.
const MIN_SPLIT_SIZE: usize = 4;

/// Leaves of [`Bvh::build_wide`] hold up to this many primitives. Bigger leaves trade node visits for
/// primitive tests, which a subgroup sharing a leaf out runs a subgroup's width at a time: crowded
/// decals shade faster with leaves of up to 64 than of 16 or 32, and no faster with larger ones
/// (benchmarks/LOG.md, topic 2).
pub const WIDE_LEAF_SIZE: u32 = 64;

/// The SAH cost of visiting a node in [`Bvh::build_wide`], in primitive tests: a subgroup sharing a
/// leaf out tests a subgroup's width of primitives in one round.
pub const WIDE_TRAVERSAL_COST: f64 = 32.0;

/// SAH bins along the longest axis of the centroids' box.
const BINS: usize = 16;

/// SAH cost of visiting an internal node, relative to testing one primitive's volume. On the GPU a
/// node visit is a dependent load and a branch, a leaf's primitives are tested back to back: at 3
/// (with leaves of up to 16) large lights, ≈ 1 m decals and 1M small lights shade faster than at 1
/// (with leaves of up to 8), and small ones as fast (benchmarks/LOG.md, topics 4 and 5).
const TRAVERSAL_COST: f64 = 3.0;

/// Most primitive slots one BVH, or one node array holding several, can address: a leaf's first
/// primitive has 24 bits.
pub const MAX_PRIMITIVES: usize = 1 << LEAF_COUNT_SHIFT;

/// One BVH node, 32 bytes, laid out for a traversal without a stack: the links visit the nodes depth
/// first, and each node says where to go next whether or not the point is inside its box. Keep in
/// sync with `BvhNode` in `accel/bvh_types.wgsl`.
///
/// `entry`: for an internal node, its first child (the second is that child's `skip`); for a leaf,
/// `LEAF | (count − 1) << 24 | first`, naming `Bvh::primitive_indices[first..first + count]`.
/// `skip`: the node that follows this one's subtree in depth-first order, where the traversal goes
/// when the point is outside the box or after a leaf; [`END`] after the last.
/// The root is node 0; an empty BVH has no nodes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub entry: u32,
    pub max: [f32; 3],
    pub skip: u32,
}

impl BvhNode {
    /// The node's box: the union of its children's, or of its primitives' boxes.
    pub fn bounds(&self) -> Aabb {
        Aabb::new(Vec3::from(self.min), Vec3::from(self.max))
    }

    pub fn is_leaf(&self) -> bool {
        self.entry & LEAF != 0
    }

    /// A leaf's `entry` for `count` (1 ..= [`MAX_LEAF_SIZE`]) primitives from `first`.
    pub fn leaf_entry(first: u32, count: u32) -> u32 {
        debug_assert!((1..=MAX_LEAF_COUNT).contains(&count) && first <= LEAF_FIRST_MASK);
        LEAF | (count - 1) << LEAF_COUNT_SHIFT | first
    }

    /// The leaf's first primitive slot.
    pub fn leaf_first(&self) -> u32 {
        self.entry & LEAF_FIRST_MASK
    }

    /// The leaf's range in `Bvh::primitive_indices`.
    pub fn leaf_range(&self) -> std::ops::Range<usize> {
        let first = self.leaf_first() as usize;
        let count = ((self.entry & !LEAF) >> LEAF_COUNT_SHIFT) as usize + 1;
        first..first + count
    }

    /// The node as it reads once its BVH is moved within shared arrays: node links shifted by
    /// `node_offset` (an [`END`] stays), a leaf's range by `primitive_offset`. Offsets wrap, so a
    /// wrapped negation moves a BVH back.
    pub fn offset(&self, node_offset: u32, primitive_offset: u32) -> BvhNode {
        let entry = if self.is_leaf() {
            BvhNode::leaf_entry(self.leaf_first().wrapping_add(primitive_offset), self.leaf_range().len() as u32)
        } else {
            self.entry.wrapping_add(node_offset)
        };
        let skip = if self.skip == END { END } else { self.skip.wrapping_add(node_offset) };
        BvhNode { entry, skip, ..*self }
    }
}

/// A BVH as uploaded: nodes (root first) and the primitive indices its leaves point into.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    pub primitive_indices: Vec<u32>,
}

impl Bvh {
    /// Builds a BVH over `aabbs`; primitive `i` is `aabbs[i]`.
    ///
    /// Every box must be finite and non-empty (flat or point boxes are fine): a NaN bound would make
    /// every comparison false and silently drop lights, so it is an error here instead. Nodes are laid
    /// out depth-first (a first child directly follows its parent), leaves hold 1 to
    /// [`SAH_MAX_LEAF_SIZE`] primitives, and no path is deeper than [`MAX_DEPTH`].
    pub fn build(aabbs: &[Aabb]) -> crate::Result<Bvh> {
        Self::build_with_leaf_size(aabbs, SAH_MAX_LEAF_SIZE)
    }

    /// As [`build`](Self::build), with leaves of at most `max_leaf_size` (1 to [`MAX_LEAF_SIZE`])
    /// primitives: 1 for a top level, whose leaves the query enters one instance at a time.
    pub fn build_with_leaf_size(aabbs: &[Aabb], max_leaf_size: u32) -> crate::Result<Bvh> {
        Self::build_with_leaves(aabbs, max_leaf_size, TRAVERSAL_COST)
    }

    /// As [`build`](Self::build), with leaves of up to [`WIDE_LEAF_SIZE`] primitives, for queries that
    /// share each leaf out among a subgroup's lanes (`shading/enumerate/decal_leaves_shared_out.wgsl`):
    /// they test a subgroup's width of primitives in one round, so the SAH counts a node visit as
    /// [`WIDE_TRAVERSAL_COST`] primitive tests. Crowded decals (100k of about a metre over Sponza),
    /// shared out, shade faster with these leaves than with [`build`](Self::build)'s (benchmarks/LOG.md,
    /// topic 2).
    pub fn build_wide(aabbs: &[Aabb]) -> crate::Result<Bvh> {
        Self::build_with_leaves(aabbs, WIDE_LEAF_SIZE, WIDE_TRAVERSAL_COST)
    }

    fn build_with_leaves(aabbs: &[Aabb], max_leaf_size: u32, traversal_cost: f64) -> crate::Result<Bvh> {
        assert!((1..=MAX_LEAF_SIZE).contains(&max_leaf_size), "leaf size {max_leaf_size}");
        let invalid = |message: String| Err(crate::Error::InvalidScene(message));
        if aabbs.len() > MAX_PRIMITIVES {
            return invalid(format!("{} volumes; one BVH holds at most {MAX_PRIMITIVES}", aabbs.len()));
        }
        for (i, b) in aabbs.iter().enumerate() {
            if !b.is_finite() {
                return invalid(format!("volume {i} has a NaN or infinite bound (min {:?}, max {:?})", b.min.to_array(), b.max.to_array()));
            }
            if !b.is_valid() {
                return invalid(format!("volume {i} is empty: min {:?} > max {:?} on some axis", b.min.to_array(), b.max.to_array()));
            }
        }
        if aabbs.is_empty() {
            return Ok(Bvh::default());
        }
        let mut prims: Vec<Prim> = aabbs
            .iter()
            .enumerate()
            .map(|(i, b)| Prim { bounds: *b, centroid: (b.min.as_dvec3() + b.max.as_dvec3()) * 0.5, index: i as u32 })
            .collect();
        let mut nodes = Vec::with_capacity(2 * aabbs.len() - 1);
        let mut children = Vec::with_capacity(2 * aabbs.len() - 1);
        let leaves = LeafSizes { max: max_leaf_size as usize, split_above: MIN_SPLIT_SIZE.min(max_leaf_size as usize), traversal_cost };
        build_node(&mut nodes, &mut children, &mut prims, 0, 1, leaves);
        link(&mut nodes, &children);
        Ok(Bvh { nodes, primitive_indices: prims.iter().map(|p| p.index).collect() })
    }

    /// An internal node's two children, in traversal order; `None` for a leaf.
    ///
    /// # Panics
    /// On a first child out of range (a BVH that fails [`Bvh::validate`]).
    pub fn children(&self, node: &BvhNode) -> Option<(u32, u32)> {
        (!node.is_leaf()).then(|| (node.entry, self.nodes[node.entry as usize].skip))
    }

    /// Calls `visit(i)` once for every primitive whose own box `aabbs[i]` contains `p` (faces
    /// included), as the GPU query does: node boxes prune, and each leaf primitive's box decides. The
    /// caller then runs the volume's tight test. `aabbs` must be the slice the BVH was built from.
    ///
    /// # Panics
    /// On a BVH that fails [`Bvh::validate`] for `aabbs` (an index out of range); built ones pass.
    pub fn query_point(&self, aabbs: &[Aabb], p: Vec3, visit: impl FnMut(u32)) {
        let root = if self.nodes.is_empty() { END } else { 0 };
        self.query_point_between(aabbs, p, [root, END], visit);
    }

    /// As [`query_point`](Self::query_point), from node `start` until the traversal reaches `stop`:
    /// a subtree, when `stop` is the node after it (an [`EntryGrid`](super::entry_grid::EntryGrid)
    /// cell names both).
    pub fn query_point_between(&self, aabbs: &[Aabb], p: Vec3, [start, stop]: [u32; 2], mut visit: impl FnMut(u32)) {
        // The GPU's traversal, without a stack: into a node whose box holds the point, past it otherwise.
        let mut n = start;
        while n != stop && n != END {
            let node = &self.nodes[n as usize];
            if !node.bounds().contains(p) {
                n = node.skip;
            } else if node.is_leaf() {
                for &i in &self.primitive_indices[node.leaf_range()] {
                    if aabbs[i as usize].contains(p) {
                        visit(i);
                    }
                }
                n = node.skip;
            } else {
                n = node.entry;
            }
        }
    }

    /// Nodes on the longest root-to-leaf path: 0 when empty, 1 when the root is a leaf.
    ///
    /// # Panics
    /// On a child index out of range (a BVH that fails [`Bvh::validate`]).
    pub fn depth(&self) -> u32 {
        if self.nodes.is_empty() {
            return 0;
        }
        let mut deepest = 0;
        let mut stack = vec![(0u32, 1u32)];
        while let Some((n, level)) = stack.pop() {
            deepest = deepest.max(level);
            if let Some((first, second)) = self.children(&self.nodes[n as usize]) {
                stack.push((first, level + 1));
                stack.push((second, level + 1));
            }
        }
        deepest
    }

    /// The nodes a walk from the root reaches, renumbered depth-first with their links remapped. A GPU
    /// build whose small subtrees became leaves (`GpuLbvh::with_max_leaf_size`) leaves the nodes below
    /// them in its node array, unreachable. A malformed tree is returned as it is, for
    /// [`validate`](Self::validate) to report.
    pub fn reachable(&self) -> Bvh {
        let mut order = Vec::new();
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let Some(node) = self.nodes.get(n as usize) else { return self.clone() };
            if order.len() == self.nodes.len() {
                return self.clone();
            }
            order.push(n);
            if !node.is_leaf() {
                let Some(first) = self.nodes.get(node.entry as usize) else { return self.clone() };
                stack.push(first.skip);
                stack.push(node.entry);
            }
        }
        if order.len() == self.nodes.len() {
            return self.clone();
        }
        let mut renumbered = vec![END; self.nodes.len()];
        for (new, &old) in order.iter().enumerate() {
            renumbered[old as usize] = new as u32;
        }
        // A reachable node linking to one no walk reaches is a broken tree, kept whole for `validate`.
        let dangling = |n: u32| n != END && renumbered.get(n as usize).is_some_and(|&r| r == END);
        if order.iter().any(|&n| {
            let node = self.nodes[n as usize];
            dangling(node.skip) || (!node.is_leaf() && dangling(node.entry))
        }) {
            return self.clone();
        }
        let remap = |n: u32| renumbered.get(n as usize).copied().unwrap_or(END);
        let nodes = order
            .iter()
            .map(|&n| {
                let node = self.nodes[n as usize];
                BvhNode { entry: if node.is_leaf() { node.entry } else { remap(node.entry) }, skip: remap(node.skip), ..node }
            })
            .collect();
        Bvh { nodes, primitive_indices: self.primitive_indices.clone() }
    }

    /// Checks everything the GPU traversal relies on, for this BVH over `aabbs`: child and primitive
    /// indices in range, every node reached exactly once from the root (no cycles, no orphans), each
    /// second child skipping where its parent does and the root to [`END`], non-empty leaves covering
    /// `primitive_indices` exactly once, every primitive in exactly one leaf, and every node's box
    /// containing its children's or its primitives' boxes.
    pub fn validate(&self, aabbs: &[Aabb]) -> Result<(), String> {
        if self.nodes.is_empty() {
            return if self.primitive_indices.is_empty() && aabbs.is_empty() {
                Ok(())
            } else {
                Err(format!("no nodes, but {} primitive indices over {} volumes", self.primitive_indices.len(), aabbs.len()))
            };
        }
        if self.primitive_indices.len() != aabbs.len() {
            return Err(format!("{} primitive indices for {} volumes", self.primitive_indices.len(), aabbs.len()));
        }
        let mut node_seen = vec![false; self.nodes.len()];
        let mut slot_seen = vec![false; self.primitive_indices.len()];
        let mut primitive_seen = vec![false; aabbs.len()];
        // Each node with the `skip` it must have: its parent's for a second child, its sibling for a
        // first child (which defines the sibling), END for the root.
        let mut stack = vec![(0u32, END)];
        while let Some((n, skip)) = stack.pop() {
            let seen = node_seen.get_mut(n as usize).ok_or_else(|| format!("node index {n} out of range ({} nodes)", self.nodes.len()))?;
            if *seen {
                return Err(format!("node {n} is reached twice"));
            }
            *seen = true;
            let node = &self.nodes[n as usize];
            if node.skip != skip {
                return Err(format!("node {n} skips to {} instead of {skip}", node.skip));
            }
            let bounds = node.bounds();
            if !bounds.is_valid() {
                return Err(format!("node {n} has an empty or non-finite box {bounds:?}"));
            }
            if node.is_leaf() {
                let range = node.leaf_range();
                if range.is_empty() || range.end > self.primitive_indices.len() {
                    return Err(format!("leaf {n} covers {range:?} of {} primitive indices", self.primitive_indices.len()));
                }
                for slot in range {
                    if std::mem::replace(&mut slot_seen[slot], true) {
                        return Err(format!("primitive slot {slot} is in two leaves (the second is node {n})"));
                    }
                    let i = self.primitive_indices[slot];
                    let b =
                        aabbs.get(i as usize).ok_or_else(|| format!("leaf {n}: primitive {i} out of range ({} volumes)", aabbs.len()))?;
                    if std::mem::replace(&mut primitive_seen[i as usize], true) {
                        return Err(format!("primitive {i} is listed twice (again in leaf {n})"));
                    }
                    if !bounds.contains_box(b) {
                        return Err(format!("leaf {n}'s box {bounds:?} does not contain primitive {i}'s {b:?}"));
                    }
                }
            } else {
                let first = node.entry;
                let first_node = self.nodes.get(first as usize).ok_or_else(|| format!("node {n}: first child {first} out of range"))?;
                let second = first_node.skip;
                let second_node = self.nodes.get(second as usize).ok_or_else(|| format!("node {n}: second child {second} out of range"))?;
                for (child, child_node) in [(first, first_node), (second, second_node)] {
                    if !bounds.contains_box(&child_node.bounds()) {
                        return Err(format!("node {n}'s box {bounds:?} does not contain child {child}'s {:?}", child_node.bounds()));
                    }
                }
                stack.push((second, node.skip));
                stack.push((first, second));
            }
        }
        if let Some(n) = node_seen.iter().position(|seen| !seen) {
            return Err(format!("node {n} is not reachable from the root"));
        }
        // Each of the n slots is in one leaf and names a distinct primitive below n: all n are listed.
        if let Some(slot) = slot_seen.iter().position(|seen| !seen) {
            return Err(format!("primitive slot {slot} is in no leaf"));
        }
        Ok(())
    }
}

/// A primitive during the build. Boxes and centroids travel with the indices being partitioned so
/// that every pass over a node's primitives reads memory in order.
#[derive(Clone, Copy)]
struct Prim {
    bounds: Aabb,
    /// In f64: centroids of boxes near ±f32::MAX, and their spread, must not overflow.
    centroid: DVec3,
    index: u32,
}

/// Appends the subtree over `prims` (which start at `first` in the final primitive order) at `level`
/// (the root is 1) with a leaf's `entry` filled in and an internal node's children noted in
/// `children`; returns its node index. Recursion depth is bounded by [`MAX_DEPTH`].
fn build_node(
    nodes: &mut Vec<BvhNode>,
    children: &mut Vec<(u32, u32)>,
    prims: &mut [Prim],
    first: usize,
    level: u32,
    leaves: LeafSizes,
) -> u32 {
    let index = nodes.len() as u32;
    let bounds = prims.iter().fold(Aabb::EMPTY, |b, p| b.union(p.bounds));
    nodes.push(BvhNode { min: bounds.min.to_array(), entry: 0, max: bounds.max.to_array(), skip: END });
    children.push((END, END));
    match split(prims, bounds, level, leaves) {
        None => nodes[index as usize].entry = BvhNode::leaf_entry(first as u32, prims.len() as u32),
        Some(mid) => {
            let (left, right) = prims.split_at_mut(mid);
            let a = build_node(nodes, children, left, first, level + 1, leaves);
            let b = build_node(nodes, children, right, first + mid, level + 1, leaves);
            children[index as usize] = (a, b);
        }
    }
    index
}

/// Sets every node's `skip`, and internal nodes' `entry`, from the children `build_node` noted.
fn link(nodes: &mut [BvhNode], children: &[(u32, u32)]) {
    let mut stack = vec![(0u32, END)];
    while let Some((n, skip)) = stack.pop() {
        nodes[n as usize].skip = skip;
        if !nodes[n as usize].is_leaf() {
            let (a, b) = children[n as usize];
            nodes[n as usize].entry = a;
            stack.push((a, b));
            stack.push((b, skip));
        }
    }
}

/// Leaf sizes of a build: nodes of at most `split_above` primitives are leaves, and the SAH may keep
/// up to `max` in one.
#[derive(Clone, Copy)]
struct LeafSizes {
    max: usize,
    split_above: usize,
    /// The SAH's cost of visiting a node, in primitive tests.
    traversal_cost: f64,
}

/// Levels below a node of `count` primitives if it and its descendants are split at the median.
fn median_levels(count: usize, leaves: LeafSizes) -> u32 {
    let mut levels = 0;
    let mut count = count;
    while count > leaves.split_above {
        count = count.div_ceil(2);
        levels += 1;
    }
    levels
}

/// Decides how to split a node: `None` for a leaf, or `Some(mid)` after reordering `prims` so that
/// `prims[..mid]` and `prims[mid..]` are the children (both non-empty).
///
/// A SAH split is taken only if its larger child can still be finished by median splits within
/// [`MAX_DEPTH`]; median splits halve the count, so from the root (at most 2^24 primitives, 23
/// levels, 24 with leaves of one) that bound always holds.
fn split(prims: &mut [Prim], bounds: Aabb, level: u32, leaves: LeafSizes) -> Option<usize> {
    let count = prims.len();
    if count <= leaves.split_above {
        return None;
    }
    let (cmin, cmax) = prims.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p.centroid), hi.max(p.centroid)));
    let extent = cmax - cmin;
    let axis = extent.max_position();
    if extent[axis] <= 0.0 {
        // All centroids coincide: no split separates them, so halve the list to bound the depth.
        return Some(count / 2);
    }
    let area = bounds.surface_area();
    // A zero-area node is a segment of points or flat boxes: its SAH costs are all 0/0.
    if area > 0.0 {
        let bin_of = |p: &Prim| (((p.centroid[axis] - cmin[axis]) * (BINS as f64 / extent[axis])) as usize).min(BINS - 1);
        let mut bin_counts = [0usize; BINS];
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        for p in prims.iter() {
            let bin = bin_of(p);
            bin_counts[bin] += 1;
            bin_bounds[bin] = bin_bounds[bin].union(p.bounds);
        }
        // Costs of splitting after bin i: sweep the right sides first, then the left ones.
        let mut right_cost = [0.0f64; BINS];
        let (mut right_box, mut right_count) = (Aabb::EMPTY, 0);
        for i in (1..BINS).rev() {
            right_box = right_box.union(bin_bounds[i]);
            right_count += bin_counts[i];
            right_cost[i] = right_box.surface_area() * right_count as f64;
        }
        let mut best: Option<(usize, f64, usize)> = None;
        let (mut left_box, mut left_count) = (Aabb::EMPTY, 0);
        for i in 1..BINS {
            left_box = left_box.union(bin_bounds[i - 1]);
            left_count += bin_counts[i - 1];
            if left_count == 0 || left_count == count {
                continue;
            }
            let cost = leaves.traversal_cost + (left_box.surface_area() * left_count as f64 + right_cost[i]) / area;
            if best.is_none_or(|(_, best_cost, _)| cost < best_cost) {
                best = Some((i, cost, left_count));
            }
        }
        if let Some((bin, cost, left_count)) = best {
            if cost >= count as f64 && count <= leaves.max {
                return None;
            }
            if level + 1 + median_levels(left_count.max(count - left_count), leaves) <= MAX_DEPTH {
                return Some(partition(prims, |p| bin_of(p) < bin));
            }
        }
    }
    let mid = count / 2;
    prims.select_nth_unstable_by(mid, |p, q| p.centroid[axis].total_cmp(&q.centroid[axis]));
    Some(mid)
}

/// Moves the primitives for which `left` holds to the front; returns how many there are.
fn partition(prims: &mut [Prim], left: impl Fn(&Prim) -> bool) -> usize {
    let mut mid = 0;
    for i in 0..prims.len() {
        if left(&prims[i]) {
            prims.swap(i, mid);
            mid += 1;
        }
    }
    mid
}

#[cfg(test)]
pub(crate) mod tests {
    use std::time::Instant;

    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    use super::*;
    use crate::accel::volumes::{light_aabb, light_contains};
    use crate::scene::{Light, LightKind};

    fn query(bvh: &Bvh, aabbs: &[Aabb], p: Vec3) -> Vec<u32> {
        let mut visited = Vec::new();
        bvh.query_point(aabbs, p, |i| visited.push(i));
        visited.sort_unstable();
        visited
    }

    pub(crate) fn brute_force(aabbs: &[Aabb], p: Vec3) -> Vec<u32> {
        (0..aabbs.len() as u32).filter(|&i| aabbs[i as usize].contains(p)).collect()
    }

    /// The invariants every build must meet, beyond `validate`: depth and leaf sizes.
    fn check_structure(bvh: &Bvh, aabbs: &[Aabb]) {
        bvh.validate(aabbs).unwrap();
        assert!(bvh.depth() <= MAX_DEPTH, "depth {}", bvh.depth());
        for node in bvh.nodes.iter().filter(|n| n.is_leaf()) {
            let count = node.leaf_range().len() as u32;
            assert!((1..=MAX_LEAF_SIZE).contains(&count), "leaf of {count} primitives");
        }
    }

    /// Compares the query with brute force at `p`: same set, each primitive once.
    fn check_point(bvh: &Bvh, aabbs: &[Aabb], p: Vec3) {
        let visited = query(bvh, aabbs, p);
        assert!(visited.windows(2).all(|w| w[0] != w[1]), "a primitive visited twice at {p:?}");
        assert_eq!(visited, brute_force(aabbs, p), "at {p:?}");
    }

    fn random_vec(rng: &mut Pcg64, scale: f32) -> Vec3 {
        Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * scale
    }

    /// Random boxes mixing the cases a builder gets wrong: flat and point boxes, exact duplicates,
    /// and scales from 1e-30 to 1e30 within one set.
    pub(crate) fn random_boxes(rng: &mut Pcg64, count: usize) -> Vec<Aabb> {
        let scale = [1.0, 1e-30, 1e30, 0.0][rng.random_range(0..4)];
        let mut boxes: Vec<Aabb> = Vec::with_capacity(count);
        for _ in 0..count {
            // Scale 0.0: mixed, each box picks its own.
            let s = if scale == 0.0 { [1e-30, 1e-3, 1.0, 1e3, 1e30][rng.random_range(0..5)] } else { scale };
            let center = random_vec(rng, s);
            let mut half = Vec3::new(rng.random(), rng.random(), rng.random()) * s * rng.random_range(0.001..0.5);
            let mut b = match rng.random_range(0..10) {
                0 if !boxes.is_empty() => boxes[rng.random_range(0..boxes.len())],
                1 => Aabb::new(center, center),
                2 => Aabb::new(Vec3::splat(-1e30), Vec3::splat(1e30)),
                _ => {
                    if rng.random_bool(0.3) {
                        half[rng.random_range(0..3)] = 0.0;
                    }
                    Aabb::new(center - half, center + half)
                }
            };
            if rng.random_bool(0.05) {
                // A box tiny in size but far from the origin, or spanning a whole axis.
                let axis = rng.random_range(0..3);
                b.min[axis] = -1e30;
                b.max[axis] = b.max[axis].max(1e-30);
            }
            boxes.push(b);
        }
        boxes
    }

    /// Random points and points on the boxes' faces, edges and corners: each coordinate is a random
    /// value, a box's min or max, or one ulp beside it.
    pub(crate) fn random_points(rng: &mut Pcg64, boxes: &[Aabb], count: usize) -> Vec<Vec3> {
        let mut points = Vec::with_capacity(count);
        for _ in 0..count {
            let scale = [1e-30, 1.0, 1e30][rng.random_range(0..3)];
            let mut p = random_vec(rng, scale);
            if !boxes.is_empty() && rng.random_bool(0.8) {
                let b = boxes[rng.random_range(0..boxes.len())];
                for axis in 0..3 {
                    p[axis] = match rng.random_range(0..6) {
                        0 => b.min[axis],
                        1 => b.max[axis],
                        2 => b.min[axis].next_down(),
                        3 => b.max[axis].next_up(),
                        4 => boxes[rng.random_range(0..boxes.len())].max[axis],
                        _ => b.min[axis] + (b.max[axis] - b.min[axis]) * rng.random::<f32>(),
                    };
                }
            }
            points.push(p);
        }
        points
    }

    /// A subtree turned into a leaf over its primitives, as the GPU builder's larger leaves are: the
    /// nodes below it drop out, renumbered links still validate, and queries are unchanged.
    #[test]
    fn reachable_drops_the_nodes_under_a_collapsed_subtree() {
        let mut rng = Pcg64::seed_from_u64(0xc011);
        let boxes = random_boxes(&mut rng, 200);
        let mut bvh = Bvh::build(&boxes).unwrap();
        assert_eq!(bvh.reachable(), bvh, "a tree without orphans is kept as it is");
        // The primitive slots of each internal node's subtree (one contiguous run, built depth-first).
        let subtree_slots = |bvh: &Bvh, root: u32| {
            let (mut slots, mut n, stop) = (Vec::new(), root, bvh.nodes[root as usize].skip);
            while n != stop {
                let node = bvh.nodes[n as usize];
                match bvh.children(&node) {
                    Some((child, _)) => n = child,
                    None => {
                        slots.extend(node.leaf_range());
                        n = node.skip;
                    }
                }
            }
            slots
        };
        // An internal node below the root over more primitives than one leaf of the builder holds.
        let first = (1..bvh.nodes.len() as u32)
            .find(|&n| !bvh.nodes[n as usize].is_leaf() && (9..=MAX_LEAF_COUNT as usize).contains(&subtree_slots(&bvh, n).len()))
            .unwrap();
        let slots = subtree_slots(&bvh, first);
        let (start, count) = (slots[0] as u32, slots.len() as u32);
        assert!(slots.iter().enumerate().all(|(i, &s)| s == slots[0] + i));
        let dropped_child = bvh.nodes[first as usize].entry;
        bvh.nodes[first as usize].entry = BvhNode::leaf_entry(start, count);
        assert!(bvh.validate(&boxes).unwrap_err().contains("not reachable"));
        let compact = bvh.reachable();
        compact.validate(&boxes).unwrap();
        // A link into the dropped nodes is a broken tree, which renumbering must not hide.
        let mut broken = bvh.clone();
        let last = (0..broken.nodes.len()).rev().find(|&n| broken.nodes[n].skip == END && broken.nodes[n].is_leaf()).unwrap();
        broken.nodes[last].skip = dropped_child;
        assert!(broken.reachable().validate(&boxes).is_err());
        assert!(compact.nodes.len() < bvh.nodes.len());
        for p in random_points(&mut rng, &boxes, 500) {
            assert_eq!(query(&compact, &boxes, p), query(&Bvh::build(&boxes).unwrap(), &boxes, p));
        }
    }

    /// Wide leaves: up to WIDE_LEAF_SIZE primitives, fewer nodes than the default build over crowded
    /// boxes, and queries that still find exactly the boxes holding the point.
    #[test]
    fn wide_builds_have_larger_leaves_and_the_same_queries() {
        let mut rng = Pcg64::seed_from_u64(0x31de);
        let crowded: Vec<Aabb> = (0..4000)
            .map(|_| {
                let c = Vec3::new(rng.random_range(0.0..20.0), rng.random_range(0.0..5.0), rng.random_range(0.0..10.0));
                Aabb::new(c - 1.0, c + 1.0)
            })
            .collect();
        for boxes in [crowded, random_boxes(&mut rng, 3000)] {
            let (wide, narrow) = (Bvh::build_wide(&boxes).unwrap(), Bvh::build(&boxes).unwrap());
            check_structure(&wide, &boxes);
            let largest = wide.nodes.iter().filter(|n| n.is_leaf()).map(|n| n.leaf_range().len()).max().unwrap();
            assert!(largest <= WIDE_LEAF_SIZE as usize, "a leaf of {largest}");
            for p in random_points(&mut rng, &boxes, 300) {
                check_point(&wide, &boxes, p);
            }
            if boxes.len() == 4000 {
                assert!(largest > SAH_MAX_LEAF_SIZE as usize, "no leaf wider than the default's");
                assert!(wide.nodes.len() * 2 < narrow.nodes.len(), "{} nodes wide, {} narrow", wide.nodes.len(), narrow.nodes.len());
            }
        }
    }

    #[test]
    fn query_matches_brute_force_on_random_sets() {
        let mut rng = Pcg64::seed_from_u64(0x5eed);
        for &(size, sets, points) in &[(0, 4, 50), (1, 40, 100), (2, 40, 100), (3, 40, 100), (7, 60, 200), (100, 40, 500), (5000, 6, 1000)]
        {
            for _ in 0..sets {
                let boxes = random_boxes(&mut rng, size);
                let bvh = Bvh::build(&boxes).unwrap();
                check_structure(&bvh, &boxes);
                for p in random_points(&mut rng, &boxes, points) {
                    check_point(&bvh, &boxes, p);
                }
            }
        }
    }

    #[test]
    fn single_primitive_leaves_for_top_levels() {
        let mut rng = Pcg64::seed_from_u64(0x7095);
        for size in [1, 2, 5, 100, 1000] {
            for _ in 0..8 {
                let boxes = random_boxes(&mut rng, size);
                let bvh = Bvh::build_with_leaf_size(&boxes, 1).unwrap();
                check_structure(&bvh, &boxes);
                assert!(
                    bvh.nodes.iter().filter(|n| n.is_leaf()).all(|n| n.leaf_range().len() == 1),
                    "{size} boxes: a leaf holds more than one"
                );
                assert_eq!(bvh.nodes.len(), 2 * size - 1);
                for p in random_points(&mut rng, &boxes, 200) {
                    check_point(&bvh, &boxes, p);
                }
            }
        }
        // Coincident boxes split by halving, still one per leaf.
        let same = vec![Aabb::new(Vec3::ZERO, Vec3::ONE); 64];
        let bvh = Bvh::build_with_leaf_size(&same, 1).unwrap();
        check_structure(&bvh, &same);
        assert_eq!(bvh.nodes.len(), 127);
    }

    #[test]
    fn degenerate_inputs() {
        let empty = Bvh::build(&[]).unwrap();
        assert!(empty.nodes.is_empty() && empty.primitive_indices.is_empty() && empty.depth() == 0);
        empty.validate(&[]).unwrap();
        check_point(&empty, &[], Vec3::ZERO);

        let one = [Aabb::new(Vec3::ZERO, Vec3::ONE)];
        let bvh = Bvh::build(&one).unwrap();
        assert_eq!(bvh.nodes, [BvhNode { min: [0.0; 3], entry: LEAF, max: [1.0; 3], skip: END }], "the root is a leaf");
        assert_eq!(bvh.primitive_indices, [0]);
        assert_eq!(bvh.depth(), 1);

        let cases: [(&str, Vec<Aabb>); 5] = [
            ("identical", vec![Aabb::new(Vec3::ZERO, Vec3::ONE); 1000]),
            ("identical points", vec![Aabb::new(Vec3::ONE, Vec3::ONE); 1000]),
            (
                "a flat grid",
                (0..900)
                    .map(|i| {
                        Aabb::new(
                            Vec3::new((i % 30) as f32, (i / 30) as f32, 0.0),
                            Vec3::new((i % 30) as f32 + 1.0, (i / 30) as f32 + 1.0, 0.0),
                        )
                    })
                    .collect(),
            ),
            ("points on a line", (0..500).map(|i| Aabb::new(Vec3::X * i as f32, Vec3::X * i as f32)).collect()),
            // Centroids spaced geometrically: linear bins put all but the last few in bin 0, so the SAH
            // alone would peel off one box per level.
            ("geometric", (0..200).map(|i| Aabb::new(Vec3::X * 1.5f32.powi(i), Vec3::X * 1.5f32.powi(i) + 1.0)).collect()),
        ];
        for (name, boxes) in cases {
            let bvh = Bvh::build(&boxes).unwrap();
            check_structure(&bvh, &boxes);
            let mut rng = Pcg64::seed_from_u64(1);
            for p in random_points(&mut rng, &boxes, 300) {
                check_point(&bvh, &boxes, p);
            }
            println!("{name}: {} boxes, {} nodes, depth {}", boxes.len(), bvh.nodes.len(), bvh.depth());
        }
    }

    #[test]
    fn non_finite_and_empty_volumes_are_rejected() {
        let mut boxes = vec![Aabb::new(Vec3::ZERO, Vec3::ONE); 20];
        boxes[17].max.y = f32::NAN;
        let err = Bvh::build(&boxes).unwrap_err().to_string();
        assert!(err.contains("volume 17 has a NaN or infinite bound"), "{err}");
        boxes[17].max.y = f32::INFINITY;
        assert!(Bvh::build(&boxes).is_err());
        boxes[17] = Aabb::EMPTY;
        let err = Bvh::build(&boxes).unwrap_err().to_string();
        assert!(err.contains("volume 17"), "{err}");
        boxes[17] = Aabb::new(Vec3::ONE, Vec3::ZERO);
        let err = Bvh::build(&boxes).unwrap_err().to_string();
        assert!(err.contains("volume 17 is empty"), "{err}");
    }

    #[test]
    fn validate_catches_broken_trees() {
        let mut rng = Pcg64::seed_from_u64(3);
        let boxes = random_boxes(&mut rng, 50);
        let good = Bvh::build(&boxes).unwrap();
        good.validate(&boxes).unwrap();
        let leaf = good.nodes.iter().position(|n| n.is_leaf()).unwrap();
        let internal = good.nodes.iter().position(|n| !n.is_leaf()).unwrap();
        // Each breakage gets the tree, a leaf's index and an internal node's index.
        type Breakage = fn(&mut Bvh, usize, usize);
        let breakages: [(&str, Breakage); 8] = [
            ("duplicate primitive", |b, _, _| b.primitive_indices[0] = b.primitive_indices[1]),
            ("primitive out of range", |b, _, _| b.primitive_indices[0] = 50),
            ("child out of range", |b, _, internal| b.nodes[internal].entry = 1000),
            ("cycle", |b, _, internal| b.nodes[internal].entry = 0),
            ("skip to an ancestor", |b, leaf, _| b.nodes[leaf].skip = 0),
            ("skip past the end", |b, leaf, _| b.nodes[leaf].skip = END),
            ("shrunken box", |b, leaf, _| b.nodes[leaf].max[0] = b.nodes[leaf].min[0] - 1.0),
            ("leaf past the primitives", |b, leaf, _| b.nodes[leaf].entry = BvhNode::leaf_entry(45, 8)),
        ];
        for (name, breakage) in breakages {
            let mut bvh = good.clone();
            breakage(&mut bvh, leaf, internal);
            assert!(bvh.validate(&boxes).is_err(), "{name} passed validation");
        }
        assert!(good.validate(&boxes[..49]).is_err(), "a volume too few");
    }

    #[test]
    fn builds_a_million_boxes() {
        let mut rng = Pcg64::seed_from_u64(11);
        let boxes: Vec<Aabb> = (0..1_000_000)
            .map(|_| {
                let c = random_vec(&mut rng, 1000.0);
                let h = Vec3::splat(rng.random_range(0.1..10.0));
                Aabb::new(c - h, c + h)
            })
            .collect();
        let start = Instant::now();
        let bvh = Bvh::build(&boxes).unwrap();
        let elapsed = start.elapsed();
        println!("1M boxes: built in {elapsed:.2?}, {} nodes, depth {}", bvh.nodes.len(), bvh.depth());
        check_structure(&bvh, &boxes);
        for p in random_points(&mut rng, &boxes, 20) {
            check_point(&bvh, &boxes, p);
        }
    }

    #[test]
    fn light_query_matches_brute_force() {
        let mut rng = Pcg64::seed_from_u64(21);
        let lights: Vec<Light> = (0..3000)
            .map(|i| {
                let kind = if i % 2 == 0 {
                    LightKind::Point
                } else {
                    let outer = rng.random_range(0.01..std::f32::consts::FRAC_PI_2);
                    LightKind::Spot { inner_cone_angle: outer * 0.5, outer_cone_angle: outer }
                };
                let direction = loop {
                    let d = random_vec(&mut rng, 1.0);
                    if d.length() > 0.1 {
                        break d.normalize();
                    }
                };
                Light {
                    kind,
                    position: random_vec(&mut rng, 50.0),
                    direction: if i % 7 == 0 { Vec3::AXES[i % 3] } else { direction },
                    color: Vec3::ONE,
                    intensity: 1.0,
                    range: rng.random_range(0.5..15.0),
                    cast_shadows: false,
                }
            })
            .collect();
        let boxes: Vec<Aabb> = lights.iter().map(light_aabb).collect();
        let bvh = Bvh::build(&boxes).unwrap();
        check_structure(&bvh, &boxes);
        let mut points: Vec<Vec3> = (0..3000).map(|_| random_vec(&mut rng, 60.0)).collect();
        // Points on the volumes' boundaries: apexes, and just inside each sphere along the spot's axis.
        points.extend(lights.iter().take(500).flat_map(|l| [l.position, l.position + l.direction * l.range.next_down()]));
        let mut total = 0;
        for p in points {
            let mut lit = Vec::new();
            bvh.query_point(&boxes, p, |i| {
                if light_contains(&lights[i as usize], p) {
                    lit.push(i);
                }
            });
            lit.sort_unstable();
            let expected: Vec<u32> = (0..lights.len() as u32).filter(|&i| light_contains(&lights[i as usize], p)).collect();
            assert_eq!(lit, expected, "at {p:?}");
            total += lit.len();
        }
        assert!(total > 1000, "the test must exercise lit points: {total}");
    }
}
