// Builds the clustered method's per-froxel lists of volumes (`accel/clusters.rs`) every frame:
//
// 1. `cluster_count`: a thread per (instance, item) pair bounds the volume in the world, finds the
//    froxels of its bounds (`cluster_grid.wgsl`) and counts itself into each; a volume reaching more
//    than SPREAD_FROXELS froxels is queued instead, and `cluster_count_spread` gives each queued
//    volume a workgroup whose threads share its froxels (a wall-sized decal reaches about 60,000,
//    far too many for one thread; benchmarks/LOG.md, topic 1);
// 2. `cluster_scan_blocks`, `cluster_scan_block_offsets`, `cluster_scan_apply`: exclusive prefix sums
//    of the counts, in blocks of SCAN_THREADS froxels, turn them into list ranges;
// 3. `cluster_fill`, `cluster_fill_spread`: the same threads and workgroups write the volumes into
//    their froxels' lists.
//
// A volume's bounds are a sphere and an oriented box in its group's space, both containing it; a
// froxel is listed when both reach it (projected rectangle and depth range).
#include "accel/cluster_grid.wgsl"
#include "accel/bvh_types.wgsl"
#include "accel/workgroup_scan.wgsl"

// Keep in sync with `ClusterBounds` in `accel/clusters.rs`.
struct ClusterBounds {
    // xyz centre, w radius
    sphere: vec4<f32>,
    box_center: vec4<f32>,
    // Half extents along the box's axes.
    box_axis_x: vec4<f32>,
    box_axis_y: vec4<f32>,
    box_axis_z: vec4<f32>,
}

// Keep in sync with `ClusterBuildParams` in `accel/clusters.rs`.
struct ClusterBuildParams {
    pair_count: u32,
    instance_count: u32,
    // Entries the lists can hold: a frame that needs more is rendered again with more room.
    capacity: u32,
    // Threads per row of the pair dispatch (x workgroups × 64).
    row_threads: u32,
}

@group(1) @binding(0) var<uniform> params: ClusterBuildParams;
@group(1) @binding(1) var<storage, read> instances: array<VolumeInstance>;
@group(1) @binding(2) var<storage, read> bounds: array<ClusterBounds>;
// Per instance, its first pair; instance_count + 1 values.
@group(1) @binding(3) var<storage, read> pair_starts: array<u32>;
@group(1) @binding(4) var<storage, read_write> counts: array<atomic<u32>>;
// Per froxel: its list's first entry and length.
@group(1) @binding(5) var<storage, read_write> ranges: array<vec2<u32>>;
@group(1) @binding(6) var<storage, read_write> cursors: array<atomic<u32>>;
// (instance, item) pairs, froxel after froxel.
@group(1) @binding(7) var<storage, read_write> entries: array<vec2<u32>>;
@group(1) @binding(8) var<storage, read_write> block_sums: array<u32>;
// [0]: entries this frame's lists need; [1]: the most any frame needed since the renderer last
// looked (`ClusterLists::fitted`).
@group(1) @binding(9) var<storage, read_write> status: array<u32>;

// Pairs (as indices below `pair_count`) reaching more than SPREAD_FROXELS froxels, queued by
// `cluster_count` for the spread passes; `count` is cleared before each frame's build. Room for every
// pair, each queued at most once.
struct SpreadQueue {
    count: atomic<u32>,
    pairs: array<u32>,
}
@group(1) @binding(10) var<storage, read_write> spread: SpreadQueue;

// Froxels one thread walks by itself; larger volumes are spread over a workgroup.
const SPREAD_FROXELS: u32 = 32u;
// Workgroups of the spread passes, each taking every SPREAD_WORKGROUPS-th queued volume. Keep in sync
// with `SPREAD_WORKGROUPS` in `accel/clusters.rs`.
const SPREAD_WORKGROUPS: u32 = 1024u;
const SPREAD_THREADS: u32 = 64u;

const FAR: f32 = 1e30;

// The froxels a volume may reach, as inclusive ranges of tile column, row and slice; x > y of
// `first` when it reaches none that a visible point can lie in.
struct FroxelRange {
    first: vec3<u32>,
    last: vec3<u32>,
    empty: bool,
}

// Extends a projected rectangle (xy min, zw max in NDC) by a world point.
fn grow_rect(rect: ptr<function, vec4<f32>>, world: vec3<f32>) {
    let clip = cluster_clip(world);
    let ndc = clip.xy / clip.w;
    *rect = vec4<f32>(min((*rect).xy, ndc), max((*rect).zw, ndc));
}

// Visible points lie at least this far in front of the camera (its near plane, less rounding's worth).
fn cluster_visible_depth() -> f32 {
    return frame.cluster_depth.z - 1e-4 * abs(frame.cluster_depth.z);
}

