//! Per-pass GPU timestamps: each pass asks for begin/end writes under its name; after the frame the
//! queries are resolved, read back and scaled by the queue's timestamp period into milliseconds.

use crate::{gpu::GpuContext, Result};

const MAX_SCOPES: u32 = 32;

pub struct GpuTimer {
    query_set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    scopes: Vec<&'static str>,
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
        let count = MAX_SCOPES * 2;
        let size = u64::from(count) * 8;
        Some(Self {
            query_set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolve: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            scopes: Vec::new(),
            period_ns: f64::from(ctx.queue.get_timestamp_period()),
        })
    }

    /// Starts a frame: forgets the previous frame's scopes.
    pub fn begin_frame(&mut self) {
        self.scopes.clear();
    }

    fn allocate(&mut self, name: &'static str) -> u32 {
        assert!((self.scopes.len() as u32) < MAX_SCOPES, "more than {MAX_SCOPES} timed passes in a frame");
        self.scopes.push(name);
        (self.scopes.len() as u32 - 1) * 2
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

    /// Records the resolve and copy; call before submitting the frame's encoder.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        let count = self.scopes.len() as u32 * 2;
        if count == 0 {
            return;
        }
        encoder.resolve_query_set(&self.query_set, 0..count, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, u64::from(count) * 8);
    }

    /// Reads the frame's timings back (blocks until the GPU is done).
    pub fn read(&self, ctx: &GpuContext) -> Result<PassTimings> {
        if self.scopes.is_empty() {
            return Ok(Vec::new());
        }
        let ticks: Vec<u64> = super::readback::map_buffer(ctx, &self.readback, 0, self.scopes.len() as u64 * 16)?;
        Ok(self
            .scopes
            .iter()
            .enumerate()
            .map(|(i, name)| {
                let elapsed = ticks[2 * i + 1].wrapping_sub(ticks[2 * i]);
                (*name, elapsed as f64 * self.period_ns / 1e6)
            })
            .collect())
    }
}
