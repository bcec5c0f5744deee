//! The LBVH builder on the GPU (`lbvh.wgsl`): rebuilds a BVH over up to `capacity` boxes in a handful
//! of compute passes and a radix sort (`radix_sort.rs`), writing the node layout the point query reads.
//! Boxes are uploaded by the caller (a group's volumes in its local space; moving groups are placed by
//! the top level, so their boxes change only when the group's contents change). The nodes land in a
//! region of a node array that may hold other BVHs too ([`LbvhTarget`]).

use super::{light_tree::LightTreeNode, radix_sort::GpuRadixSort, Aabb, Bvh, BvhNode, MAX_LEAF_SIZE};
use crate::gpu::{bindings, readback, shaders::ShaderDesc, GpuContext, GpuTimer};
use crate::{Error, Result};
use glam::Vec3;

/// Keep in sync with `Box` in `lbvh.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuBox {
    min: [f32; 4],
    max: [f32; 4],
}

/// Keep in sync with `LbvhParams` in `lbvh.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LbvhParams {
    count: u32,
    node_base: u32,
    primitive_base: u32,
    item_base: u32,
    max_leaf_size: u32,
    leaf_base: u32,
    _pad: [u32; 2],
    centre_min: [f32; 4],
    centre_max: [f32; 4],
}

/// Where a build writes: `2 × capacity − 1` nodes from `node_base` in `nodes`, and `capacity` primitive
/// indices from `primitive_base` in `primitives`, each `item_base` + the box's index, in leaf order. A
/// leaf over sorted positions [j, j + n) names the range from `leaf_base` + j: `primitive_base` where
/// queries read the primitive indices (a top level's instance indices), or `item_base` where a pass
/// after the build stores the items themselves in leaf order (a group's lights or decals). With
/// `light_tree`, an array parallel to `nodes`, each node also gets its [`LightTreeNode`] there, the
/// union of the emitters given with the boxes ([`GpuLbvh::set_emitters`], [`GpuLbvh::emitters`]).
#[derive(Clone, Debug)]
pub struct LbvhTarget {
    pub nodes: wgpu::Buffer,
    pub primitives: wgpu::Buffer,
    pub node_base: u32,
    pub primitive_base: u32,
    pub item_base: u32,
    pub leaf_base: u32,
    pub light_tree: Option<wgpu::Buffer>,
}

/// The timer scope a build is recorded in: `starts` opens it at the build's first pass, `ends` closes
/// it at the last, so consecutive builds can share one scope.
#[derive(Clone, Copy, Debug)]
pub struct TimerSpan {
    pub name: &'static str,
    pub starts: bool,
    pub ends: bool,
}

impl TimerSpan {
    /// A scope of its own.
    pub fn whole(name: &'static str) -> Self {
        Self { name, starts: true, ends: true }
    }
}

/// One entry point per pass, in dispatch order around the sort; the light tree's only with one.
const PASSES: [&str; 6] = ["lbvh_morton", "lbvh_hierarchy", "lbvh_bounds", "lbvh_emitters", "lbvh_block_power", "lbvh_write_nodes"];
const LIGHT_TREE_PASSES: [&str; 2] = ["lbvh_emitters", "lbvh_block_power"];
const WORKGROUP: u32 = 256;
/// Bits of the Morton codes: 8 per axis (`MORTON_CELLS` in `lbvh.wgsl`).
const MORTON_BITS: u32 = 24;

pub struct GpuLbvh {
    /// Each pass that runs, by entry point.
    pipelines: Vec<(&'static str, wgpu::ComputePipeline)>,
    bind_group: wgpu::BindGroup,
    sort: GpuRadixSort,
    params: wgpu::Buffer,
    boxes: wgpu::Buffer,
    /// One [`LightTreeNode`] per box where the target has a light tree; a placeholder otherwise.
    emitters: wgpu::Buffer,
    target: LbvhTarget,
    capacity: u32,
    count: u32,
    max_leaf_size: u32,
}

impl GpuLbvh {
    /// Allocates for up to `capacity` boxes, writing into buffers of its own; errors if the buffers
    /// would exceed the device's limits.
    pub fn new(ctx: &GpuContext, capacity: u32) -> Result<Self> {
        Self::with_own_buffers(ctx, capacity, false)
    }

