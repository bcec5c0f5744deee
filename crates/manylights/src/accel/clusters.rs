//! Clustered shading's lists (Olsson, Billeter & Assarsson, "Clustered Deferred and Forward Shading",
//! HPG 2012), the baseline the acceleration structures are compared against. The view frustum is cut
//! into froxels: screen tiles of [`CLUSTER_TILE_PIXELS`] and [`CLUSTER_SLICES`] depth slices,
//! exponential in view depth from the near plane to the far side of the scene
//! (`cluster_grid.wgsl`). Every frame the GPU lists, per froxel, the (instance, item) pairs whose
//! bounds reach it (`cluster_build.wgsl`: count, prefix sums, fill); shading reads its froxel's list
//! and applies each volume's exact test, as brute force does.
//!
//! The lists' total length depends on the view, so it is known only on the GPU: the lists hold
//! [`ClusterLists::capacity`] entries, every frame records what it needed, and the renderer grows
//! them and renders again when a frame needed more (`Renderer::render_frames`).

use glam::Vec3;

use crate::{
    accel::light_aabb,
    gpu::{bindings, cluster_grid::ClusterGrid, shaders::ShaderDesc, GpuContext, GpuTimer},
    scene::{Decal, Light},
    Error, Result,
};

/// Threads per workgroup of the count and fill passes.
const PAIR_WORKGROUP: u32 = 64;
/// Froxels per workgroup of the scan passes (`SCAN_THREADS` in `workgroup_scan.wgsl`).
const SCAN_WORKGROUP: u32 = 256;
/// Bytes of one list entry: (instance, item).
const ENTRY_BYTES: u64 = 8;
/// Entries the lists start with, at least, per volume instance: grown when a frame needs more.
const INITIAL_ENTRIES_PER_PAIR: u64 = 4;
/// Workgroups of the spread passes (`SPREAD_WORKGROUPS` in `cluster_build.wgsl`).
const SPREAD_WORKGROUPS: u32 = 1024;
const PASSES: [&str; 7] = [
    "cluster_count",
    "cluster_count_spread",
    "cluster_scan_blocks",
    "cluster_scan_block_offsets",
    "cluster_scan_apply",
    "cluster_fill",
    "cluster_fill_spread",
];

/// A volume's bounds for binning, in its group's space: a sphere and an oriented box, each
/// containing the volume, widened by a few ulps as `light_aabb` is. Keep in sync with
/// `ClusterBounds` in `cluster_build.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ClusterBounds {
    /// xyz centre, w radius.
    pub sphere: [f32; 4],
    pub box_center: [f32; 4],
    /// Half extents along the box's axes.
    pub box_axes: [[f32; 4]; 3],
}

impl ClusterBounds {
    /// The light's range sphere and its tight box (the box of a spot's sector).
    pub fn of_light(light: &Light) -> Self {
        let aabb = light_aabb(light);
        let pad = 4.0 * f32::EPSILON * (light.position.abs().max_element() + light.range);
        Self::new(light.position, light.range + pad, aabb.center(), [Vec3::X, Vec3::Y, Vec3::Z].map(|a| a * (aabb.max - aabb.min) * 0.5))
    }

    /// The decal's own box, and the sphere through its corners.
    pub fn of_decal(decal: &Decal) -> Self {
        let t = &decal.world_from_decal;
        let axes = [t.matrix3.x_axis, t.matrix3.y_axis, t.matrix3.z_axis].map(|a| Vec3::from(a) * 0.5);
        let center = Vec3::from(t.translation);
        let pad = 4.0 * f32::EPSILON * (center.abs().max_element() + axes.iter().map(|a| a.length()).sum::<f32>());
        let axes = axes.map(|a| a + a.signum() * pad);
        let radius = axes.iter().map(|a| a.length_squared()).sum::<f32>().sqrt() + pad;
        Self::new(center, radius, center, axes)
    }

    fn new(center: Vec3, radius: f32, box_center: Vec3, axes: [Vec3; 3]) -> Self {
        Self {
            sphere: center.extend(radius).into(),
            box_center: box_center.extend(0.0).into(),
            box_axes: axes.map(|a| a.extend(0.0).into()),
        }
    }
}

/// Keep in sync with `ClusterBuildParams` in `cluster_build.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ClusterBuildParams {
    pair_count: u32,
    instance_count: u32,
    capacity: u32,
    row_threads: u32,
}

/// What a structure's clustered lists are called: the label of their buffers and the timer scope of
/// their build.
#[derive(Clone, Copy)]
pub struct ClusterNames {
    pub label: &'static str,
    pub scope: &'static str,
}

