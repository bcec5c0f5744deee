//! The LBVH builder on the GPU (`lbvh.wgsl`): rebuilds a BVH over up to `capacity` boxes in a handful
//! of compute passes and lampshade's radix sort, writing the node layout the point query reads.
//! Boxes are uploaded by the caller (a group's volumes in its local space; moving groups are placed by
//! the top level, so their boxes change only when the group's contents change).

use super::{Aabb, Bvh, BvhNode};
use crate::gpu::{bindings, readback, shaders::ShaderDesc, GpuContext, GpuTimer};
use crate::{Error, Result};

/// Keep in sync with `Box` in `lbvh.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuBox {
    min: [f32; 4],
    max: [f32; 4],
}

/// One entry point per pass, in dispatch order around the sort.
const PASSES: [&str; 5] = ["lbvh_centre_bounds", "lbvh_morton", "lbvh_hierarchy", "lbvh_bounds", "lbvh_write_nodes"];
const WORKGROUP: u32 = 256;

pub struct GpuLbvh {
    pipelines: Vec<wgpu::ComputePipeline>,
    bind_group: wgpu::BindGroup,
    sorter: lampshade::KeyValueSorter,
    params: wgpu::Buffer,
    boxes: wgpu::Buffer,
    centre_bounds: wgpu::Buffer,
    keys: wgpu::Buffer,
    sorted_keys: wgpu::Buffer,
    pub nodes: wgpu::Buffer,
    pub primitives: wgpu::Buffer,
    node_bounds: wgpu::Buffer,
    capacity: u32,
    count: u32,
}

