//! The hardware back end of a volume structure (`settings::RayBackend::Hardware`), the paper's own
//! mechanism: each group's volumes are a bottom-level acceleration structure of boxes (in the group's
//! space, in the order the structure stores the items, so primitive k of a group is its item
//! `first_item + k`), and a top-level one places the group instances (custom index: the instance's
//! index in the structure's instance buffer). wgpu builds both; shading asks them with a ray query of
//! minimal length from the shading point (`shading/enumerate/*_ray_query.wgsl`), whose box candidates
//! get the exact test and are accumulated without committing.
//!
//! wgpu has no refit: groups asked to be rebuilt every frame (`gpu-every-frame`, as volumes that
//! change need) are built again from their boxes each frame, and the dynamic group (particle lights)
//! from the boxes its pass writes, packed by `hardware_boxes.wgsl`; the top level is rebuilt whenever
//! an instance moves or a group is rebuilt.

use glam::Affine3A;
use wgpu::util::DeviceExt;

use super::Aabb;
use crate::{
    gpu::{bindings, scene::affine_rows, shaders::ShaderDesc, timestamps::timed, GpuContext, GpuTimer},
    Error, Result,
};

/// One group's bottom level: its boxes as the build reads them (min then max, six floats a box),
/// and the structure built over them. Empty groups have none: no instance places them.
struct HardwareGroup {
    boxes: wgpu::Buffer,
    size: wgpu::BlasAABBGeometrySizeDescriptor,
    blas: wgpu::Blas,
    /// Built again every frame.
    rebuilt: bool,
}

/// The pass packing the dynamic group's boxes, written every frame in the LBVH's layout, into its
/// bottom level's box buffer.
struct PackBoxes {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    count: u32,
    scope: &'static str,
}

/// A group whose boxes a GPU pass writes every frame: `boxes` holds `count` of them in the LBVH's
/// layout (`accel/lbvh.wgsl`'s `Box`).
pub struct DynamicBoxes<'a> {
    pub boxes: &'a wgpu::Buffer,
    pub count: u32,
}

/// The timer scopes of a structure's builds: the bottom levels, the top level, and the dynamic
/// group's box packing.
pub struct HardwareScopes {
    pub groups: &'static str,
    pub top_level: &'static str,
    pub pack: &'static str,
}

pub struct HardwareVolumes {
    groups: Vec<Option<HardwareGroup>>,
    pack: Option<PackBoxes>,
    tlas: wgpu::Tlas,
    /// The bottom levels were built (at the first frame, for those built once).
    built: bool,
    scopes: HardwareScopes,
}

/// Bytes between boxes in a group's box buffer: `vec3` min then `vec3` max.
const BOX_STRIDE: u64 = wgpu::AABB_GEOMETRY_MIN_STRIDE;
/// Workgroup size of `hardware_boxes.wgsl`.
const PACK_WORKGROUP: u32 = 256;

