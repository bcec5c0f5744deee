//! The hardware back end of a volume structure (`settings::RayBackend::Hardware`), the paper's own
//! mechanism: each group's volumes are a bottom-level acceleration structure of boxes (in the group's
//! space, in the order the structure stores the items, so primitive k of a group is its item
//! `first_item + k`), and a top-level one places the group instances (custom index: the instance's
//! index in the structure's instance buffer). wgpu builds both; shading asks them with a ray query of
//! minimal length from the shading point (`shading/enumerate/*_ray_query.wgsl`), whose box candidates
//! get the exact test and are accumulated without committing.
//!
//! wgpu has no refit, so groups whose volumes change are rebuilt every frame (`rebuild_every_frame`),
//! and the top level whenever an instance moves or a group is rebuilt.

use glam::Affine3A;
use wgpu::util::DeviceExt;

use super::Aabb;
use crate::{
    gpu::{scene::affine_rows, timestamps::timed, GpuContext, GpuTimer},
    Error, Result,
};

/// One group's bottom level: its boxes as the build reads them (min then max, six floats a box),
/// and the structure built over them. Empty groups have none: no instance places them.
struct HardwareGroup {
    boxes: wgpu::Buffer,
    size: wgpu::BlasAABBGeometrySizeDescriptor,
    blas: wgpu::Blas,
}

pub struct HardwareVolumes {
    groups: Vec<Option<HardwareGroup>>,
    tlas: wgpu::Tlas,
    rebuild_every_frame: bool,
    /// The bottom levels were built (at the first frame, when built once).
    built: bool,
    blas_scope: &'static str,
    tlas_scope: &'static str,
}

/// Bytes between boxes in a group's box buffer: `vec3` min then `vec3` max.
const BOX_STRIDE: u64 = wgpu::AABB_GEOMETRY_MIN_STRIDE;

impl HardwareVolumes {
    /// The bottom levels over `group_boxes` (each group's boxes in stored order) and a top level
    /// with room for `instance_slots` instances; nothing is built until [`HardwareVolumes::record`].
    pub fn new(
        ctx: &GpuContext,
        label: &str,
        group_boxes: &[Vec<Aabb>],
        instance_slots: u32,
        rebuild_every_frame: bool,
        (blas_scope, tlas_scope): (&'static str, &'static str),
    ) -> Result<Self> {
        let limits = &ctx.limits;
        if instance_slots > limits.max_tlas_instance_count {
            return Err(Error::InvalidScene(format!(
                "{instance_slots} {label} group instances, over this GPU's {} a top-level acceleration structure holds; use --ray-backend software",
                limits.max_tlas_instance_count
            )));
        }
        let groups = group_boxes
            .iter()
            .map(|boxes| {
                if boxes.is_empty() {
                    return Ok(None);
                }
                if boxes.len() as u64 > u64::from(limits.max_blas_primitive_count) {
                    return Err(Error::InvalidScene(format!(
                        "a group of {} {label}s, over this GPU's {} boxes per bottom-level acceleration structure; use --ray-backend software",
                        boxes.len(),
                        limits.max_blas_primitive_count
                    )));
                }
                let packed: Vec<[f32; 6]> =
                    boxes.iter().map(|b| [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z]).collect();
                let boxes = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(&format!("{label} hardware boxes")),
                    contents: bytemuck::cast_slice(&packed),
                    usage: wgpu::BufferUsages::BLAS_INPUT,
                });
                let size = wgpu::BlasAABBGeometrySizeDescriptor {
                    primitive_count: packed.len() as u32,
                    // Opaque: a candidate is tested and accumulated by the shader, never committed.
                    flags: wgpu::AccelerationStructureGeometryFlags::OPAQUE,
                };
                let blas = ctx.device.create_blas(
                    &wgpu::CreateBlasDescriptor {
                        label: Some(&format!("{label} blas")),
                        flags: build_flags(rebuild_every_frame),
                        update_mode: wgpu::AccelerationStructureUpdateMode::Build,
                    },
                    wgpu::BlasGeometrySizeDescriptors::AABBs { descriptors: vec![size.clone()] },
                );
                Ok(Some(HardwareGroup { boxes, size, blas }))
            })
            .collect::<Result<Vec<_>>>()?;
        let tlas = ctx.device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some(&format!("{label} tlas")),
            max_instances: instance_slots,
            flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        Ok(Self { groups, tlas, rebuild_every_frame, built: false, blas_scope, tlas_scope })
    }

    /// The top level, as shading binds it.
    pub fn binding(&self) -> wgpu::BindingResource<'_> {
        self.tlas.as_binding()
    }

    /// Records this frame's builds: the bottom levels the first time, or every frame where they are
    /// rebuilt; the top level over `placed` (each instance's group and its place in the world, in
    /// instance-buffer order) when `moved` or a bottom level was built.
    pub fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        placed: &[(usize, Affine3A)],
        moved: bool,
    ) {
        let build_groups = !self.built || self.rebuild_every_frame;
        if build_groups {
            let entries: Vec<wgpu::BlasBuildEntry> = self
                .groups
                .iter()
                .flatten()
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
            timed(encoder, timer.as_deref_mut(), self.blas_scope, |encoder| {
                encoder.build_acceleration_structures(&entries, std::iter::empty());
            });
            self.built = true;
        }
        if !(moved || build_groups) {
            return;
        }
        for (slot, (group, world_from_group)) in placed.iter().enumerate() {
            let blas = &self.groups[*group].as_ref().expect("instances place non-empty groups").blas;
            let rows = affine_rows(world_from_group);
            let transform: [f32; 12] = bytemuck::cast(rows);
            self.tlas[slot] = Some(wgpu::TlasInstance::new(blas, transform, slot as u32, 0xff));
        }
        let tlas = &self.tlas;
        timed(encoder, timer, self.tlas_scope, |encoder| {
            encoder.build_acceleration_structures(std::iter::empty(), [tlas]);
        });
    }
}

/// Builds rebuilt every frame favour build speed; built once, trace speed.
fn build_flags(rebuild_every_frame: bool) -> wgpu::AccelerationStructureFlags {
    if rebuild_every_frame {
        wgpu::AccelerationStructureFlags::PREFER_FAST_BUILD
    } else {
        wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE
    }
}
