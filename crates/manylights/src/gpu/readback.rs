//! Copying GPU data back to the CPU: buffers, and textures with wgpu's 256-byte row alignment removed.

use crate::{gpu::GpuContext, Error, Result};

/// Maps `size` bytes of a MAP_READ buffer from `offset` and returns them as `T`s.
pub fn map_buffer<T: bytemuck::Pod>(ctx: &GpuContext, buffer: &wgpu::Buffer, offset: u64, size: u64) -> Result<Vec<T>> {
    let (sender, receiver) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, offset..offset + size, move |r| {
        let _ = sender.send(r);
    });
    ctx.wait_idle()?;
    receiver
        .recv()
        .map_err(|_| Error::Gpu("buffer mapping was dropped".into()))?
        .map_err(|e| Error::Gpu(format!("cannot map a readback buffer: {e}")))?;
    let data = {
        let view = buffer.get_mapped_range(offset..offset + size).map_err(|e| Error::Gpu(format!("cannot read a mapped buffer: {e}")))?;
        bytemuck::pod_collect_to_vec(&view)
    };
    buffer.unmap();
    Ok(data)
}

/// The second word of an 8-byte `status` buffer (STORAGE | COPY_SRC | COPY_DST), where passes
/// keep the most entries a frame needed, through `readback` (MAP_READ | COPY_DST); the word is
/// reset, so the next call sees only the frames after this one.
pub fn take_most_needed(ctx: &GpuContext, status: &wgpu::Buffer, readback: &wgpu::Buffer) -> Result<u32> {
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(status, 0, readback, 0, 8);
    encoder.clear_buffer(status, 4, None);
    ctx.queue.submit([encoder.finish()]);
    Ok(map_buffer::<u32>(ctx, readback, 0, 8)?[1])
}

/// The entries lists grow to once a frame needed `needed` (over what they held): a quarter more, so
/// a view that keeps growing re-renders rarely, but never past `max`.
pub fn grown_capacity(needed: u32, max: u32) -> u32 {
    (u64::from(needed) * 5 / 4).min(u64::from(max)) as u32
}

/// Copies a whole COPY_SRC buffer into a staging buffer and returns it as `T`s.
pub fn read_buffer<T: bytemuck::Pod>(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<T>> {
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: buffer.size(),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    ctx.queue.submit([encoder.finish()]);
    map_buffer(ctx, &staging, 0, buffer.size())
}

/// Reads a whole 2D texture of `bytes_per_pixel`-sized texels, tightly packed, row by row.
pub fn read_texture(ctx: &GpuContext, texture: &wgpu::Texture, bytes_per_pixel: u32) -> Result<Vec<u8>> {
    let (width, height) = (texture.width(), texture.height());
    let row_bytes = width * bytes_per_pixel;
    let padded_row = row_bytes.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let size = u64::from(padded_row) * u64::from(height);
    let buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(padded_row), rows_per_image: Some(height) },
        },
        texture.size(),
    );
    ctx.queue.submit([encoder.finish()]);
    let padded: Vec<u8> = map_buffer(ctx, &buffer, 0, size)?;
    Ok(padded.chunks_exact(padded_row as usize).flat_map(|row| &row[..row_bytes as usize]).copied().collect())
}

/// A read-back image, rows top to bottom.
#[derive(Clone, Debug)]
pub struct Image<T> {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<T>,
}
