//! Per-pass GPU timestamps: each pass asks for begin/end writes under its name; frames are resolved
//! into their own slot of one readback buffer, so many frames can be submitted back to back (as a
//! real frame loop does, keeping the GPU's clocks up) and read with one wait. Ticks are scaled by the
//! queue's timestamp period into milliseconds.

use crate::{gpu::GpuContext, Result};

/// Timed passes per frame.
const MAX_SCOPES: u32 = 32;
/// Frames per batch: 64 × 64 queries is wgpu's limit of 4096 queries per set.
pub const MAX_FRAMES: u32 = 64;
/// Bytes of one frame's resolved timestamps; a multiple of wgpu's 256-byte resolve alignment.
const FRAME_BYTES: u64 = MAX_SCOPES as u64 * 2 * 8;

pub struct GpuTimer {
    query_set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    /// Scope names of each frame recorded since the last read.
    frames: Vec<Vec<&'static str>>,
    period_ns: f64,
}

/// Milliseconds per named scope, in the order the passes ran.
pub type PassTimings = Vec<(&'static str, f64)>;

impl GpuTimer {
    /// `None` when the device has no timestamp queries.
    pub fn new(ctx: &GpuContext) -> Option<Self> {
        if !ctx.has_timestamps() {
            return None;
        }
        let size = FRAME_BYTES * u64::from(MAX_FRAMES);
        let buffer =
            |label, usage| ctx.device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false });
        Some(Self {
            query_set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: MAX_SCOPES * 2 * MAX_FRAMES,
            }),
            resolve: buffer("timestamp resolve", wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC),
            readback: buffer("timestamp readback", wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST),
            frames: Vec::new(),
            period_ns: f64::from(ctx.queue.get_timestamp_period()),
        })
    }

    /// True when every frame slot is used: `read` must come before the next `begin_frame`.
    pub fn is_full(&self) -> bool {
        self.frames.len() as u32 == MAX_FRAMES
    }

    /// Starts recording a frame in the next free slot.
    pub fn begin_frame(&mut self) {
        assert!(!self.is_full(), "read the timer before recording more than {MAX_FRAMES} frames");
        self.frames.push(Vec::new());
    }

    fn allocate(&mut self, name: &'static str) -> u32 {
        let frame = self.frames.len() as u32 - 1;
        let scopes = self.frames.last_mut().expect("begin_frame before timing passes");
        assert!((scopes.len() as u32) < MAX_SCOPES, "more than {MAX_SCOPES} timed passes in a frame");
        scopes.push(name);
        (frame * MAX_SCOPES + scopes.len() as u32 - 1) * 2
    }

    pub fn compute_pass(&mut self, name: &'static str) -> wgpu::ComputePassTimestampWrites<'_> {
        let first = self.allocate(name);
        wgpu::ComputePassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(first),
            end_of_pass_write_index: Some(first + 1),
        }
    }

    pub fn render_pass(&mut self, name: &'static str) -> wgpu::RenderPassTimestampWrites<'_> {
        let first = self.allocate(name);
        wgpu::RenderPassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(first),
            end_of_pass_write_index: Some(first + 1),
        }
    }

    /// Starts a scope spanning several compute passes: pass these writes to its first pass and
    /// `span_end` to its last.
    pub fn span_start(&mut self, name: &'static str) -> wgpu::ComputePassTimestampWrites<'_> {
        let first = self.allocate(name);
        wgpu::ComputePassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: Some(first),
            end_of_pass_write_index: None,
        }
    }

    /// Ends the most recent scope named `name`, started by `span_start`.
    pub fn span_end(&mut self, name: &'static str) -> wgpu::ComputePassTimestampWrites<'_> {
        let frame = self.frames.len() as u32 - 1;
        let scope = self.frames[frame as usize].iter().rposition(|n| *n == name).expect("span_end without span_start") as u32;
        wgpu::ComputePassTimestampWrites {
            query_set: &self.query_set,
            beginning_of_pass_write_index: None,
            end_of_pass_write_index: Some((frame * MAX_SCOPES + scope) * 2 + 1),
        }
    }

    /// Records the resolve and copy of the current frame; call before submitting its encoder.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let frame = self.frames.len() as u32 - 1;
        let count = self.frames[frame as usize].len() as u32 * 2;
        if count == 0 {
            return;
        }
        let first = frame * MAX_SCOPES * 2;
        let offset = u64::from(frame) * FRAME_BYTES;
        encoder.resolve_query_set(&self.query_set, first..first + count, &self.resolve, offset);
        encoder.copy_buffer_to_buffer(&self.resolve, offset, &self.readback, offset, u64::from(count) * 8);
    }

    /// Waits for the recorded frames and returns their timings, oldest first; frees every slot.
    pub fn read(&mut self, ctx: &GpuContext) -> Result<Vec<PassTimings>> {
        if self.frames.is_empty() {
            return Ok(Vec::new());
        }
        let ticks: Vec<u64> = super::readback::map_buffer(ctx, &self.readback, 0, self.frames.len() as u64 * FRAME_BYTES)?;
        let timings = self
            .frames
            .iter()
            .enumerate()
            .map(|(frame, scopes)| {
                let base = frame * MAX_SCOPES as usize * 2;
                scopes
                    .iter()
                    .enumerate()
                    .map(|(i, name)| {
                        let elapsed = ticks[base + 2 * i + 1].wrapping_sub(ticks[base + 2 * i]);
                        (*name, elapsed as f64 * self.period_ns / 1e6)
                    })
                    .collect()
            })
            .collect();
        self.frames.clear();
        Ok(timings)
    }
}

/// Records `build` between two timestamps of the scope `name`: acceleration-structure builds are
/// not passes, so empty compute passes carry the timestamps.
pub fn timed(
    encoder: &mut wgpu::CommandEncoder,
    timer: Option<&mut GpuTimer>,
    name: &'static str,
    build: impl FnOnce(&mut wgpu::CommandEncoder),
) {
    let Some(timer) = timer else {
        build(encoder);
        return;
    };
    encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(name), timestamp_writes: Some(timer.span_start(name)) });
    build(encoder);
    encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(name), timestamp_writes: Some(timer.span_end(name)) });
}
