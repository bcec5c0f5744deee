// Exclusive prefix sums across one workgroup of SCAN_THREADS threads, shared by the radix sort and
// the clustered lists' offsets. Every thread of the workgroup must call it (it has barriers).

const SCAN_THREADS: u32 = 256u;

var<workgroup> scan: array<u32, SCAN_THREADS>;

// Exclusive prefix sum of `value` over the workgroup's threads (Hillis–Steele); also returns the total.
fn workgroup_exclusive_scan(local: u32, value: u32) -> vec2<u32> {
    scan[local] = value;
    workgroupBarrier();
    for (var offset = 1u; offset < SCAN_THREADS; offset *= 2u) {
        var add = 0u;
        if local >= offset {
            add = scan[local - offset];
        }
        workgroupBarrier();
        scan[local] += add;
        workgroupBarrier();
    }
    let inclusive = scan[local];
    let total = scan[SCAN_THREADS - 1u];
    workgroupBarrier();
    return vec2<u32>(inclusive - value, total);
}