// The projected rectangle of the part of the box with centre `c` and half-axes `a` that lies beyond
// the near plane, where points can be visible. With every corner beyond it, the corners' rectangle;
// otherwise the rectangle of the box's view-space bounds cut at the near plane (projecting corners
// behind the camera bounds nothing, and a full-screen rectangle would list a volume grazing the
// camera in every tile). Empty (min > max) when nothing of the box is beyond the near plane.
fn box_rect(c: vec3<f32>, a: mat3x3<f32>) -> vec4<f32> {
    let near = cluster_visible_depth();
    var rect = vec4<f32>(FAR, FAR, -FAR, -FAR);
    var beyond_near = true;
    for (var corner = 0u; corner < 8u; corner += 1u) {
        let s = vec3<f32>(vec3<u32>(corner, corner >> 1u, corner >> 2u) & vec3<u32>(1u)) * 2.0 - 1.0;
        let world = c + a * s;
        beyond_near = beyond_near && cluster_view_depth(world) >= near;
        grow_rect(&rect, world);
    }
    if beyond_near {
        return rect;
    }
    let eye = frame.world_from_view[3].xyz;
    let view_axes = mat3x3<f32>(frame.world_from_view[0].xyz, frame.world_from_view[1].xyz, -frame.world_from_view[2].xyz);
    // The box in view space (x right, y up, z depth): centre and half extents along those axes.
    let centre = (c - eye) * view_axes;
    let half = vec3<f32>(dot(abs(view_axes[0] * a), vec3<f32>(1.0)), dot(abs(view_axes[1] * a), vec3<f32>(1.0)), dot(abs(view_axes[2] * a), vec3<f32>(1.0)));
    var low = centre - half;
    let high = centre + half;
    rect = vec4<f32>(FAR, FAR, -FAR, -FAR);
    if high.z < near {
        return rect;
    }
    low.z = max(low.z, near);
    for (var corner = 0u; corner < 8u; corner += 1u) {
        let pick = vec3<bool>((vec3<u32>(corner, corner >> 1u, corner >> 2u) & vec3<u32>(1u)) == vec3<u32>(1u));
        grow_rect(&rect, eye + view_axes * select(low, high, pick));
    }
    return rect;
}

fn volume_froxels(instance: VolumeInstance, b: ClusterBounds) -> FroxelRange {
    let right = frame.world_from_view[0].xyz;
    let up = frame.world_from_view[1].xyz;
    let forward = -frame.world_from_view[2].xyz;

    // The sphere, bounded by the cube around it along the camera's axes.
    let center = instance_point_to_world(instance, b.sphere.xyz);
    let radius = b.sphere.w * instance.scale;
    let sphere_depth = cluster_view_depth(center);
    var rect = box_rect(center, mat3x3<f32>(right * radius, up * radius, forward * radius));
    var depth = vec2<f32>(sphere_depth - radius, sphere_depth + radius);

    // The oriented box.
    let box_center = instance_point_to_world(instance, b.box_center.xyz);
    let axes = mat3x3<f32>(
        (vec4<f32>(b.box_axis_x.xyz, 0.0) * instance.world_from_group),
        (vec4<f32>(b.box_axis_y.xyz, 0.0) * instance.world_from_group),
        (vec4<f32>(b.box_axis_z.xyz, 0.0) * instance.world_from_group),
    );
    let box_depth = cluster_view_depth(box_center);
    let box_extent = dot(abs(forward * axes), vec3<f32>(1.0));
    let box = box_rect(box_center, axes);
    rect = vec4<f32>(max(rect.xy, box.xy), min(rect.zw, box.zw));
    depth = vec2<f32>(max(depth.x, box_depth - box_extent), min(depth.y, box_depth + box_extent));

    // Visible points lie in front of the camera and inside the screen.
    var range: FroxelRange;
    range.empty = depth.y < cluster_visible_depth() || any(rect.xy > vec2<f32>(1.0)) || any(rect.zw < vec2<f32>(-1.0));
    // Widened by rounding's worth, so a point on the bounds never falls in a froxel outside them.
    rect += vec4<f32>(-1e-4, -1e-4, 1e-4, 1e-4);
    depth += vec2<f32>(-1e-5, 1e-5) * abs(depth) - vec2<f32>(1e-7, -1e-7);
    // Rows run top to bottom: the rectangle's top edge (max y) is the first row.
    let first_tile = cluster_tile(vec2<f32>(rect.x, rect.w));
    let last_tile = cluster_tile(vec2<f32>(rect.z, rect.y));
    range.first = vec3<u32>(first_tile, cluster_slice(depth.x));
    range.last = vec3<u32>(last_tile, cluster_slice(depth.y));
    return range;
}