    /// As [`new`](Self::new), with every node's [`LightTreeNode`] built alongside, in a buffer of its own.
    pub fn with_light_tree(ctx: &GpuContext, capacity: u32) -> Result<Self> {
        Self::with_own_buffers(ctx, capacity, true)
    }

    fn with_own_buffers(ctx: &GpuContext, capacity: u32, light_tree: bool) -> Result<Self> {
        let capacity = capacity.max(1);
        let node_bytes = u64::from(2 * capacity - 1) * std::mem::size_of::<BvhNode>() as u64;
        check_binding_size(ctx, capacity, node_bytes)?;
        let buffer = |label, size: u64| {
            let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
            ctx.device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let target = LbvhTarget {
            nodes: buffer("lbvh nodes", node_bytes),
            primitives: buffer("lbvh primitives", u64::from(capacity) * 4),
            node_base: 0,
            primitive_base: 0,
            item_base: 0,
            leaf_base: 0,
            light_tree: light_tree.then(|| buffer("lbvh light tree", node_bytes)),
        };
        Self::with_target(ctx, capacity, target)
    }

    /// Allocates for up to `capacity` boxes, writing into `target`'s regions.
    pub fn with_target(ctx: &GpuContext, capacity: u32, target: LbvhTarget) -> Result<Self> {
        let device = &ctx.device;
        let capacity = capacity.max(1);
        let node_capacity = u64::from(2 * capacity - 1);
        check_binding_size(ctx, capacity, node_capacity * std::mem::size_of::<BvhNode>() as u64)?;
        let node_end = (u64::from(target.node_base) + node_capacity) * std::mem::size_of::<BvhNode>() as u64;
        let primitive_end = (u64::from(target.primitive_base) + u64::from(capacity)) * 4;
        let tree_short = target.light_tree.as_ref().is_some_and(|tree| node_end > tree.size());
        if node_end > target.nodes.size() || primitive_end > target.primitives.size() || tree_short {
            return Err(Error::Gpu(format!("an LBVH over {capacity} boxes does not fit its target's regions")));
        }
        use wgpu::BufferUsages as U;
        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let params = buffer("lbvh params", std::mem::size_of::<LbvhParams>() as u64, U::UNIFORM | U::COPY_DST);
        let boxes = buffer("lbvh boxes", u64::from(capacity) * 32, U::STORAGE | U::COPY_DST);
        let keys = buffer("lbvh keys", u64::from(capacity) * 8, U::STORAGE | U::COPY_SRC);
        let sorted_keys = buffer("lbvh sorted keys", u64::from(capacity) * 8, U::STORAGE | U::COPY_DST);
        let parents = buffer("lbvh parents", node_capacity * 4, U::STORAGE);
        // Internal nodes only (there is one fewer than boxes): leaves write their boxes directly.
        let node_bounds = buffer("lbvh node bounds", u64::from(capacity) * 24, U::STORAGE);
        let ranges = buffer("lbvh node ranges", u64::from(capacity) * 8, U::STORAGE);
        // The light tree's inputs and working arrays (`lbvh.wgsl`), one-element placeholders without it.
        let tree = target.light_tree.is_some();
        let tree_bytes = |bytes: u64| if tree { bytes } else { 32 };
        let emitters = buffer("lbvh emitters", tree_bytes(u64::from(capacity) * 32), U::STORAGE | U::COPY_DST);
        let tree_placeholder = (!tree).then(|| buffer("lbvh light tree placeholder", 32, U::STORAGE));
        let tree_bounds = buffer("lbvh light tree bounds", tree_bytes(u64::from(capacity) * 32), U::STORAGE);
        let leaf_power = buffer("lbvh leaf power", tree_bytes(u64::from(capacity) * 8), U::STORAGE);
        let block_power = buffer("lbvh block power", tree_bytes(u64::from(capacity.div_ceil(WORKGROUP)) * 4), U::STORAGE);

        let compute = wgpu::ShaderStages::COMPUTE;
        let read_write = |binding| bindings::storage_read_write(binding, compute);
        // Keep in sync with the bindings of `lbvh.wgsl`.
        let layout = bindings::layout(
            device,
            "lbvh",
            &[
                bindings::uniform(0, compute),
                bindings::storage_read(1, compute), // boxes
                read_write(2),                      // keys
                bindings::storage_read(3, compute), // sorted keys
                read_write(4),                      // nodes
                read_write(5),                      // primitives
                read_write(6),                      // parents
                read_write(7),                      // node bounds
                read_write(8),                      // node ranges
                bindings::storage_read(9, compute), // emitters
                read_write(10),                     // light tree
                read_write(11),                     // light tree bounds
                read_write(12),                     // leaf power
                read_write(13),                     // block power
            ],
        );
        let bind_group = bindings::bind_group(
            device,
            "lbvh",
            &layout,
            [
                &params,
                &boxes,
                &keys,
                &sorted_keys,
                &target.nodes,
                &target.primitives,
                &parents,
                &node_bounds,
                &ranges,
                &emitters,
                target.light_tree.as_ref().or(tree_placeholder.as_ref()).expect("a tree or its placeholder"),
                &tree_bounds,
                &leaf_power,
                &block_power,
            ]
            .iter()
            .map(|b| b.as_entire_binding())
            .collect(),
        );
        let shader = ShaderDesc::new("accel/lbvh.wgsl");
        let constants = [("LIGHT_TREE", if tree { 1.0 } else { 0.0 })];
        let pipelines = PASSES
            .iter()
            .filter(|entry| tree || !LIGHT_TREE_PASSES.contains(entry))
            .map(|&entry| Ok((entry, bindings::compute_pipeline_with_constants(device, entry, &shader, &[&layout], &constants)?)))
            .collect::<Result<_>>()?;
        Ok(Self {
            pipelines,
            bind_group,
            sort: GpuRadixSort::new(ctx, &keys, &sorted_keys, capacity)?,
            params,
            boxes,
            emitters,
            target,
            capacity,
            count: 0,
            max_leaf_size: 1,
        })
    }

    /// Builds leaves of up to `size` boxes (1 to [`MAX_LEAF_SIZE`]): subtrees of Karras's hierarchy
    /// over at most that many boxes become leaves. Takes effect at the next `set_boxes` or
    /// `set_gpu_boxes`.
    pub fn with_max_leaf_size(mut self, size: u32) -> Self {
        self.max_leaf_size = size.clamp(1, MAX_LEAF_SIZE);
        self
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
        self.sort.set_problem(queue, self.count, MORTON_BITS)?;
        // The Morton grid spans the box centres, computed as `lbvh.wgsl` does (no overflow near f32::MAX).
        let centre = |b: &Aabb| b.min * 0.5 + b.max * 0.5;
        let (centre_min, centre_max) =
            boxes.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(low, high), b| (low.min(centre(b)), high.max(centre(b))));
        let t = &self.target;
        let params = LbvhParams {
            count: self.count,
            node_base: t.node_base,
            primitive_base: t.primitive_base,
            item_base: t.item_base,
            max_leaf_size: self.max_leaf_size,
            leaf_base: t.leaf_base,
            _pad: [0; 2],
            centre_min: centre_min.extend(0.0).to_array(),
            centre_max: centre_max.extend(0.0).to_array(),
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        Ok(())
    }

    /// Sets every following build to `count` boxes that a GPU pass writes into [`boxes`](Self::boxes)
    /// before each build (`GpuBox` layout: min, max as vec4s), with Morton codes over `centres`: box
    /// centres outside it are clamped into it, which keeps the tree exact, only looser.
    pub fn set_gpu_boxes(&mut self, queue: &wgpu::Queue, count: u32, centres: &Aabb) -> Result<()> {
        if count > self.capacity {
            return Err(Error::InvalidConfig(format!("{count} volumes exceed the BVH's capacity of {}", self.capacity)));
        }
        if !centres.is_valid() {
            return Err(Error::InvalidScene(format!("the Morton domain {centres:?} of GPU-written boxes is not finite")));
        }
        self.count = count;
        self.sort.set_problem(queue, count, MORTON_BITS)?;
        let t = &self.target;
        let params = LbvhParams {
            count,
            node_base: t.node_base,
            primitive_base: t.primitive_base,
            item_base: t.item_base,
            max_leaf_size: self.max_leaf_size,
            leaf_base: t.leaf_base,
            _pad: [0; 2],
            centre_min: centres.min.extend(0.0).to_array(),
            centre_max: centres.max.extend(0.0).to_array(),
        };
        queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        Ok(())
    }

    /// The boxes the next build reads, for a GPU pass to write (see [`set_gpu_boxes`](Self::set_gpu_boxes)).
    pub fn boxes(&self) -> &wgpu::Buffer {
        &self.boxes
    }

    /// Sets the emitters of the boxes [`set_boxes`](Self::set_boxes) set, one per box, for the light
    /// tree (a light's: [`LightTreeNode::of_light`]). Errors without a light tree.
    pub fn set_emitters(&mut self, queue: &wgpu::Queue, emitters: &[LightTreeNode]) -> Result<()> {
        if self.target.light_tree.is_none() {
            return Err(Error::InvalidConfig(
                "emitters given to a BVH built without a light tree; build it with GpuLbvh::with_light_tree or a target with a light tree"
                    .into(),
            ));
        }
        if emitters.len() != self.count as usize {
            return Err(Error::InvalidConfig(format!("{} emitters for {} boxes; give one per box", emitters.len(), self.count)));
        }
        if !emitters.is_empty() {
            queue.write_buffer(&self.emitters, 0, bytemuck::cast_slice(emitters));
        }
        Ok(())
    }

    /// The emitters the next build reads where it builds a light tree, for a GPU pass to write, one
    /// [`LightTreeNode`] per box of [`boxes`](Self::boxes).
    pub fn emitters(&self) -> &wgpu::Buffer {
        &self.emitters
    }

    /// The first of the build's primitive indices in its target's `primitives`.
    pub fn primitive_base(&self) -> u32 {
        self.target.primitive_base
    }

    /// Number of nodes the last `set_boxes` builds (0 for no boxes).
    pub fn node_count(&self) -> u32 {
        (2 * self.count).saturating_sub(1)
    }

    /// Records a full rebuild. `span` says which scope it is timed in: builds of several BVHs in a
    /// row may share one.
    pub fn record(&mut self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, span: TimerSpan) -> Result<()> {
        if self.count == 0 {
            return Ok(());
        }
        let items = self.count.div_ceil(WORKGROUP);
        let nodes = (self.count - 1).div_ceil(WORKGROUP);
        let last = self.pipelines.len() - 1;
        for (index, (entry, pipeline)) in self.pipelines.iter().enumerate() {
            if *entry == "lbvh_hierarchy" {
                self.sort.record(encoder);
            }
            let timestamp_writes = timer.as_deref_mut().and_then(|t| match index {
                0 if span.starts => Some(t.span_start(span.name)),
                i if i == last && span.ends => Some(t.span_end(span.name)),
                _ => None,
            });
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(entry), timestamp_writes });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            let groups = match *entry {
                "lbvh_write_nodes" => nodes,
                "lbvh_block_power" => 1,
                _ => items,
            };
            pass.dispatch_workgroups(groups, 1, 1);
        }
        Ok(())
    }

