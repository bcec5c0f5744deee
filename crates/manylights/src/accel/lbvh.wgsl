// LBVH build on the GPU (Karras 2012), over `params.count` boxes, into the node layout of
// `accel/bvh_types.wgsl`: 24-bit Morton codes of the box centres → (radix sort, `radix_sort.wgsl`)
// → one thread per internal node finds its range and split → bounds propagated from the leaves up.
// Karras's internal node i is stored at node 2i (the root at 0) and leaf k at 2k + 1, the last leaf
// at 2k (where no internal node is), all offset by `node_base` in `nodes`: several BVHs (a top level
// and the groups' BVHs) share one node array, so the query needs no binding per BVH. Interleaved so,
// a subtree over sorted leaves [a, b] lies within nodes [2a, 2b + 1] and the node after it at 2b + 2
// or above: a walk of the subtree ends at the first node at or past its `skip`, as in the depth-first
// order of CPU builds, which lets entry grids (`rebuilt_grid.wgsl`) start queries inside it. `primitives[primitive_base + k]` gets `item_base` + the index of the
// k-th box in sorted (leaf) order among this build's boxes; a leaf over sorted positions [k, k + n)
// names the range from `leaf_base + k` (`LbvhTarget` in `lbvh.rs`).
#include "accel/bvh_types.wgsl"

struct LbvhParams {
    count: u32,
    node_base: u32,
    primitive_base: u32,
    item_base: u32,
    // Subtrees over at most this many boxes are leaves (1: every box its own leaf).
    max_leaf_size: u32,
    leaf_base: u32,
    // The Morton grid: the bounds of the box centres when the CPU uploads the boxes, or bounds the
    // centres are known to stay within when a GPU pass writes them (centres outside are clamped in).
    centre_min: vec4<f32>,
    centre_max: vec4<f32>,
}

struct Box {
    min: vec4<f32>,
    max: vec4<f32>,
}

const NO_PARENT: u32 = 0xffffffffu;

@group(0) @binding(0) var<uniform> params: LbvhParams;
@group(0) @binding(1) var<storage, read> boxes: array<Box>;
// (Morton code, box index): the sort's input ...
@group(0) @binding(2) var<storage, read_write> keys: array<vec2<u32>>;
// ... and its output.
@group(0) @binding(3) var<storage, read> sorted_keys: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read_write> nodes: array<BvhNode>;
@group(0) @binding(5) var<storage, read_write> primitives: array<u32>;
@group(0) @binding(6) var<storage, read_write> parents: array<u32>;
// Internal nodes' bounds as order-preserving integers, 6 per node (min xyz complemented, then max xyz,
// so all six grow by atomicMax): only for nodes spanning blocks, which the hierarchy pass clears to 0.
@group(0) @binding(7) var<storage, read_write> node_bounds: array<atomic<u32>>;
// Internal nodes' ranges of sorted leaves [x, y].
@group(0) @binding(8) var<storage, read_write> ranges: array<vec2<u32>>;

// With LIGHT_TREE, the build also gives every node its light-tree emitters (`accel/light_tree.rs`):
// the union of `emitters`, one per box (a light's position as a point box, its power and range),
// written to `tree` at the node's index. Bounds and ranges are unions as the boxes are (block-local
// in workgroup memory, spanning nodes through `tree_bounds`); power is a sum, which atomic max cannot
// carry, so a spanning node adds the sums of its first and last blocks' parts (`leaf_power`) to those
// of the whole blocks between (`block_power`, prefix sums over blocks). Without it these are
// one-element placeholders.
override LIGHT_TREE: bool = false;
@group(0) @binding(9) var<storage, read> emitters: array<LightTreeNode>;
@group(0) @binding(10) var<storage, read_write> tree: array<LightTreeNode>;
// Spanning nodes' emitters as order-preserving integers, TREE_SLOTS per node: positions' min xyz
// complemented, max xyz, the largest range and the largest single power.
@group(0) @binding(11) var<storage, read_write> tree_bounds: array<atomic<u32>>;
// Per sorted leaf: the power summed from its block's first leaf to it (x) and from it to the
// block's last (y).
@group(0) @binding(12) var<storage, read_write> leaf_power: array<vec2<f32>>;
// Per block: its total power, then (after `lbvh_block_power`) the total of the blocks before it.
@group(0) @binding(13) var<storage, read_write> block_power: array<f32>;

const TREE_SLOTS: u32 = 8u;

// f32 → u32 keeping the order, so atomicMax works on floats; ~ordered(x) turns max into min.
fn ordered(x: f32) -> u32 {
    let bits = bitcast<u32>(x);
    return select(bits | 0x80000000u, ~bits, (bits & 0x80000000u) != 0u);
}