/// The clustered method's lists, for structures that shading reads through them: the froxel grid,
/// the bounds each volume is binned by (group space), and the scene's bind group layout, whose frame
/// uniforms the list build reads.
pub struct Clustering<'a> {
    pub grid: ClusterGrid,
    pub bounds: Vec<ClusterBounds>,
    pub frame_layout: &'a wgpu::BindGroupLayout,
}

impl Clustering<'_> {
    /// The lists over a structure's instances (`instances`, holding `instance_items` items each),
    /// whose items are stored in the order of `scene_indices` (their indices into `bounds`).
    pub fn lists(
        self,
        ctx: &GpuContext,
        names: ClusterNames,
        instances: &wgpu::Buffer,
        instance_items: &[u32],
        scene_indices: &[u32],
    ) -> Result<ClusterLists> {
        let bounds: Vec<ClusterBounds> = scene_indices.iter().map(|&i| self.bounds[i as usize]).collect();
        ClusterLists::new(ctx, names, self.frame_layout, instances, instance_items, &bounds, self.grid)
    }
}

/// One structure's per-froxel lists and the passes that build them.
pub struct ClusterLists {
    /// Per froxel, (first entry, length): bound to shading.
    pub ranges: wgpu::Buffer,
    /// (instance, item) pairs: bound to shading; replaced when grown.
    pub entries: wgpu::Buffer,
    label: &'static str,
    scope: &'static str,
    grid: ClusterGrid,
    pair_count: u32,
    instance_count: u32,
    capacity: u32,
    max_capacity: u32,
    pipelines: Vec<wgpu::ComputePipeline>,
    layout: wgpu::BindGroupLayout,
    bind_group: wgpu::BindGroup,
    params: wgpu::Buffer,
    inputs: [wgpu::Buffer; 3],
    counts: wgpu::Buffer,
    cursors: wgpu::Buffer,
    block_sums: wgpu::Buffer,
    status: wgpu::Buffer,
    status_readback: wgpu::Buffer,
    /// Pairs reaching many froxels, queued for the spread passes: a count, then a pair index each.
    spread: wgpu::Buffer,
}