    /// Reads the last build back, with indices local to it (as if `node_base`, `primitive_base`,
    /// `item_base` and `leaf_base` were 0) and only the nodes a walk reaches ([`Bvh::reachable`]): for tests and
    /// validation.
    pub fn read_back(&self, ctx: &GpuContext) -> Result<Bvh> {
        let copy = |source: &wgpu::Buffer, offset: u64, size: u64| read_range(ctx, source, offset, size);
        let t = &self.target;
        let nodes = copy(&t.nodes, u64::from(t.node_base) * 32, u64::from(self.node_count()) * 32)?;
        let primitives = copy(&t.primitives, u64::from(t.primitive_base) * 4, u64::from(self.count) * 4)?;
        ctx.check_errors()?;
        let mut bvh = Bvh { nodes: bytemuck::pod_collect_to_vec(&nodes), primitive_indices: bytemuck::pod_collect_to_vec(&primitives) };
        for node in &mut bvh.nodes {
            *node = node.offset(t.node_base.wrapping_neg(), t.leaf_base.wrapping_neg());
        }
        for primitive in &mut bvh.primitive_indices {
            *primitive = primitive.wrapping_sub(t.item_base);
        }
        Ok(bvh.reachable())
    }

    /// Reads the last build back with its light tree: every node as stored (unreachable ones too,
    /// with indices local to the build, as [`read_back`](Self::read_back) makes them) and each one's
    /// [`LightTreeNode`]; for tests. Errors without a light tree.
    pub fn read_back_light_tree(&self, ctx: &GpuContext) -> Result<(Vec<BvhNode>, Vec<LightTreeNode>)> {
        let t = &self.target;
        let Some(tree) = &t.light_tree else {
            return Err(Error::InvalidConfig(
                "this BVH is built without a light tree to read back; build it with GpuLbvh::with_light_tree".into(),
            ));
        };
        let (offset, size) = (u64::from(t.node_base) * 32, u64::from(self.node_count()) * 32);
        let read = |source: &wgpu::Buffer| read_range(ctx, source, offset, size);
        let nodes: Vec<BvhNode> = bytemuck::pod_collect_to_vec(&read(&t.nodes)?);
        let tree: Vec<LightTreeNode> = bytemuck::pod_collect_to_vec(&read(tree)?);
        ctx.check_errors()?;
        Ok((nodes.into_iter().map(|n| n.offset(t.node_base.wrapping_neg(), t.leaf_base.wrapping_neg())).collect(), tree))
    }
}

