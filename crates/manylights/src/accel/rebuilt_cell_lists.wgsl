// Cell lists built on the GPU, once or every frame (`accel/rebuilt_cell_lists.rs`): a uniform grid over a
// group whose cells list every volume that may reach them, as (instance, item) pairs in the clustered
// lists' format, built in four passes:
//
// 1. `cell_lists_count`: a thread per volume counts itself into each cell its box meets and its
//    sphere and oriented box reach;
// 2. `cell_lists_scan_blocks`: exclusive prefix sums of the counts within blocks of BLOCK_CELLS cells,
//    and each block's total; each cell's count moves to its cursor, and the count is reset to zero
//    for the next frame;
// 3. `cell_lists_scan_offsets`: each block adds the totals of the blocks before it, giving every
//    cell the range of its list, and the last block records how many entries the lists need;
// 4. `cell_lists_fill`: the same threads as the count write themselves into those cells' lists,
//    counting each cell's cursor down. A volume the fill sees in a cell the count did not (should
//    the two passes' arithmetic ever round differently) finds the cursor at zero and is left out,
//    and counts never carry over into the next frame.
//
// Cells are widened by a margin, and those on the grid's faces reach out to infinity: a point looks up
// its cell clamped into the grid (`cell_list_index` in `accel/bvh_types.wgsl`), so a volume that
// moved past the grid's faces is still listed where such points look.
#include "accel/workgroup_scan.wgsl"

// Keep in sync with `CellListParams` in `accel/rebuilt_cell_lists.rs`.
struct CellListParams {
    min: vec3<f32>,
    item_count: u32,
    cell_size: vec3<f32>,
    // The group's first item in the structure: entries name items by their index there.
    first_item: u32,
    cells_per_unit: vec3<f32>,
    // Entries the lists can hold: a frame that needs more is rendered again with more room.
    capacity: u32,
    dims: vec3<u32>,
    block_count: u32,
    margin: vec3<f32>,
    // Threads per row of the per-volume dispatch (x workgroups × VOLUME_THREADS).
    row_threads: u32,
}

// A volume's bounds in its group's space, each containing it: a sphere, a box, and an oriented box as
// the rows of the map into its unit cube [-0.5, 0.5]³ (zero rows where there is none). Keep in sync
// with `ListBounds` in `accel/rebuilt_cell_lists.rs`.
struct ListBounds {
    // xyz centre, w radius.
    sphere: vec4<f32>,
    low: vec4<f32>,
    high: vec4<f32>,
    unit_from_group: array<vec4<f32>, 3>,
}

@group(0) @binding(0) var<uniform> params: CellListParams;
@group(0) @binding(1) var<storage, read> bounds: array<ListBounds>;
// Per cell, how many volumes it lists: zero between frames.
@group(0) @binding(2) var<storage, read_write> counts: array<atomic<u32>>;
// Per cell, the entries of its list the fill has yet to write.
@group(0) @binding(7) var<storage, read_write> cursors: array<atomic<u32>>;
// Per cell: its list's first entry and length (bound to shading).
@group(0) @binding(3) var<storage, read_write> ranges: array<vec2<u32>>;
// (instance, item) pairs, cell after cell (bound to shading).
@group(0) @binding(4) var<storage, read_write> entries: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read_write> block_sums: array<u32>;
// [0]: entries this frame's lists need; [1]: the most any frame needed since the renderer last
// looked (`RebuiltCellLists::fitted`).
@group(0) @binding(6) var<storage, read_write> status: array<atomic<u32>>;

const VOLUME_THREADS: u32 = 64u;
// Cells per block of the scans: four per thread. Keep in sync with `BLOCK_CELLS` in
// `accel/rebuilt_cell_lists.rs`.
const BLOCK_CELLS: u32 = 4u * SCAN_THREADS;
// Beyond any finite coordinate: the grid's faces reach out to it.
const FAR: f32 = 3.0e38;

fn cell_count() -> u32 {
    return params.dims.x * params.dims.y * params.dims.z;
}

fn clamped_cell(p: vec3<f32>) -> vec3<u32> {
    return vec3<u32>(clamp(floor((p - params.min) * params.cells_per_unit), vec3<f32>(0.0), vec3<f32>(params.dims - 1u)));
}

