//! Deformed meshes' vertices, every frame, before anything draws or traces them (`deform.wgsl`): one
//! dispatch per deformed mesh, from a copy of its vertices at rest, by a wave or by its pose (morph
//! targets and skin, whose weights and joint matrices the CPU evaluates from the animation). It also
//! writes where each deformed vertex was a frame earlier, for the velocities of motion blur. On the
//! CPU it boxes each deformed mesh as the frame deforms it, which the raster passes cull it by.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::scene::animation::Animation;
use crate::scene::deform::{pose_state, Deformation, DeformedReach, Deformer, PoseClock};
use crate::scene::{Aabb, Scene, Vertex};
use crate::Result;

/// Keep in sync with `DeformJob` in `deform.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct DeformJob {
    first_vertex: u32,
    vertex_count: u32,
    rest_first: u32,
    /// 0: a wave, 1: a pose.
    kind: u32,
    direction: [f32; 3],
    amplitude: f32,
    wavenumber: f32,
    speed: f32,
    time: f32,
    previous_time: f32,
    target_count: u32,
    offsets_first: u32,
    influence_sets: u32,
    influences_first: u32,
    joint_count: u32,
    /// Where the frame's joint matrices and weights start in the state buffer, in vec4s.
    state_first: u32,
    _pad: [u32; 2],
}

/// Jobs sit 256 bytes apart in their uniform buffer: wgpu's alignment for dynamic offsets.
const JOB_STRIDE: u64 = 256;

/// One deformed mesh: its job and, for a pose, what the CPU evaluates every frame.
struct Job {
    gpu: DeformJob,
    deformer: Deformer,
    reach: DeformedReach,
}

pub struct Deform {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    jobs: Vec<Job>,
    job_buffer: wgpu::Buffer,
    state_buffer: wgpu::Buffer,
}

/// A pose's frame state in vec4s: joint matrices now and a frame before, then weights now and before.
fn state_len(joints: usize, targets: usize) -> u32 {
    (8 * joints + 2 * targets.div_ceil(4)) as u32
}

/// A storage buffer of `data`, or of one zero record where there is none.
fn storage<T: bytemuck::Pod + Default>(device: &wgpu::Device, label: &str, data: &[T], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    let one = [T::default()];
    let contents = if data.is_empty() { bytemuck::cast_slice(&one) } else { bytemuck::cast_slice(data) };
    wgpu::util::DeviceExt::create_buffer_init(
        device,
        &wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage: wgpu::BufferUsages::STORAGE | usage },
    )
}