fn unordered(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

fn box_centre(b: Box) -> vec3<f32> {
    return b.min.xyz * 0.5 + b.max.xyz * 0.5;
}

// Cells per axis of the Morton grid. 8 bits per axis (24-bit codes) sort in three radix passes
// instead of 10 bits' four, and the trees they build shade as fast (benchmarks/LOG.md, topic 5);
// equal codes are ordered by position, so any precision builds a valid tree.
const MORTON_CELLS: f32 = 256.0;

// Spreads the low 10 bits of v to every third bit.
fn spread_bits(v: u32) -> u32 {
    var x = v & 0x3ffu;
    x = (x | (x << 16u)) & 0x030000ffu;
    x = (x | (x << 8u)) & 0x0300f00fu;
    x = (x | (x << 4u)) & 0x030c30c3u;
    x = (x | (x << 2u)) & 0x09249249u;
    return x;
}

@compute @workgroup_size(256)
fn lbvh_morton(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let low = params.centre_min.xyz;
    let extent = max(params.centre_max.xyz - low, vec3<f32>(1e-30));
    let cell = vec3<u32>(clamp((box_centre(boxes[id.x]) - low) / extent * MORTON_CELLS, vec3<f32>(0.0), vec3<f32>(MORTON_CELLS - 1.0)));
    let code = (spread_bits(cell.x) << 2u) | (spread_bits(cell.y) << 1u) | spread_bits(cell.z);
    keys[id.x] = vec2<u32>(code, id.x);
}

// Length of the common prefix of sorted keys i and j, ties broken by position (Karras); -1 out of range.
fn common_prefix(i: i32, j: i32) -> i32 {
    if j < 0 || j >= i32(params.count) {
        return -1;
    }
    let a = sorted_keys[i].x;
    let b = sorted_keys[j].x;
    if a == b {
        return 32 + i32(countLeadingZeros(u32(i) ^ u32(j)));
    }
    return i32(countLeadingZeros(a ^ b));
}

// Local index (within this build) of a child in `parents`: internal nodes 0 .. count - 2, leaf k at
// count - 1 + k.
fn child_node(index: i32, is_leaf: bool) -> u32 {
    return select(u32(index), params.count - 1u + u32(index), is_leaf);
}

// Where a child is stored, relative to `node_base` (see the top of this file).
fn node_slot(index: i32, is_leaf: bool) -> u32 {
    let last_leaf = is_leaf && index == i32(params.count) - 1;
    return 2u * u32(index) + select(0u, 1u, is_leaf && !last_leaf);
}

// Whether internal node i's range runs up from i (Karras: it grows towards the neighbour sharing the
// longer prefix).
fn range_runs_up(i: i32) -> bool {
    return common_prefix(i, i + 1) > common_prefix(i, i - 1);
}

// `skip` of the nodes whose range ends at sorted key `last`: the node after them in depth-first
// order, which is the largest subtree starting at key last + 1. It is a second child, and Karras
// stores second children at the start of their range: internal node last + 1 if that node's range
// runs up from it, otherwise leaf last + 1. Found locally, so no pass over the finished tree.
fn skip_after(last: i32) -> u32 {
    let n = i32(params.count);
    if last == n - 1 {
        return BVH_END;
    }
    let next = last + 1;
    let is_leaf = next == n - 1 || !range_runs_up(next);
    return params.node_base + node_slot(next, is_leaf);
}

@compute @workgroup_size(256)
fn lbvh_hierarchy(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = params.count;
    if id.x >= n {
        return;
    }
    // Every thread writes its leaf; threads below n - 1 also build internal node id.x.
    let leaf = params.node_base + node_slot(i32(id.x), true);
    // One box per leaf: the count − 1 bits stay 0.
    nodes[leaf].entry = BVH_LEAF | (params.leaf_base + id.x);
    nodes[leaf].skip = skip_after(i32(id.x));
    primitives[params.primitive_base + id.x] = params.item_base + sorted_keys[id.x].y;
    if id.x == 0u {
        parents[0] = NO_PARENT;
    }
    if id.x + 1u >= n {
        return;
    }

    let i = i32(id.x);
    // Direction of the range and its other end (Karras, "Maximizing parallelism in the construction
    // of BVHs, octrees, and k-d trees", 2012).
    let d = select(-1, 1, range_runs_up(i));
    let min_prefix = common_prefix(i, i - d);
    var max_length = 2;
    while common_prefix(i, i + max_length * d) > min_prefix {
        max_length *= 2;
    }
    var length = 0;
    for (var step = max_length / 2; step >= 1; step /= 2) {
        if common_prefix(i, i + (length + step) * d) > min_prefix {
            length += step;
        }
    }
    let j = i + length * d;
    // The split: the last position sharing more than the range's common prefix with i.
    let node_prefix = common_prefix(i, j);
    var split = 0;
    var step = length;
    loop {
        step = (step + 1) / 2;
        if common_prefix(i, i + (split + step) * d) > node_prefix {
            split += step;
        }
        if step <= 1 {
            break;
        }
    }
    let gamma = i + split * d + min(d, 0);
    let left = child_node(gamma, min(i, j) == gamma);
    let right = child_node(gamma + 1, max(i, j) == gamma + 1);
    let first_child = node_slot(gamma, min(i, j) == gamma);
    let first = u32(min(i, j));
    let size = u32(max(i, j)) + 1u - first;
    // A small subtree becomes a leaf over its range of sorted boxes; the nodes below it are never
    // reached (the bounds pass still gives it the box of its whole range).
    let node = params.node_base + 2u * id.x;
    nodes[node].entry = select(params.node_base + first_child, BVH_LEAF | ((size - 1u) << BVH_LEAF_COUNT_SHIFT) | (params.leaf_base + first), size <= params.max_leaf_size);
    nodes[node].skip = skip_after(max(i, j));
    parents[left] = id.x;
    parents[right] = id.x;
    ranges[id.x] = vec2<u32>(u32(min(i, j)), u32(max(i, j)));
    // Only nodes spanning blocks collect their bounds in `node_bounds` (see `lbvh_bounds`).
    let block_start = id.x - id.x % BLOCK;
    if u32(min(i, j)) < block_start || u32(max(i, j)) >= block_start + BLOCK {
        for (var slot = 0u; slot < 6u; slot += 1u) {
            atomicStore(&node_bounds[id.x * 6u + slot], 0u);
        }
        if LIGHT_TREE {
            for (var slot = 0u; slot < TREE_SLOTS; slot += 1u) {
                atomicStore(&tree_bounds[id.x * TREE_SLOTS + slot], 0u);
            }
        }
    }
}

// A block is the 256 consecutive leaves of one `lbvh_bounds` workgroup. A node whose range lies inside
// one block is "block-local": its box is found in workgroup memory and written out by that workgroup;
// only the few nodes spanning blocks (about log n per block boundary) go through global atomics.
const BLOCK: u32 = 256u;

// Whether internal node `node`'s range lies in the block starting at leaf `block_start`.
fn in_block(node: u32, block_start: u32) -> bool {
    let range = ranges[node];
    return range.x >= block_start && range.y < block_start + BLOCK;
}

// The only block that can hold internal node `node` is its own index's: Karras ranges start or end there.
fn block_local(node: u32) -> bool {
    return in_block(node, node - node % BLOCK);
}

// Carries `values` (a box as order-preserving integers) up from internal node `start` with atomic max,
// one slot (min or max of an axis) at a time, and stops carrying a slot once a node already holds as
// much: whoever put that value there carries it (or found it) above, so every ancestor still ends up
// exact. Atomic max is order-independent: no thread waits for another and no memory ordering between
// threads is assumed.
// `values` holds 6 slots for `node_bounds` (a box) or, `to_tree`, TREE_SLOTS for `tree_bounds`.
fn carry_up_globally(start: u32, values: array<u32, TREE_SLOTS>, to_tree: bool) {
    let slots = select(6u, TREE_SLOTS, to_tree);
    var rising = (1u << slots) - 1u;
    var node = start;
    loop {
        for (var slot = 0u; slot < slots; slot += 1u) {
            if (rising & (1u << slot)) == 0u {
                continue;
            }
            var held: u32;
            if to_tree {
                held = atomicMax(&tree_bounds[node * TREE_SLOTS + slot], values[slot]);
            } else {
                held = atomicMax(&node_bounds[node * 6u + slot], values[slot]);
            }
            if held >= values[slot] {
                rising &= ~(1u << slot);
            }
        }
        if rising == 0u || node == 0u {
            break;
        }
        node = parents[node];
    }
}

fn ordered_box(min_corner: vec3<f32>, max_corner: vec3<f32>) -> array<u32, TREE_SLOTS> {
    var values: array<u32, TREE_SLOTS>;
    for (var axis = 0u; axis < 3u; axis += 1u) {
        values[axis] = ~ordered(min_corner[axis]);
        values[axis + 3u] = ordered(max_corner[axis]);
    }
    return values;
}

// The block's leaf boxes, by position in the block.
var<workgroup> block_min: array<vec3<f32>, BLOCK>;
var<workgroup> block_max: array<vec3<f32>, BLOCK>;

// Each leaf writes its own box into its node and workgroup memory; then each block-local internal node
// takes the union of its range's leaves there, with no atomics and no thread waiting on another; the
// boxes of the block's topmost nodes (and of leaves whose parent spans blocks) are carried on
// globally. Looping over ranges of up to 256 boxes in workgroup memory built up to 65k boxes as fast
// or up to 5 % sooner than carrying each leaf's box up the block's nodes with workgroup atomics, which
// contend near the block's top (benchmarks/LOG.md, topic 1).
@compute @workgroup_size(256)
fn lbvh_bounds(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let n = params.count;
    let block_start = group.x * BLOCK;
    let k = block_start + local;
    let leaf = n - 1u + k;
    var leaf_values: array<u32, TREE_SLOTS>;
    if k < n {
        let b = boxes[sorted_keys[k].y];
        let slot = params.node_base + node_slot(i32(k), true);
        nodes[slot].min = b.min.xyz;
        nodes[slot].max = b.max.xyz;
        block_min[local] = b.min.xyz;
        block_max[local] = b.max.xyz;
        leaf_values = ordered_box(b.min.xyz, b.max.xyz);
    }
    workgroupBarrier();

    // Internal node `k` (this thread's index in the block), if it is block-local.
    if k + 1u < n && in_block(k, block_start) {
        let range = ranges[k] - vec2<u32>(block_start);
        var low = block_min[range.x];
        var high = block_max[range.x];
        for (var j = range.x + 1u; j <= range.y; j += 1u) {
            low = min(low, block_min[j]);
            high = max(high, block_max[j]);
        }
        let node = params.node_base + 2u * k;
        nodes[node].min = low;
        nodes[node].max = high;
        let parent = parents[k];
        if parent != NO_PARENT && !in_block(parent, block_start) {
            carry_up_globally(parent, ordered_box(low, high), false);
        }
    }
    // Leaf `k`, if its parent spans blocks (a lone leaf is the root: nothing above it).
    if k < n && n > 1u && !in_block(parents[leaf], block_start) {
        carry_up_globally(parents[leaf], leaf_values, false);
    }
}

// The block's emitters, by position in the block, and its leaves' power summed from the block's
// first leaf (`power_up`) and to its last (`power_down`).
var<workgroup> block_emitter_min: array<vec3<f32>, BLOCK>;
var<workgroup> block_emitter_max: array<vec3<f32>, BLOCK>;
var<workgroup> block_range: array<f32, BLOCK>;
var<workgroup> block_leaf_power: array<f32, BLOCK>;
var<workgroup> power_up: array<f32, BLOCK>;
var<workgroup> power_down: array<f32, BLOCK>;

fn emitters_values(e: LightTreeNode, largest_power: f32) -> array<u32, TREE_SLOTS> {
    var values = ordered_box(e.min, e.max);
    values[6] = ordered(e.range);
    values[7] = ordered(largest_power);
    return values;
}

// LIGHT_TREE only, after `lbvh_bounds`, over the same blocks: each leaf's emitter goes to its node,
// the block's power is scanned both ways, each block-local internal node takes the union of its
// range's emitters (its power summed leaf by leaf), and what spans blocks is carried on globally.
@compute @workgroup_size(256)
fn lbvh_emitters(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let n = params.count;
    let block_start = group.x * BLOCK;
    let k = block_start + local;
    var e = LightTreeNode(vec3<f32>(3.4e38), 0.0, vec3<f32>(-3.4e38), 0.0);
    if k < n {
        e = emitters[sorted_keys[k].y];
        tree[params.node_base + node_slot(i32(k), true)] = e;
    }
    block_emitter_min[local] = e.min;
    block_emitter_max[local] = e.max;
    block_range[local] = e.range;
    block_leaf_power[local] = e.power;
    power_up[local] = e.power;
    power_down[local] = e.power;
    workgroupBarrier();
    // Hillis–Steele, both ways at once.
    for (var offset = 1u; offset < BLOCK; offset *= 2u) {
        var below = 0.0;
        if local >= offset {
            below = power_up[local - offset];
        }
        var above = 0.0;
        if local + offset < BLOCK {
            above = power_down[local + offset];
        }
        workgroupBarrier();
        power_up[local] += below;
        power_down[local] += above;
        workgroupBarrier();
    }
    if k < n {
        leaf_power[k] = vec2<f32>(power_up[local], power_down[local]);
    }
    if local == 0u {
        block_power[group.x] = power_down[0];
    }

    if k + 1u < n && in_block(k, block_start) {
        let range = ranges[k] - vec2<u32>(block_start);
        var merged = LightTreeNode(block_emitter_min[range.x], 0.0, block_emitter_max[range.x], 0.0);
        var largest_power = 0.0;
        for (var j = range.x; j <= range.y; j += 1u) {
            merged.min = min(merged.min, block_emitter_min[j]);
            merged.max = max(merged.max, block_emitter_max[j]);
            merged.range = max(merged.range, block_range[j]);
            merged.power += block_leaf_power[j];
            largest_power = max(largest_power, block_leaf_power[j]);
        }
        tree[params.node_base + 2u * k] = merged;
        let parent = parents[k];
        if parent != NO_PARENT && !in_block(parent, block_start) {
            carry_up_globally(parent, emitters_values(merged, largest_power), true);
        }
    }
    let leaf = n - 1u + k;
    if k < n && n > 1u && !in_block(parents[leaf], block_start) {
        carry_up_globally(parents[leaf], emitters_values(e, e.power), true);
    }
}

// LIGHT_TREE only, one workgroup: turns each block's power into the total of the blocks before it.
@compute @workgroup_size(256)
fn lbvh_block_power(@builtin(local_invocation_index) local: u32) {
    let blocks = (params.count + BLOCK - 1u) / BLOCK;
    let chunk = (blocks + BLOCK - 1u) / BLOCK;
    let first = min(local * chunk, blocks);
    let end = min(first + chunk, blocks);
    var sum = 0.0;
    for (var b = first; b < end; b += 1u) {
        sum += block_power[b];
    }
    power_up[local] = sum;
    workgroupBarrier();
    for (var offset = 1u; offset < BLOCK; offset *= 2u) {
        var below = 0.0;
        if local >= offset {
            below = power_up[local - offset];
        }
        workgroupBarrier();
        power_up[local] += below;
        workgroupBarrier();
    }
    // The chunks before this thread's, summed by the scan: exactly 0 after dark chunks.
    var before = 0.0;
    if local > 0u {
        before = power_up[local - 1u];
    }
    for (var b = first; b < end; b += 1u) {
        let own = block_power[b];
        block_power[b] = before;
        before += own;
    }
}

// Internal nodes spanning blocks only: `lbvh_bounds` (and `lbvh_emitters`) wrote the others.
@compute @workgroup_size(256)
fn lbvh_write_nodes(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x + 1u >= params.count || block_local(id.x) {
        return;
    }
    let base = id.x * 6u;
    let node = params.node_base + 2u * id.x;
    nodes[node].min = vec3<f32>(unordered(~atomicLoad(&node_bounds[base])), unordered(~atomicLoad(&node_bounds[base + 1u])), unordered(~atomicLoad(&node_bounds[base + 2u])));
    nodes[node].max = vec3<f32>(unordered(atomicLoad(&node_bounds[base + 3u])), unordered(atomicLoad(&node_bounds[base + 4u])), unordered(atomicLoad(&node_bounds[base + 5u])));
    if LIGHT_TREE {
        let slots = id.x * TREE_SLOTS;
        var e: LightTreeNode;
        e.min = vec3<f32>(unordered(~atomicLoad(&tree_bounds[slots])), unordered(~atomicLoad(&tree_bounds[slots + 1u])), unordered(~atomicLoad(&tree_bounds[slots + 2u])));
        e.max = vec3<f32>(unordered(atomicLoad(&tree_bounds[slots + 3u])), unordered(atomicLoad(&tree_bounds[slots + 4u])), unordered(atomicLoad(&tree_bounds[slots + 5u])));
        e.range = unordered(atomicLoad(&tree_bounds[slots + 6u]));
        // The range [x, y] spans blocks: the rest of x's block, the start of y's, the whole blocks
        // between. Prefix sums over blocks can round a small middle away next to a large total; the
        // largest single power keeps a node whose lights shine from weighing nothing.
        let range = ranges[id.x];
        let first_block = range.x / BLOCK;
        let last_block = range.y / BLOCK;
        var between = 0.0;
        if last_block > first_block + 1u {
            between = max(block_power[last_block] - block_power[first_block + 1u], 0.0);
        }
        let largest = unordered(atomicLoad(&tree_bounds[slots + 7u]));
        e.power = max(leaf_power[range.x].y + leaf_power[range.y].x + between, largest);
        tree[node] = e;
    }
}
