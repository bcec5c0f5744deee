// LBVH build on the GPU (Karras 2012), over `params.count` boxes, into the node layout of
// `accel/bvh_types.wgsl`: scene bounds of the box centres → 30-bit Morton codes → (radix sort, lampshade)
// → one thread per internal node finds its range and split → bounds propagated from the leaves up.
// Node indices: internal nodes 0 .. count - 2 (root 0), leaf k at count - 1 + k, all offset by
// `node_base` in `nodes`: several BVHs (a top level and the groups' BVHs) share one node array, so the
// query needs no binding per BVH. Leaves name `primitives[primitive_base + k]`, which holds
// `item_base` + the index of the box among this build's boxes.
#include "accel/bvh_types.wgsl"

struct LbvhParams {
    count: u32,
    node_base: u32,
    primitive_base: u32,
    item_base: u32,
}

struct Box {
    min: vec4<f32>,
    max: vec4<f32>,
}

const NO_PARENT: u32 = 0xffffffffu;

@group(0) @binding(0) var<uniform> params: LbvhParams;
@group(0) @binding(1) var<storage, read> boxes: array<Box>;
// Centre bounds as order-preserving integers: 0..2 hold ~min (maximised), 3..5 max.
@group(0) @binding(2) var<storage, read_write> centre_bounds: array<atomic<u32>, 6>;
// (Morton code, box index): the sort's input ...
@group(0) @binding(3) var<storage, read_write> keys: array<vec2<u32>>;
// ... and its output.
@group(0) @binding(4) var<storage, read> sorted_keys: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read_write> nodes: array<BvhNode>;
@group(0) @binding(6) var<storage, read_write> primitives: array<u32>;
@group(0) @binding(7) var<storage, read_write> parents: array<u32>;
// Internal nodes' bounds as order-preserving integers, 6 per node like `centre_bounds`; cleared to 0.
@group(0) @binding(8) var<storage, read_write> node_bounds: array<atomic<u32>>;

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

var<workgroup> group_bounds: array<atomic<u32>, 6>;

@compute @workgroup_size(256)
fn lbvh_centre_bounds(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    if local < 6u {
        atomicStore(&group_bounds[local], 0u);
    }
    workgroupBarrier();
    if id.x < params.count {
        let c = box_centre(boxes[id.x]);
        for (var axis = 0u; axis < 3u; axis += 1u) {
            atomicMax(&group_bounds[axis], ~ordered(c[axis]));
            atomicMax(&group_bounds[axis + 3u], ordered(c[axis]));
        }
    }
    workgroupBarrier();
    // One global atomic per workgroup and slot instead of one per box.
    if local < 6u {
        atomicMax(&centre_bounds[local], atomicLoad(&group_bounds[local]));
    }
}

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
    let low = vec3<f32>(unordered(~atomicLoad(&centre_bounds[0])), unordered(~atomicLoad(&centre_bounds[1])), unordered(~atomicLoad(&centre_bounds[2])));
    let high = vec3<f32>(unordered(atomicLoad(&centre_bounds[3])), unordered(atomicLoad(&centre_bounds[4])), unordered(atomicLoad(&centre_bounds[5])));
    let extent = max(high - low, vec3<f32>(1e-30));
    let cell = vec3<u32>(clamp((box_centre(boxes[id.x]) - low) / extent * 1024.0, vec3<f32>(0.0), vec3<f32>(1023.0)));
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

// Local node index (within this build) of a child.
fn child_node(index: i32, is_leaf: bool) -> u32 {
    return select(u32(index), params.count - 1u + u32(index), is_leaf);
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
    return params.node_base + child_node(next, is_leaf);
}

@compute @workgroup_size(256)
fn lbvh_hierarchy(@builtin(global_invocation_id) id: vec3<u32>) {
    let n = params.count;
    if id.x >= n {
        return;
    }
    // Every thread writes its leaf; threads below n - 1 also build internal node id.x.
    let leaf = params.node_base + n - 1u + id.x;
    // One box per leaf: the count − 1 bits stay 0.
    nodes[leaf].entry = BVH_LEAF | (params.primitive_base + id.x);
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
    nodes[params.node_base + id.x].entry = params.node_base + left;
    nodes[params.node_base + id.x].skip = skip_after(max(i, j));
    parents[left] = id.x;
    parents[right] = id.x;
}

// Each leaf writes its own box, then carries it up the tree with atomic max, one slot (min or max of
// an axis) at a time, and stops carrying a slot once a node already holds as much: whoever put that
// value there carries it (or found it) above, so every ancestor still ends up exact. Atomic max is
// order-independent, so no thread waits for another and no memory ordering between threads is
// assumed; stopping early keeps thousands of threads from queueing on the root (6.2 → see
// BENCHMARKS.md at 1M boxes).
@compute @workgroup_size(256)
fn lbvh_bounds(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.count {
        return;
    }
    let b = boxes[sorted_keys[id.x].y];
    let leaf = params.count - 1u + id.x;
    nodes[params.node_base + leaf].min = b.min.xyz;
    nodes[params.node_base + leaf].max = b.max.xyz;
    if leaf == 0u {
        // A lone leaf is the root.
        return;
    }
    var values: array<u32, 6>;
    for (var axis = 0u; axis < 3u; axis += 1u) {
        values[axis] = ~ordered(b.min[axis]);
        values[axis + 3u] = ordered(b.max[axis]);
    }
    var rising = 0x3fu;
    var node = parents[leaf];
    loop {
        for (var slot = 0u; slot < 6u; slot += 1u) {
            if (rising & (1u << slot)) != 0u && atomicMax(&node_bounds[node * 6u + slot], values[slot]) >= values[slot] {
                rising &= ~(1u << slot);
            }
        }
        if rising == 0u || node == 0u {
            break;
        }
        node = parents[node];
    }
}

// Internal nodes only: leaves wrote their boxes in `lbvh_bounds`.
@compute @workgroup_size(256)
fn lbvh_write_nodes(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x + 1u >= params.count {
        return;
    }
    let base = id.x * 6u;
    let node = params.node_base + id.x;
    for (var axis = 0u; axis < 3u; axis += 1u) {
        nodes[node].min[axis] = unordered(~atomicLoad(&node_bounds[base + axis]));
        nodes[node].max[axis] = unordered(atomicLoad(&node_bounds[base + 3u + axis]));
    }
}