// Whether the volume's sphere and oriented box both reach the (widened) cell. The oriented box is
// tested along its own three axes (the cell's are the box's, which the caller's range has tested):
// along each, the cell's centre lies within half the unit cube plus the cell's reach, with a
// ten-thousandth more for rounding, as the CPU-built lists test decals (`decal_may_reach`). Cells on
// the grid's faces reach out to infinity: only the sphere bounds them.
fn volume_reaches_cell(b: ListBounds, cell: vec3<u32>) -> bool {
    let corner = params.min + vec3<f32>(cell) * params.cell_size;
    let on_face = any(cell == vec3<u32>(0u)) || any(cell == params.dims - 1u);
    let low = select(corner - params.margin, vec3<f32>(-FAR), cell == vec3<u32>(0u));
    let high = select(corner + params.cell_size + params.margin, vec3<f32>(FAR), cell == params.dims - 1u);
    let gap = max(max(low - b.sphere.xyz, b.sphere.xyz - high), vec3<f32>(0.0));
    if dot(gap, gap) > b.sphere.w * b.sphere.w {
        return false;
    }
    if on_face {
        return true;
    }
    let centre = corner + 0.5 * params.cell_size;
    let half = 0.5 * params.cell_size + params.margin;
    for (var i = 0u; i < 3u; i += 1u) {
        let row = b.unit_from_group[i];
        let reach = dot(abs(row.xyz), half);
        if abs(dot(row.xyz, centre) + row.w) > 0.5 + reach + 1e-4 * (1.0 + reach) {
            return false;
        }
    }
    return true;
}

// Counts the volume into its cells (`fill` false), or writes it into their lists (`fill` true).
fn visit_cells(item: u32, fill: bool) {
    let b = bounds[item];
    let first = clamped_cell(b.low.xyz - params.margin);
    let last = clamped_cell(b.high.xyz + params.margin);
    for (var z = first.z; z <= last.z; z += 1u) {
        for (var y = first.y; y <= last.y; y += 1u) {
            for (var x = first.x; x <= last.x; x += 1u) {
                if !volume_reaches_cell(b, vec3<u32>(x, y, z)) {
                    continue;
                }
                let cell = (z * params.dims.y + y) * params.dims.x + x;
                if !fill {
                    atomicAdd(&counts[cell], 1u);
                    continue;
                }
                let left = atomicSub(&cursors[cell], 1u);
                let slot = ranges[cell].x + left - 1u;
                if left > 0u && slot < params.capacity {
                    entries[slot] = vec2<u32>(0u, params.first_item + item);
                }
            }
        }
    }
}

@compute @workgroup_size(VOLUME_THREADS)
fn cell_lists_count(@builtin(global_invocation_id) id: vec3<u32>) {
    let item = id.y * params.row_threads + id.x;
    if item < params.item_count {
        visit_cells(item, false);
    }
}

@compute @workgroup_size(SCAN_THREADS)
fn cell_lists_scan_blocks(@builtin(local_invocation_index) local: u32, @builtin(workgroup_id) group: vec3<u32>) {
    let first = group.x * BLOCK_CELLS + 4u * local;
    var count = vec4<u32>(0u);
    for (var i = 0u; i < 4u; i += 1u) {
        if first + i < cell_count() {
            count[i] = atomicExchange(&counts[first + i], 0u);
            atomicStore(&cursors[first + i], count[i]);
        }
    }
    let scan = workgroup_exclusive_scan(local, count.x + count.y + count.z + count.w);
    var offset = scan.x;
    for (var i = 0u; i < 4u; i += 1u) {
        if first + i < cell_count() {
            ranges[first + i] = vec2<u32>(offset, count[i]);
        }
        offset += count[i];
    }
    if local == 0u {
        block_sums[group.x] = scan.y;
    }
}

@compute @workgroup_size(SCAN_THREADS)
fn cell_lists_scan_offsets(@builtin(local_invocation_index) local: u32, @builtin(workgroup_id) group: vec3<u32>) {
    var before = 0u;
    for (var block = local; block < group.x; block += SCAN_THREADS) {
        before += block_sums[block];
    }
    let base = workgroup_exclusive_scan(local, before).y;
    let first = group.x * BLOCK_CELLS + 4u * local;
    for (var i = 0u; i < 4u; i += 1u) {
        if first + i < cell_count() {
            ranges[first + i].x += base;
        }
    }
    if local == 0u && group.x + 1u == params.block_count {
        let needed = base + block_sums[group.x];
        atomicStore(&status[0], needed);
        atomicMax(&status[1], needed);
    }
}

@compute @workgroup_size(VOLUME_THREADS)
fn cell_lists_fill(@builtin(global_invocation_id) id: vec3<u32>) {
    let item = id.y * params.row_threads + id.x;
    if item < params.item_count {
        visit_cells(item, true);
    }
}