/// `size` bytes of a COPY_SRC buffer from `offset`.
fn read_range(ctx: &GpuContext, source: &wgpu::Buffer, offset: u64, size: u64) -> Result<Vec<u8>> {
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("lbvh readback"),
        size: size.max(4),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    if size > 0 {
        encoder.copy_buffer_to_buffer(source, offset, &staging, 0, size);
    }
    ctx.queue.submit([encoder.finish()]);
    let mut bytes: Vec<u8> = readback::map_buffer(ctx, &staging, 0, size.max(4))?;
    bytes.truncate(size as usize);
    Ok(bytes)
}

fn check_binding_size(ctx: &GpuContext, capacity: u32, node_bytes: u64) -> Result<()> {
    // The per-item passes are one row of workgroups.
    let groups = capacity.div_ceil(WORKGROUP);
    if groups > ctx.limits.max_compute_workgroups_per_dimension {
        return Err(Error::InvalidConfig(format!(
            "a GPU-built BVH over {capacity} volumes needs {groups} workgroups in a row, over this GPU's limit of {}; use at most {} volumes per group",
            ctx.limits.max_compute_workgroups_per_dimension,
            ctx.limits.max_compute_workgroups_per_dimension * WORKGROUP
        )));
    }
    let limit = ctx.limits.max_storage_buffer_binding_size;
    if node_bytes > limit {
        return Err(Error::InvalidConfig(format!(
            "a BVH over {capacity} volumes needs {} MiB of nodes, over this GPU's storage binding limit of {} MiB",
            node_bytes >> 20,
            limit >> 20
        )));
    }
    Ok(())
}