impl Deform {
    /// The pass for `scene`'s deformers; `None` when it has none.
    pub fn new(ctx: &GpuContext, scene: &Scene, gpu_scene: &GpuScene) -> Result<Option<Self>> {
        if scene.deformers.is_empty() {
            return Ok(None);
        }
        let device = &ctx.device;
        let mut rest: Vec<Vertex> = Vec::new();
        let mut offsets: Vec<[f32; 4]> = Vec::new();
        let mut influences: Vec<[u32; 4]> = Vec::new();
        let mut state_len_total = 0u32;
        let mut jobs = Vec::with_capacity(scene.deformers.len());
        for deformer in &scene.deformers {
            // A mesh's primitives' vertices follow one another in the scene's buffer.
            let first_vertex = gpu_scene.primitive_ranges[deformer.mesh].first().map_or(0, |r| r.2);
            let rest_first = rest.len() as u32;
            for primitive in &scene.meshes[deformer.mesh].primitives {
                rest.extend_from_slice(&primitive.vertices);
            }
            let reach = deformer.reach(&rest[rest_first as usize..]);
            let mut gpu = DeformJob { first_vertex, vertex_count: rest.len() as u32 - rest_first, rest_first, ..Default::default() };
            match &deformer.deformation {
                Deformation::Wave(wave) => {
                    gpu.direction = wave.direction.to_array();
                    gpu.amplitude = wave.amplitude;
                    gpu.wavenumber = std::f32::consts::TAU / wave.wavelength;
                    gpu.speed = wave.speed;
                }
                Deformation::Pose(pose) => {
                    gpu.kind = 1;
                    gpu.target_count = pose.targets.len() as u32;
                    gpu.offsets_first = offsets.len() as u32;
                    for target in &pose.targets {
                        for o in target {
                            offsets.extend([o.position.extend(0.0), o.normal.extend(0.0), o.tangent.extend(0.0)].map(|v| v.to_array()));
                        }
                    }
                    if let Some(skin) = &pose.skin {
                        gpu.influence_sets = skin.sets as u32;
                        gpu.influences_first = influences.len() as u32;
                        gpu.joint_count = skin.joints.len() as u32;
                        for (joints, weights) in skin.joint_indices.iter().zip(&skin.weights) {
                            influences.push(*joints);
                            influences.push(weights.map(f32::to_bits));
                        }
                    }
                    gpu.state_first = state_len_total;
                    state_len_total += state_len(gpu.joint_count as usize, pose.targets.len());
                }
            }
            jobs.push(Job { gpu, deformer: deformer.clone(), reach });
        }
        let max_invocations = u64::from(ctx.limits.max_compute_workgroups_per_dimension) * 64;
        if let Some(job) = jobs.iter().find(|job| u64::from(job.gpu.vertex_count) > max_invocations) {
            return Err(crate::Error::InvalidScene(format!(
                "deformed mesh {} ({}) has {} vertices, over the {max_invocations} this GPU deforms in one dispatch; deform a smaller mesh",
                job.deformer.mesh, scene.meshes[job.deformer.mesh].name, job.gpu.vertex_count
            )));
        }
        let limit = ctx.limits.max_storage_buffer_binding_size;
        let bytes = (offsets.len() * 16).max(influences.len() * 16);
        if bytes as u64 > limit {
            return Err(crate::Error::InvalidScene(format!(
                "the morph targets or skin weights take {:.1} MiB, over this GPU's storage binding limit of {:.1} MiB; use fewer targets or a smaller mesh",
                bytes as f64 / 1048576.0,
                limit as f64 / 1048576.0
            )));
        }
        let rest_buffer = storage(device, "deformed meshes at rest", &rest, wgpu::BufferUsages::empty());
        let offset_buffer = storage(device, "morph target offsets", &offsets, wgpu::BufferUsages::empty());
        let influence_buffer = storage(device, "skin influences", &influences, wgpu::BufferUsages::empty());
        let state_buffer =
            storage(device, "pose joints and weights", &vec![[0f32; 4]; state_len_total as usize], wgpu::BufferUsages::COPY_DST);
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
                bindings::storage_read_write(3, c),
                bindings::storage_read(4, c),
                bindings::storage_read(5, c),
                bindings::storage_read(6, c),
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
                gpu_scene.previous_positions.as_entire_binding(),
                offset_buffer.as_entire_binding(),
                influence_buffer.as_entire_binding(),
                state_buffer.as_entire_binding(),
            ],
        );
        Ok(Some(Self { pipeline, bind_group, jobs, job_buffer, state_buffer }))
    }

    /// Writes the frame's time, and the time a frame before (for the velocities), for the next frame
    /// submitted; poses take their joints and weights from `animation` at those times. Returns each
    /// deformed mesh's box at `time`, in its own space.
    pub fn write_time(&mut self, queue: &wgpu::Queue, time: f32, previous_time: f32, animation: Option<&Animation>) -> Vec<(usize, Aabb)> {
        let posed = self.jobs.iter().any(|job| matches!(job.deformer.deformation, Deformation::Pose(_)));
        let clocks = posed.then(|| [time, previous_time].map(|t| PoseClock::at(t, animation)));
        // Waves' boxes hold at every time; poses' follow the clock, evaluated once for both.
        let unposed;
        let now = match &clocks {
            Some([now, _]) => now,
            None => {
                unposed = PoseClock::at(time, None);
                &unposed
            }
        };
        let bounds = self.jobs.iter().map(|job| (job.deformer.mesh, job.reach.bounds(&job.deformer, now))).collect();
        for (i, job) in self.jobs.iter_mut().enumerate() {
            job.gpu.time = time;
            job.gpu.previous_time = previous_time;
            queue.write_buffer(&self.job_buffer, i as u64 * JOB_STRIDE, bytemuck::bytes_of(&job.gpu));
            let (Deformation::Pose(pose), Some(clocks)) = (&job.deformer.deformation, &clocks) else { continue };
            let [now, before] = [&clocks[0], &clocks[1]].map(|clock| pose_state(pose, clock));
            let mut state: Vec<[f32; 4]> = Vec::with_capacity(state_len(now.joints.len(), now.weights.len()) as usize);
            for joints in [&now.joints, &before.joints] {
                state.extend(joints.iter().flat_map(|m| m.to_cols_array_2d()));
            }
            for weights in [&now.weights, &before.weights] {
                state.extend(weights.chunks(4).map(|c| std::array::from_fn(|k| c.get(k).copied().unwrap_or(0.0))));
            }
            if !state.is_empty() {
                queue.write_buffer(&self.state_buffer, u64::from(job.gpu.state_first) * 16, bytemuck::cast_slice(&state));
            }
        }
        bounds
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("deform"),
            timestamp_writes: timer.map(|t| t.compute_pass("deform")),
        });
        pass.set_pipeline(&self.pipeline);
        for (i, job) in self.jobs.iter().enumerate() {
            pass.set_bind_group(0, &self.bind_group, &[(i as u64 * JOB_STRIDE) as u32]);
            pass.dispatch_workgroups(job.gpu.vertex_count.div_ceil(64), 1, 1);
        }
    }
}