impl GpuLbvh {
    /// Allocates for up to `capacity` boxes; errors if the buffers would exceed the device's limits.
    pub fn new(ctx: &GpuContext, capacity: u32) -> Result<Self> {
        let device = &ctx.device;
        let capacity = capacity.max(1);
        let node_capacity = u64::from(2 * capacity - 1);
        let largest = node_capacity * std::mem::size_of::<BvhNode>() as u64;
        if largest > ctx.limits.max_storage_buffer_binding_size {
            return Err(Error::InvalidConfig(format!(
                "a BVH over {capacity} volumes needs {} MiB buffers, over this GPU's storage binding limit of {} MiB",
                largest >> 20,
                ctx.limits.max_storage_buffer_binding_size >> 20
            )));
        }
        use wgpu::BufferUsages as U;
        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let params = buffer("lbvh params", 16, U::UNIFORM | U::COPY_DST);
        let boxes = buffer("lbvh boxes", u64::from(capacity) * 32, U::STORAGE | U::COPY_DST);
        let centre_bounds = buffer("lbvh centre bounds", 24, U::STORAGE | U::COPY_DST);
        let keys = buffer("lbvh keys", u64::from(capacity) * 8, U::STORAGE);
        let sorted_keys = buffer("lbvh sorted keys", u64::from(capacity) * 8, U::STORAGE);
        let nodes = buffer("lbvh nodes", node_capacity * 32, U::STORAGE | U::COPY_SRC);
        let primitives = buffer("lbvh primitives", u64::from(capacity) * 4, U::STORAGE | U::COPY_SRC);
        let parents = buffer("lbvh parents", node_capacity * 4, U::STORAGE);
        let node_bounds = buffer("lbvh node bounds", node_capacity * 24, U::STORAGE | U::COPY_DST);

        let compute = wgpu::ShaderStages::COMPUTE;
        let read_write = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: compute,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: false },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        // Keep in sync with the bindings of `lbvh.wgsl`.
        let layout = bindings::layout(
            device,
            "lbvh",
            &[
                bindings::uniform(0, compute),
                bindings::storage_read(1, compute), // boxes
                read_write(2),                      // centre bounds
                read_write(3),                      // keys
                bindings::storage_read(4, compute), // sorted keys
                read_write(5),                      // nodes
                read_write(6),                      // primitives
                read_write(7),                      // parents
                read_write(8),                      // node bounds
            ],
        );
        let bind_group = bindings::bind_group(
            device,
            "lbvh",
            &layout,
            [&params, &boxes, &centre_bounds, &keys, &sorted_keys, &nodes, &primitives, &parents, &node_bounds]
                .iter()
                .map(|b| b.as_entire_binding())
                .collect(),
        );
        let shader = ShaderDesc::new("accel/lbvh.wgsl");
        let pipelines = PASSES.iter().map(|entry| bindings::compute_pipeline(device, entry, &shader, &[&layout])).collect::<Result<_>>()?;
        Ok(Self {
            pipelines,
            bind_group,
            sorter: lampshade::KeyValueSorter::new_for_adapter(device, &ctx.queue, &ctx.info),
            params,
            boxes,
            centre_bounds,
            keys,
            sorted_keys,
            nodes,
            primitives,
            node_bounds,
            capacity,
            count: 0,
        })
    }

    /// Sets the boxes of the next build. Non-finite or inverted boxes are errors, as for the CPU builder.
    pub fn set_boxes(&mut self, queue: &wgpu::Queue, boxes: &[Aabb]) -> Result<()> {
        if boxes.len() as u64 > u64::from(self.capacity) {
            return Err(Error::InvalidConfig(format!("{} volumes exceed the BVH's capacity of {}", boxes.len(), self.capacity)));
        }
        if let Some(i) = boxes.iter().position(|b| !b.is_valid()) {
            return Err(Error::InvalidScene(format!("volume {i} has a NaN, infinite or inverted bound: {:?}", boxes[i])));
        }
        let gpu: Vec<GpuBox> =
            boxes.iter().map(|b| GpuBox { min: b.min.extend(0.0).to_array(), max: b.max.extend(0.0).to_array() }).collect();
        if !gpu.is_empty() {
            queue.write_buffer(&self.boxes, 0, bytemuck::cast_slice(&gpu));
        }
        self.count = boxes.len() as u32;
        queue.write_buffer(&self.params, 0, bytemuck::cast_slice(&[self.count, 0, 0, 0]));
        Ok(())
    }

    /// Number of nodes the last `set_boxes` builds (0 for no boxes).
    pub fn node_count(&self) -> u32 {
        (2 * self.count).saturating_sub(1)
    }

    /// Records a full rebuild, timed as one scope `lbvh_build`.
    pub fn record(&mut self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>) -> Result<()> {
        if self.count == 0 {
            return Ok(());
        }
        encoder.clear_buffer(&self.centre_bounds, 0, None);
        encoder.clear_buffer(&self.node_bounds, 0, Some(u64::from(self.node_count()) * 24));
        let items = self.count.div_ceil(WORKGROUP);
        let nodes = self.node_count().div_ceil(WORKGROUP);
        let last = PASSES.len() - 1;
        for (index, (entry, pipeline)) in PASSES.iter().zip(&self.pipelines).enumerate() {
            if *entry == "lbvh_hierarchy" {
                self.sorter
                    .record_sort_with_key_bits(encoder, &self.keys, &self.sorted_keys, self.count, 30)
                    .map_err(|e| Error::Gpu(format!("radix sort: {e}")))?;
            }
            let timestamp_writes = timer.as_deref_mut().and_then(|t| match index {
                0 => Some(t.span_start("lbvh_build")),
                i if i == last => Some(t.span_end("lbvh_build")),
                _ => None,
            });
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(entry), timestamp_writes });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            pass.dispatch_workgroups(if *entry == "lbvh_write_nodes" { nodes } else { items }, 1, 1);
        }
        Ok(())
    }

    /// Reads the last build back: for tests and validation.
    pub fn read_back(&self, ctx: &GpuContext) -> Result<Bvh> {
        let copy = |source: &wgpu::Buffer, size: u64| -> Result<Vec<u8>> {
            let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("lbvh readback"),
                size: size.max(4),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            if size > 0 {
                encoder.copy_buffer_to_buffer(source, 0, &staging, 0, size);
            }
            ctx.queue.submit([encoder.finish()]);
            let mut bytes: Vec<u8> = readback::map_buffer(ctx, &staging, 0, size.max(4))?;
            bytes.truncate(size as usize);
            Ok(bytes)
        };
        let nodes = copy(&self.nodes, u64::from(self.node_count()) * 32)?;
        let primitives = copy(&self.primitives, u64::from(self.count) * 4)?;
        ctx.check_errors()?;
        Ok(Bvh { nodes: bytemuck::pod_collect_to_vec(&nodes), primitive_indices: bytemuck::pod_collect_to_vec(&primitives) })
    }
}