// The pair with index `pair` (below `pair_count`), as (instance, item).
fn pair_of(pair: u32) -> vec2<u32> {
    // The last instance whose first pair is at or before `pair`.
    var lo = 0u;
    var hi = params.instance_count;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if pair_starts[mid] <= pair {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return vec2<u32>(lo, instances[lo].first_item + pair - pair_starts[lo]);
}

fn froxel_count(range: FroxelRange) -> u32 {
    let size = range.last - range.first + 1u;
    return size.x * size.y * size.z;
}

// Counts the pair into the froxel (`fill` false), or, once the counts are prefix sums, writes it into
// the froxel's list.
fn visit_froxel(pair: vec2<u32>, froxel: u32, fill: bool) {
    if fill {
        let entry = ranges[froxel].x + atomicAdd(&cursors[froxel], 1u);
        if entry < params.capacity {
            entries[entry] = pair;
        }
    } else {
        atomicAdd(&counts[froxel], 1u);
    }
}

// Walks the froxels the thread's pair may reach, unless there are more than SPREAD_FROXELS: those
// pairs the count pass queues for the spread passes.
fn cluster_visit(id: vec3<u32>, fill: bool) {
    let index = id.y * params.row_threads + id.x;
    if index >= params.pair_count {
        return;
    }
    let pair = pair_of(index);
    let range = volume_froxels(instances[pair.x], bounds[pair.y]);
    if range.empty {
        return;
    }
    if froxel_count(range) > SPREAD_FROXELS {
        if !fill {
            spread.pairs[atomicAdd(&spread.count, 1u)] = index;
        }
        return;
    }
    for (var z = range.first.z; z <= range.last.z; z += 1u) {
        for (var y = range.first.y; y <= range.last.y; y += 1u) {
            for (var x = range.first.x; x <= range.last.x; x += 1u) {
                visit_froxel(pair, cluster_index(vec2<u32>(x, y), z), fill);
            }
        }
    }
}

// A workgroup's share of the queued pairs, their froxels shared among its threads.
fn cluster_spread(group: u32, local: u32, fill: bool) {
    let queued = atomicLoad(&spread.count);
    for (var slot = group; slot < queued; slot += SPREAD_WORKGROUPS) {
        let pair = pair_of(spread.pairs[slot]);
        let range = volume_froxels(instances[pair.x], bounds[pair.y]);
        let size = range.last - range.first + 1u;
        for (var i = local; i < froxel_count(range); i += SPREAD_THREADS) {
            let column = range.first.x + i % size.x;
            let row = range.first.y + (i / size.x) % size.y;
            let slice = range.first.z + i / (size.x * size.y);
            visit_froxel(pair, cluster_index(vec2<u32>(column, row), slice), fill);
        }
    }
}

@compute @workgroup_size(64)
fn cluster_count(@builtin(global_invocation_id) id: vec3<u32>) {
    cluster_visit(id, false);
}

@compute @workgroup_size(SPREAD_THREADS)
fn cluster_count_spread(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    cluster_spread(group.x, local, false);
}

// Per block of SCAN_THREADS froxels: offsets within the block, and the block's total.
@compute @workgroup_size(256)
fn cluster_scan_blocks(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>,
                       @builtin(local_invocation_index) local: u32) {
    let froxel = id.x;
    let inside = froxel < cluster_froxel_count();
    let count = select(0u, atomicLoad(&counts[min(froxel, cluster_froxel_count() - 1u)]), inside);
    let scanned = workgroup_exclusive_scan(local, count);
    if inside {
        ranges[froxel] = vec2<u32>(scanned.x, count);
    }
    if local == 0u {
        block_sums[group.x] = scanned.y;
    }
}

// One workgroup: block totals into block offsets (each thread sums a run of blocks), and the total.
@compute @workgroup_size(256)
fn cluster_scan_block_offsets(@builtin(local_invocation_index) local: u32) {
    let blocks = (cluster_froxel_count() + SCAN_THREADS - 1u) / SCAN_THREADS;
    let per_thread = (blocks + SCAN_THREADS - 1u) / SCAN_THREADS;
    let first = min(local * per_thread, blocks);
    let last = min(first + per_thread, blocks);
    var sum = 0u;
    for (var b = first; b < last; b += 1u) {
        sum += block_sums[b];
    }
    let scanned = workgroup_exclusive_scan(local, sum);
    var offset = scanned.x;
    for (var b = first; b < last; b += 1u) {
        let block = block_sums[b];
        block_sums[b] = offset;
        offset += block;
    }
    if local == 0u {
        status[0] = scanned.y;
        status[1] = max(status[1], scanned.y);
    }
}

@compute @workgroup_size(256)
fn cluster_scan_apply(@builtin(global_invocation_id) id: vec3<u32>, @builtin(workgroup_id) group: vec3<u32>) {
    if id.x < cluster_froxel_count() {
        ranges[id.x].x += block_sums[group.x];
        atomicStore(&cursors[id.x], 0u);
    }
}

@compute @workgroup_size(64)
fn cluster_fill(@builtin(global_invocation_id) id: vec3<u32>) {
    cluster_visit(id, true);
}

@compute @workgroup_size(SPREAD_THREADS)
fn cluster_fill_spread(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    cluster_spread(group.x, local, true);
}