impl HardwareVolumes {
    /// The bottom levels over `group_boxes` (each group's boxes in stored order), and over `dynamic`
    /// after them, and a top level with room for `instance_slots` instances; nothing is built until
    /// [`HardwareVolumes::record`].
    pub fn new(
        ctx: &GpuContext,
        label: &str,
        group_boxes: &[Vec<Aabb>],
        dynamic: Option<DynamicBoxes>,
        instance_slots: u32,
        rebuild_every_frame: bool,
        scopes: HardwareScopes,
    ) -> Result<Self> {
        let limits = &ctx.limits;
        if instance_slots > limits.max_tlas_instance_count {
            return Err(Error::InvalidScene(format!(
                "{instance_slots} {label} group instances, over this GPU's {} a top-level acceleration structure holds; use --ray-backend software",
                limits.max_tlas_instance_count
            )));
        }
        let fits = |count: u64| {
            if count > u64::from(limits.max_blas_primitive_count) {
                return Err(Error::InvalidScene(format!(
                    "a group of {count} {label}s, over this GPU's {} boxes per bottom-level acceleration structure; use --ray-backend software",
                    limits.max_blas_primitive_count
                )));
            }
            Ok(())
        };
        let mut groups = group_boxes
            .iter()
            .map(|boxes| {
                if boxes.is_empty() {
                    return Ok(None);
                }
                fits(boxes.len() as u64)?;
                let packed: Vec<[f32; 6]> = boxes.iter().map(|b| [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z]).collect();
                let buffer = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(&format!("{label} hardware boxes")),
                    contents: bytemuck::cast_slice(&packed),
                    usage: wgpu::BufferUsages::BLAS_INPUT,
                });
                Ok(Some(HardwareGroup::new(ctx, label, buffer, packed.len() as u32, rebuild_every_frame)))
            })
            .collect::<Result<Vec<_>>>()?;
        let pack = match dynamic.filter(|d| d.count > 0) {
            Some(DynamicBoxes { boxes, count }) => {
                fits(u64::from(count))?;
                let packed = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(&format!("{label} dynamic hardware boxes")),
                    size: u64::from(count) * BOX_STRIDE,
                    usage: wgpu::BufferUsages::BLAS_INPUT | wgpu::BufferUsages::STORAGE,
                    mapped_at_creation: false,
                });
                let pack = PackBoxes::new(ctx, boxes, &packed, count, scopes.pack)?;
                groups.push(Some(HardwareGroup::new(ctx, label, packed, count, true)));
                Some(pack)
            }
            None => None,
        };
        let tlas = ctx.device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some(&format!("{label} tlas")),
            max_instances: instance_slots,
            flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        Ok(Self { groups, pack, tlas, built: false, scopes })
    }

    /// The top level, as shading binds it.
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        self.tlas.as_binding()
    }

    /// Records this frame's builds, after the dynamic group's boxes are written: the bottom levels
    /// the first time, those rebuilt every frame each time; the top level over `placed()` (each
    /// instance's group and its place in the world, in instance-buffer order) when `moved` or a
    /// bottom level was built.
    pub fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        moved: bool,
        placed: impl FnOnce() -> Vec<(usize, Affine3A)>,
    ) {
        if let Some(pack) = &self.pack {
            pack.record(encoder, timer.as_deref_mut());
        }
        let first = !self.built;
        let entries: Vec<wgpu::BlasBuildEntry> = self
            .groups
            .iter()
            .flatten()
            .filter(|g| first || g.rebuilt)
            .map(|g| wgpu::BlasBuildEntry {
                blas: &g.blas,
                geometry: wgpu::BlasGeometries::AabbGeometries(vec![wgpu::BlasAabbGeometry {
                    size: &g.size,
                    stride: BOX_STRIDE,
                    aabb_buffer: &g.boxes,
                    primitive_offset: 0,
                }]),
            })
            .collect();
        let built_groups = !entries.is_empty();
        if built_groups {
            timed(encoder, timer.as_deref_mut(), self.scopes.groups, |encoder| {
                encoder.build_acceleration_structures(&entries, std::iter::empty());
            });
        }
        if !(first || moved || built_groups) {
            return;
        }
        for (slot, (group, world_from_group)) in placed().iter().enumerate() {
            let blas = &self.groups[*group].as_ref().expect("instances place non-empty groups").blas;
            let transform: [f32; 12] = bytemuck::cast(affine_rows(world_from_group));
            self.tlas[slot] = Some(wgpu::TlasInstance::new(blas, transform, slot as u32, 0xff));
        }
        let tlas = &self.tlas;
        timed(encoder, timer, self.scopes.top_level, |encoder| {
            encoder.build_acceleration_structures(std::iter::empty(), [tlas]);
        });
        self.built = true;
    }
}

impl HardwareGroup {
    fn new(ctx: &GpuContext, label: &str, boxes: wgpu::Buffer, count: u32, rebuilt: bool) -> Self {
        let size = wgpu::BlasAABBGeometrySizeDescriptor {
            primitive_count: count,
            // Opaque: a candidate is tested and accumulated by the shader, never committed.
            flags: wgpu::AccelerationStructureGeometryFlags::OPAQUE,
        };
        let blas = ctx.device.create_blas(
            &blas_descriptor(&format!("{label} blas"), rebuilt),
            wgpu::BlasGeometrySizeDescriptors::AABBs { descriptors: vec![size.clone()] },
        );
        Self { boxes, size, blas, rebuilt }
    }
}

/// A bottom level's descriptor: rebuilt every frame, build speed first; built once, trace speed.
pub(crate) fn blas_descriptor(label: &str, rebuilt_every_frame: bool) -> wgpu::CreateBlasDescriptor<'_> {
    wgpu::CreateBlasDescriptor {
        label: Some(label),
        flags: if rebuilt_every_frame {
            wgpu::AccelerationStructureFlags::PREFER_FAST_BUILD
        } else {
            wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE
        },
        update_mode: wgpu::AccelerationStructureUpdateMode::Build,
    }
}

impl PackBoxes {
    fn new(ctx: &GpuContext, boxes: &wgpu::Buffer, packed: &wgpu::Buffer, count: u32, scope: &'static str) -> Result<Self> {
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = bindings::layout(
            &ctx.device,
            "hardware_boxes",
            &[bindings::uniform(0, compute), bindings::storage_read(1, compute), bindings::storage_read_write(2, compute)],
        );
        let pipeline =
            bindings::compute_pipeline(&ctx.device, "hardware_boxes", &ShaderDesc::new("accel/hardware_boxes.wgsl"), &[&layout])?;
        let uniform = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("hardware boxes count"),
            contents: bytemuck::cast_slice(&[count, 0, 0, 0]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind_group = bindings::bind_group(
            &ctx.device,
            "hardware_boxes",
            &layout,
            vec![uniform.as_entire_binding(), boxes.as_entire_binding(), packed.as_entire_binding()],
        );
        Ok(Self { pipeline, bind_group, count, scope })
    }

    fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hardware_boxes"),
            timestamp_writes: timer.map(|t| t.compute_pass(self.scope)),
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.dispatch_workgroups(self.count.div_ceil(PACK_WORKGROUP), 1, 1);
    }
}
