//! Items in leaf order for structures whose groups are rebuilt on the GPU (`leaf_order.wgsl`). Group
//! leaves name their items directly, so the items a leaf holds must lie in the order of its build's
//! sorted boxes. CPU-built groups are uploaded that way; a GPU rebuild sorts anew every frame, so after
//! it this pass copies every item from a scene-order copy to its leaf position, as the primitive
//! indices the builds left say.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuTimer};
use crate::Result;
use wgpu::util::DeviceExt;

const WORKGROUP: u32 = 256;

/// Keep in sync with `LeafOrderParams` in `leaf_order.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LeafOrderParams {
    count: u32,
    first_primitive: u32,
    vec4s_per_item: u32,
    row_threads: u32,
}

pub struct LeafOrder {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    dispatch: (u32, u32),
    scope: &'static str,
}

/// Where the pass writes the items, and the primitive indices of the rebuilt leaves it reads.
pub struct LeafOrderTarget<'a> {
    pub items: &'a wgpu::Buffer,
    pub primitives: &'a wgpu::Buffer,
    /// The first of the items' primitive indices.
    pub first_primitive: u32,
}

impl LeafOrder {
    /// The pass that writes `count` items of `item_bytes` each (a multiple of 16) into `target.items`
    /// from `scene_items`, item i from scene item `target.primitives[target.first_primitive + i]`,
    /// timed as `scope`.
    pub fn new(
        ctx: &GpuContext,
        scope: &'static str,
        scene_items: &[u8],
        item_bytes: usize,
        LeafOrderTarget { items, primitives, first_primitive }: LeafOrderTarget,
    ) -> Result<Self> {
        debug_assert!(item_bytes.is_multiple_of(16) && !scene_items.is_empty());
        let device = &ctx.device;
        let count = (scene_items.len() / item_bytes) as u32;
        let vec4s_per_item = (item_bytes / 16) as u32;
        let groups = (count * vec4s_per_item).div_ceil(WORKGROUP);
        let x = groups.min(ctx.limits.max_compute_workgroups_per_dimension);
        let dispatch = (x, groups.div_ceil(x));
        let params = LeafOrderParams { count, first_primitive, vec4s_per_item, row_threads: x * WORKGROUP };
        let buffer = |label: &str, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let params = buffer("leaf order params", bytemuck::bytes_of(&params), wgpu::BufferUsages::UNIFORM);
        let scene_items = buffer("items in scene order", scene_items, wgpu::BufferUsages::STORAGE);
        let compute = wgpu::ShaderStages::COMPUTE;
        // Keep in sync with the bindings of `leaf_order.wgsl`.
        let layout = bindings::layout(
            device,
            "leaf order",
            &[
                bindings::uniform(0, compute),
                bindings::storage_read(1, compute),
                bindings::storage_read(2, compute),
                bindings::storage_read_write(3, compute),
            ],
        );
        let bind_group = bindings::bind_group(
            device,
            "leaf order",
            &layout,
            [&params, &scene_items, primitives, items].iter().map(|b| b.as_entire_binding()).collect(),
        );
        let pipeline = bindings::compute_pipeline(device, "leaf_order", &ShaderDesc::new("accel/leaf_order.wgsl"), &[&layout])?;
        Ok(Self { pipeline, bind_group, dispatch, scope })
    }

    /// Records the copy: after the builds, before anything reads the items.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.scope),
            timestamp_writes: timer.map(|t| t.compute_pass(self.scope)),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.dispatch_workgroups(self.dispatch.0, self.dispatch.1, 1);
    }
}
