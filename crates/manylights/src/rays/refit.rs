//! The GPU refit of deformed meshes' BLASes (`refit.wgsl`), every frame, into the copy the frame
//! traces (`RayStructure::deformed`): every deformed mesh's triangles from the deformed vertices in
//! one dispatch, then their nodes by height (leaves first; a node's height is one more than its
//! taller child's), one dispatch per height for all meshes together, in one compute pass timed as
//! `blas_refit`. Batching the meshes keeps the dispatches (each a barrier) to about a tree's height.

use super::RayStructure;
use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

/// Keep in sync with `RefitStep` in `refit.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct RefitStep {
    first: u32,
    count: u32,
    meshes: u32,
    mesh_count: u32,
}

/// Steps sit 256 bytes apart in their uniform buffer: wgpu's alignment for dynamic offsets.
const STEP_STRIDE: u64 = 256;

/// One dispatch: its kind (triangles or a depth's nodes), its step's slot and its invocation count.
struct Dispatch {
    nodes: bool,
    slot: u32,
    count: u32,
}

pub struct BlasRefit {
    triangles_pipeline: wgpu::ComputePipeline,
    nodes_pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    /// Each copy's dispatches, in order.
    dispatches: [Vec<Dispatch>; 2],
}

impl BlasRefit {
    /// The refit of `rays`' deformed BLASes (bound through `gpu_scene`'s buffers); `None` when none is
    /// deformed.
    pub fn new(ctx: &GpuContext, gpu_scene: &GpuScene, rays: &RayStructure) -> Result<Option<Self>> {
        if rays.deformed.is_empty() {
            return Ok(None);
        }
        let device = &ctx.device;
        let mut steps = Vec::new();
        let mut primitives: Vec<[u32; 2]> = Vec::new();
        // Per copy, each deformed mesh's triangle range and primitive table: (start, end, table, 0).
        let mut meshes: Vec<[u32; 4]> = Vec::new();
        let mut order: Vec<u32> = Vec::new();
        let mut dispatches = [Vec::new(), Vec::new()];
        let max_invocations = u64::from(ctx.limits.max_compute_workgroups_per_dimension) * 64;
        let tables: Vec<u32> = rays
            .deformed
            .iter()
            .map(|deformed| {
                let table = primitives.len() as u32;
                primitives.extend(
                    gpu_scene.primitive_ranges[deformed.mesh].iter().map(|&(first_index, _, base_vertex)| [first_index, base_vertex]),
                );
                table
            })
            .collect();
        for (copy, copy_dispatches) in dispatches.iter_mut().enumerate() {
            let mut push = |step: RefitStep, nodes: bool| {
                copy_dispatches.push(Dispatch { nodes, slot: steps.len() as u32, count: step.count });
                steps.push(step);
            };
            let first_mesh = meshes.len() as u32;
            meshes.extend(rays.deformed.iter().zip(&tables).map(|(d, &table)| [d.triangles[copy].start, d.triangles[copy].end, table, 0]));
            let start = rays.deformed.iter().map(|d| d.triangles[copy].start).min().unwrap_or(0);
            let end = rays.deformed.iter().map(|d| d.triangles[copy].end).max().unwrap_or(0);
            if u64::from(end - start) > max_invocations {
                return Err(crate::Error::InvalidScene(format!(
                    "the deformed meshes have {} triangles, over the {max_invocations} this GPU refits in one dispatch; deform fewer or smaller meshes",
                    end - start
                )));
            }
            let mesh_count = rays.deformed.len() as u32;
            push(RefitStep { first: start, count: end - start, meshes: first_mesh, mesh_count }, false);
            // Heights: children come before parents in each copy's order.
            let mut by_height: Vec<Vec<u32>> = Vec::new();
            for deformed in &rays.deformed {
                let mut height: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
                for &n in &deformed.refit_order[copy] {
                    let node = &rays.nodes[n as usize];
                    let h = if node.is_leaf() {
                        0
                    } else {
                        let first = node.entry;
                        1 + height[&first].max(height[&rays.nodes[first as usize].skip])
                    };
                    height.insert(n, h);
                    if by_height.len() <= h {
                        by_height.resize_with(h + 1, Vec::new);
                    }
                    by_height[h].push(n);
                }
            }
            for level in &by_height {
                let first = order.len() as u32;
                order.extend_from_slice(level);
                push(RefitStep { first, count: level.len() as u32, meshes: first_mesh, mesh_count }, true);
            }
        }
        let mut step_bytes = vec![0u8; steps.len() * STEP_STRIDE as usize];
        for (i, step) in steps.iter().enumerate() {
            let at = i * STEP_STRIDE as usize;
            step_bytes[at..at + std::mem::size_of::<RefitStep>()].copy_from_slice(bytemuck::bytes_of(step));
        }
        let init = |label, contents: &[u8], usage| {
            wgpu::util::DeviceExt::create_buffer_init(device, &wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
        };
        let step_buffer = init("refit steps", &step_bytes, wgpu::BufferUsages::UNIFORM);
        let primitive_buffer = init("refit primitives", bytemuck::cast_slice(&primitives), wgpu::BufferUsages::STORAGE);
        let order_buffer = init("refit order", bytemuck::cast_slice(&order), wgpu::BufferUsages::STORAGE);
        let mesh_buffer = init("refit meshes", bytemuck::cast_slice(&meshes), wgpu::BufferUsages::STORAGE);

        let c = wgpu::ShaderStages::COMPUTE;
        let step_size = wgpu::BufferSize::new(std::mem::size_of::<RefitStep>() as u64);
        // Keep in sync with `refit.wgsl`.
        let layout = bindings::layout(
            device,
            "blas_refit",
            &[
                bindings::uniform_dynamic(0, c, std::mem::size_of::<RefitStep>() as u64),
                bindings::storage_read(1, c),
                bindings::storage_read(2, c),
                bindings::storage_read(3, c),
                bindings::storage_read(4, c),
                bindings::storage_read_write(5, c),
                bindings::storage_read_write(6, c),
                bindings::storage_read(7, c),
            ],
        );
        let shader = ShaderDesc::new("rays/refit.wgsl");
        let triangles_pipeline = bindings::compute_pipeline(device, "refit_triangles", &shader, &[&layout])?;
        let nodes_pipeline = bindings::compute_pipeline(device, "refit_nodes", &shader, &[&layout])?;
        let bind_group = bindings::bind_group(
            device,
            "blas_refit",
            &layout,
            vec![
                wgpu::BindingResource::Buffer(wgpu::BufferBinding { buffer: &step_buffer, offset: 0, size: step_size }),
                gpu_scene.vertex_buffer.as_entire_binding(),
                gpu_scene.index_buffer.as_entire_binding(),
                primitive_buffer.as_entire_binding(),
                order_buffer.as_entire_binding(),
                gpu_scene.ray_node_buffer.as_entire_binding(),
                gpu_scene.ray_triangle_buffer.as_entire_binding(),
                mesh_buffer.as_entire_binding(),
            ],
        );
        Ok(Some(Self { triangles_pipeline, nodes_pipeline, bind_group, dispatches }))
    }

    /// Records the refit of copy `parity` of every deformed BLAS.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, parity: usize) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("blas_refit"),
            timestamp_writes: timer.map(|t| t.compute_pass("blas_refit")),
        });
        // Each dispatch reads what the one before wrote: wgpu orders dispatches of a pass.
        for dispatch in &self.dispatches[parity] {
            pass.set_pipeline(if dispatch.nodes { &self.nodes_pipeline } else { &self.triangles_pipeline });
            pass.set_bind_group(0, &self.bind_group, &[(u64::from(dispatch.slot) * STEP_STRIDE) as u32]);
            pass.dispatch_workgroups(dispatch.count.div_ceil(64), 1, 1);
        }
    }
}
