//! The hardware back end of the ray hierarchy (`settings::RayBackend::Hardware`): wgpu builds a
//! bottom-level acceleration structure over every stored BLAS's triangles, in the same leaf order
//! (so primitive k of a BLAS is triangle `first_triangle + k` of `RayStructure::triangles`, which
//! shading reads for the hit), and a top level over the instances in `RayStructure::instances`' order
//! (custom index: the instance's place there). `trace_ray_query.wgsl` traces them.
//!
//! The triangles' corners are one buffer, three positions per stored triangle. A deformed mesh's
//! copies are refitted on the GPU every frame (`refit.rs`); `hardware_corners.wgsl` then writes the
//! frame's copy's corners from its refitted triangles, and that copy's bottom level is rebuilt (wgpu
//! has no refit). The top level is rebuilt whenever instances may have moved.

use std::ops::Range;

use wgpu::util::DeviceExt;

use super::RayStructure;
use crate::{
    accel::hardware::blas_descriptor,
    gpu::{bindings, shaders::ShaderDesc, timestamps::timed, GpuContext, GpuTimer},
    Error, Result,
};

/// Bytes of one corner: three `f32`.
const CORNER_BYTES: u64 = 12;

struct HardwareBlas {
    size: wgpu::BlasTriangleGeometrySizeDescriptor,
    first_corner: u32,
    blas: wgpu::Blas,
}

/// The GPU pass writing deformed copies' corners from their refitted triangles: one dispatch over
/// each copy's range of triangles (every deformed mesh's copy `parity` is one range, `RayStructure::
/// deformed`).
struct CornerPass {
    pipeline: wgpu::ComputePipeline,
    bind_groups: [wgpu::BindGroup; 2],
    ranges: [Range<u32>; 2],
}

pub struct HardwareRays {
    blases: Vec<HardwareBlas>,
    /// Each deformed mesh's two copies, as indices into `blases`.
    deformed: Vec<[usize; 2]>,
    corners: wgpu::Buffer,
    corner_pass: Option<CornerPass>,
    tlas: wgpu::Tlas,
    built: bool,
}

