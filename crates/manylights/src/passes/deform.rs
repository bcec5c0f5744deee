//! Deformed meshes' vertices, every frame, before anything draws or traces them (`deform.wgsl`): one
//! dispatch per deformed mesh, from a copy of its vertices at rest.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::scene::{deform::Deformer, Scene, Vertex};
use crate::Result;

/// Keep in sync with `DeformJob` in `deform.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct DeformJob {
    first_vertex: u32,
    vertex_count: u32,
    rest_first: u32,
    _pad0: u32,
    direction: [f32; 3],
    amplitude: f32,
    wavenumber: f32,
    speed: f32,
    time: f32,
    _pad1: f32,
}

/// Jobs sit 256 bytes apart in their uniform buffer: wgpu's alignment for dynamic offsets.
const JOB_STRIDE: u64 = 256;

pub struct Deform {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    jobs: Vec<DeformJob>,
    job_buffer: wgpu::Buffer,
}

impl Deform {
    /// The pass for `scene`'s deformers; `None` when it has none.
    pub fn new(ctx: &GpuContext, scene: &Scene, gpu_scene: &GpuScene) -> Result<Option<Self>> {
        if scene.deformers.is_empty() {
            return Ok(None);
        }
        let device = &ctx.device;
        let mut rest: Vec<Vertex> = Vec::new();
        let jobs: Vec<DeformJob> = scene
            .deformers
            .iter()
            .map(|&Deformer { mesh, wave }| {
                // A mesh's primitives' vertices follow one another in the scene's buffer.
                let first_vertex = gpu_scene.primitive_ranges[mesh].first().map_or(0, |r| r.2);
                let rest_first = rest.len() as u32;
                for primitive in &scene.meshes[mesh].primitives {
                    rest.extend_from_slice(&primitive.vertices);
                }
                DeformJob {
                    first_vertex,
                    vertex_count: rest.len() as u32 - rest_first,
                    rest_first,
                    _pad0: 0,
                    direction: wave.direction.to_array(),
                    amplitude: wave.amplitude,
                    wavenumber: std::f32::consts::TAU / wave.wavelength,
                    speed: wave.speed,
                    time: 0.0,
                    _pad1: 0.0,
                }
            })
            .collect();
        let max_invocations = u64::from(ctx.limits.max_compute_workgroups_per_dimension) * 64;
        if let Some(job) = jobs.iter().zip(&scene.deformers).find(|(job, _)| u64::from(job.vertex_count) > max_invocations) {
            return Err(crate::Error::InvalidScene(format!(
                "deformed mesh {} ({}) has {} vertices, over the {max_invocations} this GPU deforms in one dispatch; deform a smaller mesh",
                job.1.mesh, scene.meshes[job.1.mesh].name, job.0.vertex_count
            )));
        }
        let rest_buffer = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("deformed meshes at rest"),
                contents: bytemuck::cast_slice(&rest),
                usage: wgpu::BufferUsages::STORAGE,
            },
        );
        let job_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("deform jobs"),
            size: JOB_STRIDE * jobs.len() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let c = wgpu::ShaderStages::COMPUTE;
        // Keep in sync with `deform.wgsl`.
        let layout = bindings::layout(
            device,
            "deform",
            &[
                bindings::uniform_dynamic(0, c, std::mem::size_of::<DeformJob>() as u64),
                bindings::storage_read(1, c),
                bindings::storage_read_write(2, c),
            ],
        );
        let pipeline = bindings::compute_pipeline(device, "deform", &ShaderDesc::new("passes/deform.wgsl"), &[&layout])?;
        let bind_group = bindings::bind_group(
            device,
            "deform",
            &layout,
            vec![
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &job_buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(std::mem::size_of::<DeformJob>() as u64),
                }),
                rest_buffer.as_entire_binding(),
                gpu_scene.vertex_buffer.as_entire_binding(),
            ],
        );
        Ok(Some(Self { pipeline, bind_group, jobs, job_buffer }))
    }

    /// Writes the frame's time for the next frame submitted.
    pub fn write_time(&mut self, queue: &wgpu::Queue, time: f32) {
        for (i, job) in self.jobs.iter_mut().enumerate() {
            job.time = time;
            queue.write_buffer(&self.job_buffer, i as u64 * JOB_STRIDE, bytemuck::bytes_of(job));
        }
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("deform"),
            timestamp_writes: timer.map(|t| t.compute_pass("deform")),
        });
        pass.set_pipeline(&self.pipeline);
        for (i, job) in self.jobs.iter().enumerate() {
            pass.set_bind_group(0, &self.bind_group, &[(i as u64 * JOB_STRIDE) as u32]);
            pass.dispatch_workgroups(job.vertex_count.div_ceil(64), 1, 1);
        }
    }
}