impl ClusterLists {
    /// Lists over `bounds` (one per item) for the instances in `instances` (`VolumeInstance`s, whose
    /// item ranges `instance_items` gives), on the froxels of `grid`. `frame_layout` is the scene's
    /// bind group layout: the build reads the frame uniforms from it.
    pub fn new(
        ctx: &GpuContext,
        ClusterNames { label, scope }: ClusterNames,
        frame_layout: &wgpu::BindGroupLayout,
        instances: &wgpu::Buffer,
        instance_items: &[u32],
        bounds: &[ClusterBounds],
        grid: ClusterGrid,
    ) -> Result<Self> {
        let device = &ctx.device;
        let mut pair_starts = Vec::with_capacity(instance_items.len() + 1);
        let mut pairs = 0u64;
        for &items in instance_items {
            pair_starts.push(pairs as u32);
            pairs += u64::from(items);
        }
        let max_capacity = (ctx.limits.max_storage_buffer_binding_size / ENTRY_BYTES).min(u64::from(u32::MAX)) as u32;
        if pairs > u64::from(u32::MAX) {
            return Err(Error::InvalidScene(format!("{pairs} {label} instances are too many for clustered lists; use the bvh method")));
        }
        pair_starts.push(pairs as u32);
        let spread_bytes = 4 + pairs * 4;
        if spread_bytes > ctx.limits.max_storage_buffer_binding_size {
            return Err(Error::InvalidScene(format!(
                "{pairs} {label} instances need a {} MiB queue for clustered lists, over this GPU's storage binding limit of {} MiB; use the bvh method or fewer instances",
                spread_bytes >> 20,
                ctx.limits.max_storage_buffer_binding_size >> 20
            )));
        }
        let capacity = (pairs * INITIAL_ENTRIES_PER_PAIR).clamp(1 << 16, u64::from(max_capacity)) as u32;

        use wgpu::util::DeviceExt;
        use wgpu::BufferUsages as U;
        let buffer = |name: &str, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("{label} cluster {name}")),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            })
        };
        let init = |name: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(&format!("{label} cluster {name}")),
                contents: if contents.is_empty() { &[0; 16] } else { contents },
                usage: U::STORAGE,
            })
        };
        let froxels = u64::from(grid.froxels());
        let inputs =
            [instances.clone(), init("bounds", bytemuck::cast_slice(bounds)), init("pair starts", bytemuck::cast_slice(&pair_starts))];
        let params = buffer("params", std::mem::size_of::<ClusterBuildParams>() as u64, U::UNIFORM | U::COPY_DST);
        let counts = buffer("counts", froxels * 4, U::STORAGE | U::COPY_DST);
        let ranges = buffer("ranges", froxels * 8, U::STORAGE);
        let cursors = buffer("cursors", froxels * 4, U::STORAGE);
        let entries = buffer("entries", u64::from(capacity) * ENTRY_BYTES, U::STORAGE);
        let block_sums = buffer("block sums", froxels.div_ceil(u64::from(SCAN_WORKGROUP)) * 4, U::STORAGE);
        let status = buffer("status", 8, U::STORAGE | U::COPY_SRC | U::COPY_DST);
        let status_readback = buffer("status readback", 8, U::MAP_READ | U::COPY_DST);
        let spread = buffer("spread queue", spread_bytes, U::STORAGE | U::COPY_DST);

        let compute = wgpu::ShaderStages::COMPUTE;
        // Keep in sync with the bindings of `cluster_build.wgsl`.
        let mut entries_layout = vec![bindings::uniform(0, compute)];
        entries_layout.extend((1..=3).map(|b| bindings::storage_read(b, compute)));
        entries_layout.extend((4..=10).map(|b| bindings::storage_read_write(b, compute)));
        let layout = bindings::layout(device, "cluster build", &entries_layout);
        let shader = ShaderDesc::new("accel/cluster_build.wgsl");
        let pipelines = PASSES
            .iter()
            .map(|entry| bindings::compute_pipeline(device, entry, &shader, &[frame_layout, &layout]))
            .collect::<Result<_>>()?;
        let bind_group = build_bind_group(
            ctx,
            &layout,
            [&params, &inputs[0], &inputs[1], &inputs[2], &counts, &ranges, &cursors, &entries, &block_sums, &status, &spread],
        );
        let mut lists = Self {
            bind_group,
            ranges,
            entries,
            label,
            scope,
            grid,
            pair_count: pairs as u32,
            instance_count: instance_items.len() as u32,
            capacity,
            max_capacity,
            pipelines,
            layout,
            params,
            inputs,
            counts,
            cursors,
            block_sums,
            status,
            status_readback,
            spread,
        };
        lists.bind(ctx);
        Ok(lists)
    }

    /// Entries the lists hold now.
    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// Writes the build's parameters and bind group for the current entries buffer.
    fn bind(&mut self, ctx: &GpuContext) {
        let params = ClusterBuildParams {
            pair_count: self.pair_count,
            instance_count: self.instance_count,
            capacity: self.capacity,
            row_threads: self.dispatch().0 * PAIR_WORKGROUP,
        };
        ctx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let buffers = [
            &self.params,
            &self.inputs[0],
            &self.inputs[1],
            &self.inputs[2],
            &self.counts,
            &self.ranges,
            &self.cursors,
            &self.entries,
            &self.block_sums,
            &self.status,
            &self.spread,
        ];
        self.bind_group = build_bind_group(ctx, &self.layout, buffers);
    }

    /// Workgroups of the per-pair passes, as (x, y): rows of at most 65535.
    fn dispatch(&self) -> (u32, u32) {
        let groups = self.pair_count.div_ceil(PAIR_WORKGROUP).max(1);
        let x = groups.min(65535);
        (x, groups.div_ceil(x))
    }

    /// Records this frame's build, timed as one scope. The frame uniforms must be written.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, frame: &wgpu::BindGroup) {
        if self.pair_count == 0 {
            return;
        }
        encoder.clear_buffer(&self.counts, 0, None);
        encoder.clear_buffer(&self.spread, 0, Some(4));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.scope),
            timestamp_writes: timer.map(|t| t.compute_pass(self.scope)),
        });
        pass.set_bind_group(0, frame, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        let blocks = self.grid.froxels().div_ceil(SCAN_WORKGROUP);
        let (x, y) = self.dispatch();
        for (entry, pipeline) in PASSES.iter().zip(&self.pipelines) {
            pass.set_pipeline(pipeline);
            match *entry {
                "cluster_count" | "cluster_fill" => pass.dispatch_workgroups(x, y, 1),
                "cluster_count_spread" | "cluster_fill_spread" => pass.dispatch_workgroups(SPREAD_WORKGROUPS, 1, 1),
                "cluster_scan_block_offsets" => pass.dispatch_workgroups(1, 1, 1),
                _ => pass.dispatch_workgroups(blocks, 1, 1),
            }
        }
    }

    /// Whether the lists held every entry the frames since the last call needed; if not, grows them
    /// (the caller renders those frames again, and rebinds `entries`).
    pub fn fitted(&mut self, ctx: &GpuContext) -> Result<bool> {
        let needed = crate::gpu::readback::take_most_needed(ctx, &self.status, &self.status_readback)?;
        if needed <= self.capacity {
            return Ok(true);
        }
        if needed > self.max_capacity {
            return Err(Error::InvalidScene(format!(
                "the clustered {} lists need {needed} entries ({} MiB) in this view, over this GPU's storage binding limit of {} MiB; \
                 use the bvh method, fewer or smaller {}s, or a smaller image",
                self.label,
                (u64::from(needed) * ENTRY_BYTES) >> 20,
                ctx.limits.max_storage_buffer_binding_size >> 20,
                self.label,
            )));
        }
        self.capacity = crate::gpu::readback::grown_capacity(needed, self.max_capacity);
        self.entries = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("{} cluster entries", self.label)),
            size: u64::from(self.capacity) * ENTRY_BYTES,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        self.bind(ctx);
        Ok(false)
    }
}

