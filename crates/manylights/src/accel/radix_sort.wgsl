// Stable LSD radix sort of (key, value) pairs by the key, 8 bits per pass, three dispatches a pass:
// count each tile's digits, turn the counts into each tile's output offsets, scatter. A tile is
// THREADS * ROUNDS consecutive pairs; the scatter ranks pairs of one digit in a tile by position with
// bit masks in workgroup memory, so it needs neither subgroup operations nor progress guarantees
// between workgroups (lavapipe runs it as the GPUs do).

#include "accel/workgroup_scan.wgsl"

struct SortPass {
    count: u32,
    // Bit position of this pass's digit.
    shift: u32,
    tiles: u32,
    // Which pass this is: its digit totals' slot.
    index: u32,
}

// Threads per workgroup: one per digit in `sort_offsets` and `sort_scatter`.
const THREADS: u32 = SCAN_THREADS;
// Rounds of THREADS pairs a tile takes, set per sort by its capacity (`radix_sort.rs`).
override ROUNDS: u32 = 8u;
const DIGITS: u32 = 256u;
// Bit mask words per digit: one bit per thread of a round.
const WORDS: u32 = THREADS / 32u;

@group(0) @binding(0) var<uniform> pass_info: SortPass;
@group(0) @binding(1) var<storage, read> source: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read_write> destination: array<vec2<u32>>;
// Per tile and digit (tile-major): the tile's count of the digit, then its first output position.
@group(0) @binding(3) var<storage, read_write> tile_digits: array<u32>;
// Per pass and digit: how many keys have the digit; cleared before the sort.
@group(0) @binding(4) var<storage, read_write> digit_totals: array<atomic<u32>>;

fn digit_of(key: u32) -> u32 {
    return (key >> pass_info.shift) & (DIGITS - 1u);
}

var<workgroup> counts: array<atomic<u32>, DIGITS>;

@compute @workgroup_size(256)
fn sort_count(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    atomicStore(&counts[local], 0u);
    workgroupBarrier();
    let tile_start = group.x * (THREADS * ROUNDS);
    for (var round = 0u; round < ROUNDS; round += 1u) {
        let position = tile_start + round * THREADS + local;
        if position < pass_info.count {
            atomicAdd(&counts[digit_of(source[position].x)], 1u);
        }
    }
    workgroupBarrier();
    let count = atomicLoad(&counts[local]);
    tile_digits[group.x * DIGITS + local] = count;
    if count != 0u {
        atomicAdd(&digit_totals[pass_info.index * DIGITS + local], count);
    }
}

// One workgroup per digit: the digit's first output position is the number of smaller digits; each
// tile's is that plus the digit's count in the tiles before it.
@compute @workgroup_size(256)
fn sort_offsets(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let digit = group.x;
    let smaller = select(0u, atomicLoad(&digit_totals[pass_info.index * DIGITS + local]), local < digit);
    var carry = workgroup_exclusive_scan(local, smaller).y;
    for (var first = 0u; first < pass_info.tiles; first += THREADS) {
        let tile = first + local;
        let count = select(0u, tile_digits[tile * DIGITS + digit], tile < pass_info.tiles);
        let scanned = workgroup_exclusive_scan(local, count);
        if tile < pass_info.tiles {
            tile_digits[tile * DIGITS + digit] = carry + scanned.x;
        }
        carry += scanned.y;
    }
}

// Per digit: one bit per thread of the current round holding that digit.
var<workgroup> round_masks: array<atomic<u32>, DIGITS * WORDS>;
// Per digit: where the tile's next pair with it goes.
var<workgroup> next_position: array<u32, DIGITS>;

@compute @workgroup_size(256)
fn sort_scatter(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    next_position[local] = tile_digits[group.x * DIGITS + local];
    for (var word = 0u; word < WORDS; word += 1u) {
        atomicStore(&round_masks[local * WORDS + word], 0u);
    }
    workgroupBarrier();
    let word = local / 32u;
    let bit = 1u << (local % 32u);
    // Rounds of THREADS consecutive pairs, in order: a pair's rank among its digit in the tile is the
    // pairs of that digit in earlier rounds plus those at lower threads in its own, which keeps the sort
    // stable.
    for (var round = 0u; round < ROUNDS; round += 1u) {
        let position = group.x * (THREADS * ROUNDS) + round * THREADS + local;
        let valid = position < pass_info.count;
        var pair = vec2<u32>(0u);
        var digit = 0u;
        if valid {
            pair = source[position];
            digit = digit_of(pair.x);
            atomicOr(&round_masks[digit * WORDS + word], bit);
        }
        workgroupBarrier();
        if valid {
            var rank = countOneBits(atomicLoad(&round_masks[digit * WORDS + word]) & (bit - 1u));
            for (var w = 0u; w < word; w += 1u) {
                rank += countOneBits(atomicLoad(&round_masks[digit * WORDS + w]));
            }
            destination[next_position[digit] + rank] = pair;
        }
        workgroupBarrier();
        // Thread `local` now owns digit `local`: advance its position and clear its masks.
        var in_round = 0u;
        for (var w = 0u; w < WORDS; w += 1u) {
            in_round += countOneBits(atomicExchange(&round_masks[local * WORDS + w], 0u));
        }
        next_position[local] += in_round;
        workgroupBarrier();
    }
}
