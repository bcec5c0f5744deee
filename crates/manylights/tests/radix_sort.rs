//! The GPU radix sort orders pairs by their key bits and keeps equal keys in input order (the LBVH
//! relies on both), for sizes around its tile and for every pass count.

use manylights::{accel::radix_sort::GpuRadixSort, gpu::GpuContext};
use rand::{Rng, SeedableRng};

fn sort_on_gpu(
    ctx: &GpuContext,
    sort: &mut GpuRadixSort,
    buffers: &(wgpu::Buffer, wgpu::Buffer),
    pairs: &[[u32; 2]],
    key_bits: u32,
) -> Vec<[u32; 2]> {
    if !pairs.is_empty() {
        ctx.queue.write_buffer(&buffers.0, 0, bytemuck::cast_slice(pairs));
    }
    sort.set_problem(&ctx.queue, pairs.len() as u32, key_bits).unwrap();
    let size = (pairs.len() as u64 * 8).max(8);
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    sort.record(&mut encoder);
    encoder.copy_buffer_to_buffer(&buffers.1, 0, &staging, 0, size);
    ctx.queue.submit([encoder.finish()]);
    let bytes = manylights::gpu::readback::map_buffer(ctx, &staging, 0, size).unwrap();
    bytemuck::pod_collect_to_vec::<u8, [u32; 2]>(&bytes)[..pairs.len()].to_vec()
}

#[test]
fn sorts_stably_by_the_key_bits() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    // Capacities whose tiles take 2, 4 and 8 rounds of 256 pairs.
    for (capacity, tile) in [(70_000, 512), (200_000, 1024), (600_000, 2048)] {
        let buffer = |label| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: capacity as u64 * 8,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let buffers = (buffer("pairs"), buffer("scratch"));
        let mut sort = GpuRadixSort::new(&ctx, &buffers.0, &buffers.1, capacity).unwrap();
        assert_eq!(sort.tile_size(), tile, "tiles for a capacity of {capacity}");
        // 8, 16, 24 and 32 bits take 1 to 4 passes (even counts end with a copy).
        let small = [(0, 24), (1, 24), (2, 30), (255, 8), (tile, 16), (tile + 1, 24), (5000, 30)];
        let cases: &[(u32, u32)] = if capacity == 70_000 { &small } else { &[(tile + 1, 24)] };
        for &(count, key_bits) in cases.iter().chain(&[(capacity, 24), (capacity, 32)]) {
            // Few distinct keys in some cases, so equal keys must keep their order.
            let distinct = if count % 2 == 0 { 7 } else { u64::MAX };
            let pairs: Vec<[u32; 2]> = (0..count)
                .map(|value| {
                    let key = (rng.random::<u64>() % distinct) as u32;
                    [if key_bits == 32 { key } else { key & ((1 << key_bits) - 1) }, value]
                })
                .collect();
            let mut expected = pairs.clone();
            expected.sort_by_key(|pair| pair[0]);
            let sorted = sort_on_gpu(&ctx, &mut sort, &buffers, &pairs, key_bits);
            assert!(sorted == expected, "{count} pairs by {key_bits} bits (capacity {capacity}): not sorted stably");
        }
        assert!(sort.set_problem(&ctx.queue, capacity + 1, 24).is_err());
        assert!(sort.set_problem(&ctx.queue, 10, 0).is_err());
    }
}
