//! A stable GPU radix sort of `(key, value)` pairs of `u32` by the key's low bits
//! (`radix_sort.wgsl`), for the LBVH's Morton codes: three dispatches per 8-bit digit (count per
//! tile, offsets, scatter). It sorts in place between two buffers of the caller's.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext};
use crate::{Error, Result};

/// Threads of a tile's workgroup, each taking one pair a round. Keep in sync with `radix_sort.wgsl`.
const THREADS: u32 = 256;
const DIGITS: u64 = 256;
const DIGIT_BITS: u32 = 8;
const MAX_PASSES: usize = 4;
const PASSES: [&str; 3] = ["sort_count", "sort_offsets", "sort_scatter"];

/// Rounds of a tile (its `ROUNDS`, a pipeline constant), by the sort's capacity: about 256 tiles, at
/// least 2 rounds and at most 8. A tile's workgroup takes its rounds one after another, so fewer
/// rounds in more tiles sort few pairs sooner; at a million, tiles of 8 rounds were faster, and at
/// 262,144, of 4 (benchmarks/LOG.md, topic 1).
fn tile_rounds(capacity: u32) -> u32 {
    (capacity / (THREADS * 256)).next_power_of_two().clamp(2, 8)
}

pub struct GpuRadixSort {
    pipelines: Vec<wgpu::ComputePipeline>,
    /// Per pass: its parameters, and its bind group (even passes read `pairs` and write `scratch`,
    /// odd passes the other way).
    pass_params: Vec<wgpu::Buffer>,
    bind_groups: Vec<wgpu::BindGroup>,
    digit_totals: wgpu::Buffer,
    pairs: wgpu::Buffer,
    scratch: wgpu::Buffer,
    capacity: u32,
    /// Pairs per tile.
    tile: u32,
    count: u32,
    key_bits: u32,
}

impl GpuRadixSort {
    /// Sorts up to `capacity` pairs held in `pairs`, with `scratch` (as large) as the other buffer of
    /// the ping-pong.
    pub fn new(ctx: &GpuContext, pairs: &wgpu::Buffer, scratch: &wgpu::Buffer, capacity: u32) -> Result<Self> {
        let device = &ctx.device;
        let bytes = u64::from(capacity) * 8;
        if pairs.size() < bytes || scratch.size() < bytes {
            return Err(Error::Gpu(format!("radix sort buffers are smaller than {capacity} pairs")));
        }
        use wgpu::BufferUsages as U;
        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let rounds = tile_rounds(capacity);
        let tile = THREADS * rounds;
        let tiles = u64::from(capacity.div_ceil(tile).max(1));
        let tile_digits = buffer("radix sort tile digits", tiles * DIGITS * 4, U::STORAGE);
        let digit_totals = buffer("radix sort digit totals", MAX_PASSES as u64 * DIGITS * 4, U::STORAGE | U::COPY_DST);
        let compute = wgpu::ShaderStages::COMPUTE;
        // Keep in sync with the bindings of `radix_sort.wgsl`.
        let layout = bindings::layout(
            device,
            "radix sort",
            &[
                bindings::uniform(0, compute),
                bindings::storage_read(1, compute),       // source
                bindings::storage_read_write(2, compute), // destination
                bindings::storage_read_write(3, compute), // tile digits
                bindings::storage_read_write(4, compute), // digit totals
            ],
        );
        let pass_params: Vec<wgpu::Buffer> = (0..MAX_PASSES).map(|_| buffer("radix sort pass", 16, U::UNIFORM | U::COPY_DST)).collect();
        let bind_groups = pass_params
            .iter()
            .enumerate()
            .map(|(index, params)| {
                let (source, destination) = if index.is_multiple_of(2) { (pairs, scratch) } else { (scratch, pairs) };
                bindings::bind_group(
                    device,
                    "radix sort pass",
                    &layout,
                    [params, source, destination, &tile_digits, &digit_totals].iter().map(|b| b.as_entire_binding()).collect(),
                )
            })
            .collect();
        let shader = ShaderDesc::new("accel/radix_sort.wgsl");
        let rounds = [("ROUNDS", f64::from(rounds))];
        let pipelines = PASSES
            .iter()
            .map(|entry| bindings::compute_pipeline_with_constants(device, entry, &shader, &[&layout], &rounds))
            .collect::<Result<_>>()?;
        Ok(Self {
            pipelines,
            pass_params,
            bind_groups,
            digit_totals,
            pairs: pairs.clone(),
            scratch: scratch.clone(),
            capacity,
            tile,
            count: 0,
            key_bits: 0,
        })
    }

    /// Pairs per tile: a multiple of 256 that the capacity chose ([`tile_rounds`]).
    pub fn tile_size(&self) -> u32 {
        self.tile
    }

    fn pass_count(&self) -> usize {
        self.key_bits.div_ceil(DIGIT_BITS) as usize
    }

    /// Sets what the next `record` sorts: the first `count` pairs, by the low `key_bits` (1..=32) bits
    /// of their keys (higher bits must be 0).
    pub fn set_problem(&mut self, queue: &wgpu::Queue, count: u32, key_bits: u32) -> Result<()> {
        if count > self.capacity {
            return Err(Error::InvalidConfig(format!("{count} pairs exceed the radix sort's capacity of {}", self.capacity)));
        }
        if !(1..=32).contains(&key_bits) {
            return Err(Error::InvalidConfig(format!("a radix sort by {key_bits} key bits: it takes 1 to 32")));
        }
        self.count = count;
        self.key_bits = key_bits;
        for (index, params) in self.pass_params.iter().take(self.pass_count()).enumerate() {
            let info = [count, index as u32 * DIGIT_BITS, count.div_ceil(self.tile), index as u32];
            queue.write_buffer(params, 0, bytemuck::cast_slice(&info));
        }
        Ok(())
    }

    /// Records the sort. The sorted pairs end in the scratch buffer; the pairs buffer is overwritten.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder) {
        if self.count == 0 {
            return;
        }
        encoder.clear_buffer(&self.digit_totals, 0, None);
        let tiles = self.count.div_ceil(self.tile);
        // One compute pass: wgpu orders the dispatches within it.
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("radix sort"), timestamp_writes: None });
        for bind_group in &self.bind_groups[..self.pass_count()] {
            for (entry, pipeline) in PASSES.iter().zip(&self.pipelines) {
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, bind_group, &[]);
                pass.dispatch_workgroups(if *entry == "sort_offsets" { DIGITS as u32 } else { tiles }, 1, 1);
            }
        }
        drop(pass);
        if self.pass_count().is_multiple_of(2) {
            encoder.copy_buffer_to_buffer(&self.pairs, 0, &self.scratch, 0, u64::from(self.count) * 8);
        }
    }
}