/// The build's bind group, buffers in `cluster_build.wgsl`'s binding order.
fn build_bind_group(ctx: &GpuContext, layout: &wgpu::BindGroupLayout, buffers: [&wgpu::Buffer; 11]) -> wgpu::BindGroup {
    bindings::bind_group(&ctx.device, "cluster build", layout, buffers.iter().map(|b| b.as_entire_binding()).collect())
}

#[cfg(test)]
mod tests {
    use std::mem::{offset_of, size_of};

    use glam::{Affine3A, Quat};

    use super::*;
    use crate::scene::LightKind;

    fn struct_layout(source: &str, name: &str) -> (u32, Vec<u32>) {
        let module = naga::front::wgsl::parse_str(source).unwrap();
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let (_, ty) = module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name)).unwrap();
        let naga::TypeInner::Struct { members, span } = &ty.inner else { panic!("{name} is not a struct") };
        (*span, members.iter().map(|m| m.offset).collect())
    }

    #[test]
    fn gpu_structs_match_their_wgsl_layouts() {
        let source = crate::gpu::shaders::ShaderDesc::new("accel/cluster_build.wgsl").compose().unwrap();
        let (span, offsets) = struct_layout(&source, "ClusterBounds");
        assert_eq!(span as usize, size_of::<ClusterBounds>());
        assert_eq!(offsets, [0, 16, 32, 48, 64]);
        assert_eq!(offset_of!(ClusterBounds, box_axes), 32);
        let (span, _) = struct_layout(&source, "ClusterBuildParams");
        assert_eq!(span as usize, size_of::<ClusterBuildParams>());
    }

    /// Points inside a volume are inside both of its bounds.
    #[test]
    fn bounds_contain_their_volumes() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let inside_box = |b: &ClusterBounds, p: Vec3| {
            let d = p - Vec3::from_slice(&b.box_center);
            b.box_axes.iter().all(|a| {
                let a = Vec3::from_slice(a);
                d.dot(a).abs() <= a.length_squared() * (1.0 + 1e-6)
            })
        };
        let inside_sphere = |b: &ClusterBounds, p: Vec3| (p - Vec3::from_slice(&b.sphere)).length() <= b.sphere[3];
        for _ in 0..200 {
            let position = Vec3::new(rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0));
            let kind = if rng.random_bool(0.5) {
                LightKind::Point
            } else {
                LightKind::Spot { inner_cone_angle: 0.0, outer_cone_angle: rng.random_range(0.05..1.5) }
            };
            let light = Light {
                position,
                range: rng.random_range(0.1..5.0),
                color: Vec3::ONE,
                intensity: 1.0,
                kind,
                direction: Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), 1.0).normalize(),
                cast_shadows: false,
            };
            let decal = Decal {
                world_from_decal: Affine3A::from_scale_rotation_translation(
                    Vec3::new(rng.random_range(0.1..3.0), rng.random_range(0.1..3.0), rng.random_range(0.1..3.0)),
                    Quat::from_rotation_arc(Vec3::Z, light.direction),
                    position,
                ),
                material: 0,
                layer: 0,
                weight: 1.0,
            };
            let (lb, db) = (ClusterBounds::of_light(&light), ClusterBounds::of_decal(&decal));
            for _ in 0..200 {
                let p = position + Vec3::new(rng.random_range(-6.0..6.0), rng.random_range(-6.0..6.0), rng.random_range(-6.0..6.0));
                if crate::accel::light_contains(&light, p) {
                    assert!(inside_sphere(&lb, p) && inside_box(&lb, p), "{light:?} {p}");
                }
                if crate::accel::decal_contains(&decal, p) {
                    assert!(inside_sphere(&db, p) && inside_box(&db, p), "{decal:?} {p}");
                }
            }
        }
    }
}