impl HardwareRays {
    /// The structures over `rays`' BLASes and instances; nothing is built before the first
    /// [`HardwareRays::record`].
    pub fn new(ctx: &GpuContext, rays: &RayStructure) -> Result<Self> {
        let limits = &ctx.limits;
        if rays.instances.len() as u64 > u64::from(limits.max_tlas_instance_count) {
            return Err(Error::InvalidScene(format!(
                "{} mesh instances to trace, over this GPU's {} a top-level acceleration structure holds; use --ray-backend software",
                rays.instances.len(),
                limits.max_tlas_instance_count
            )));
        }
        let corners: Vec<[f32; 3]> = rays
            .triangles
            .iter()
            .flat_map(|t| {
                let v0 = glam::Vec3::from(t.v0);
                [v0, v0 + glam::Vec3::from(t.e1), v0 + glam::Vec3::from(t.e2)].map(|v| v.to_array())
            })
            .collect();
        let corners = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ray triangle corners"),
            // At least one corner: a hierarchy with no triangle still binds a buffer.
            contents: if corners.is_empty() { &[0; CORNER_BYTES as usize] } else { bytemuck::cast_slice(&corners) },
            usage: wgpu::BufferUsages::BLAS_INPUT | wgpu::BufferUsages::STORAGE,
        });
        let deformed_roots: Vec<u32> = rays.deformed.iter().flat_map(|d| d.roots).collect();
        let mut blases = Vec::with_capacity(rays.blases.len());
        for span in &rays.blases {
            let count = span.triangles.len() as u32;
            if u64::from(count) > u64::from(limits.max_blas_primitive_count) {
                return Err(Error::InvalidScene(format!(
                    "a mesh of {count} triangles, over this GPU's {} a bottom-level acceleration structure holds; use --ray-backend software",
                    limits.max_blas_primitive_count
                )));
            }
            let size = wgpu::BlasTriangleGeometrySizeDescriptor {
                vertex_format: wgpu::VertexFormat::Float32x3,
                vertex_count: 3 * count,
                index_format: None,
                index_count: None,
                // Alpha-masked triangles come back to the shader as candidates.
                flags: if span.alpha_masked {
                    wgpu::AccelerationStructureGeometryFlags::empty()
                } else {
                    wgpu::AccelerationStructureGeometryFlags::OPAQUE
                },
            };
            let rebuilt = deformed_roots.contains(&span.root);
            let blas = ctx.device.create_blas(
                &blas_descriptor("ray blas", rebuilt),
                wgpu::BlasGeometrySizeDescriptors::Triangles { descriptors: vec![size.clone()] },
            );
            blases.push(HardwareBlas { size, first_corner: 3 * span.triangles.start, blas });
        }
        let index_of = |root: u32| rays.blas_index(root).expect("deformed roots are stored BLASes");
        let deformed = rays.deformed.iter().map(|d| d.roots.map(index_of)).collect();
        let tlas = ctx.device.create_tlas(&wgpu::CreateTlasDescriptor {
            label: Some("ray tlas"),
            max_instances: rays.instances.len().max(1) as u32,
            flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
            update_mode: wgpu::AccelerationStructureUpdateMode::Build,
        });
        Ok(Self { blases, deformed, corners, corner_pass: None, tlas, built: false })
    }

    /// The top level, which the scene's bind group holds.
    pub fn tlas(&self) -> &wgpu::Tlas {
        &self.tlas
    }

    /// Sets up the pass that writes deformed copies' corners from `triangles` (the scene's ray
    /// triangles, which the refit rewrites), where `rays` has deformed meshes.
    pub fn with_deformed_corners(mut self, ctx: &GpuContext, rays: &RayStructure, triangles: &wgpu::Buffer) -> Result<Self> {
        if rays.deformed.is_empty() {
            return Ok(self);
        }
        let copy_range = |copy: usize| {
            let ranges = rays.deformed.iter().map(|d| d.triangles[copy].clone());
            let start = ranges.clone().map(|r| r.start).min().unwrap_or(0);
            start..ranges.map(|r| r.end).max().unwrap_or(0)
        };
        let ranges = [copy_range(0), copy_range(1)];
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = bindings::layout(
            &ctx.device,
            "hardware_corners",
            &[bindings::uniform(0, compute), bindings::storage_read(1, compute), bindings::storage_read_write(2, compute)],
        );
        let pipeline =
            bindings::compute_pipeline(&ctx.device, "hardware_corners", &ShaderDesc::new("rays/hardware_corners.wgsl"), &[&layout])?;
        let bind_groups = ranges.clone().map(|range| {
            let uniform = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("hardware corners range"),
                contents: bytemuck::cast_slice(&[range.start, range.end, 0, 0]),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            bindings::bind_group(
                &ctx.device,
                "hardware_corners",
                &layout,
                vec![uniform.as_entire_binding(), triangles.as_entire_binding(), self.corners.as_entire_binding()],
            )
        });
        self.corner_pass = Some(CornerPass { pipeline, bind_groups, ranges });
        Ok(self)
    }

    /// Records this frame's builds, after the refit of copy `parity`: every bottom level the first
    /// time, then the deformed meshes' copy `parity` every frame (its corners written first), and the
    /// top level over `rays`' instances as placed now, the first time and whenever `moved`.
    pub fn record(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        mut timer: Option<&mut GpuTimer>,
        rays: &RayStructure,
        parity: usize,
        moved: bool,
    ) {
        let rebuilt: Vec<usize> =
            if self.built { self.deformed.iter().map(|copies| copies[parity]).collect() } else { (0..self.blases.len()).collect() };
        if let Some(pass) = self.corner_pass.as_ref().filter(|p| !p.ranges[parity].is_empty()) {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("hardware_corners"),
                timestamp_writes: timer.as_deref_mut().map(|t| t.compute_pass("hardware_corners")),
            });
            compute.set_pipeline(&pass.pipeline);
            compute.set_bind_group(0, &pass.bind_groups[parity], &[]);
            compute.dispatch_workgroups((pass.ranges[parity].len() as u32).div_ceil(64), 1, 1);
        }
        if !rebuilt.is_empty() {
            let entries: Vec<wgpu::BlasBuildEntry> = rebuilt
                .iter()
                .map(|&b| {
                    let blas = &self.blases[b];
                    wgpu::BlasBuildEntry {
                        blas: &blas.blas,
                        geometry: wgpu::BlasGeometries::TriangleGeometries(vec![wgpu::BlasTriangleGeometry {
                            size: &blas.size,
                            vertex_buffer: &self.corners,
                            first_vertex: blas.first_corner,
                            vertex_stride: CORNER_BYTES,
                            index_buffer: None,
                            first_index: None,
                            transform_buffer: None,
                            transform_buffer_offset: None,
                        }]),
                    }
                })
                .collect();
            timed(encoder, timer.as_deref_mut(), "ray_blas_build", |encoder| {
                encoder.build_acceleration_structures(&entries, std::iter::empty());
            });
        }
        // The first frame builds the top level even over no instance: shading binds it.
        if self.built && !moved && rebuilt.is_empty() {
            return;
        }
        for (slot, instance) in rays.instances.iter().enumerate() {
            let local_from_world = affine_from_rows(&instance.local_from_world);
            let det = local_from_world.matrix3.determinant();
            // Singular maps send every ray to a standstill in the software back end: no hit.
            self.tlas[slot] = (det.is_finite() && det != 0.0).then(|| {
                let blas = rays.blas_index(instance.blas_root).expect("instances place stored BLASes");
                let rows = crate::gpu::scene::affine_rows(&local_from_world.inverse());
                wgpu::TlasInstance::new(&self.blases[blas].blas, bytemuck::cast(rows), slot as u32, 0xff)
            });
        }
        let tlas = &self.tlas;
        timed(encoder, timer, "ray_tlas_build", |encoder| {
            encoder.build_acceleration_structures(std::iter::empty(), [tlas]);
        });
        self.built = true;
    }
}

/// The affine map whose rows (of `vec4(p, 1.0) * rows`) are `rows`.
fn affine_from_rows(rows: &[[f32; 4]; 3]) -> glam::Affine3A {
    glam::Affine3A::from_mat4(glam::Mat4::from_cols_array_2d(&[rows[0], rows[1], rows[2], [0.0, 0.0, 0.0, 1.0]]).transpose())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_become_the_map_they_describe() {
        let map = glam::Affine3A::from_scale_rotation_translation(
            glam::Vec3::new(1.0, 2.0, 0.5),
            glam::Quat::from_rotation_y(0.7),
            glam::Vec3::new(3.0, -1.0, 2.0),
        );
        let back = affine_from_rows(&crate::gpu::scene::affine_rows(&map));
        assert!(back.abs_diff_eq(map, 1e-6));
    }
}
