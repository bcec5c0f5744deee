//! Dynamic particle lights through 3D textures, after "GPU-based dynamic point light particles
//! rendering using 3D textures" (Korea Computer Graphics Society, 2020). Every frame a compute pass
//! places each particle (`motion.wgsl`, a function of time alone: frames can be rendered again and give
//! the same particles), a second one splats every particle into the voxels its radius reaches — its
//! colour times the point-light falloff, and its direction weighted alike — and resolves the sums into
//! two filterable 3D textures (`splat.wgsl`), which shading samples at the surface.
//!
//! The exact alternative (`ParticleMethod::Bvh`) makes each particle a point light in the lights'
//! acceleration structure instead (`lights.wgsl`: its record and its box, for a group rebuilt on the
//! GPU every frame), shaded like any light.
//!
//! The grid is one volume fixed over the scene (the paper's), or a clipmap: cascades of the same
//! voxel count centred on the camera, each with voxels twice the size of the one before, so a large
//! world needs no world-sized texture ([`ParticleVolume`]). The cascades are stacked along z in the
//! same two textures. Everything is splatted again every frame, so a moving camera needs no
//! toroidal scrolling: each frame's cascades are simply placed around the eye, snapped to their
//! voxels so lighting does not swim.
//!
//! [`ParticleSettings`] describes the particles (the CPU scene's part) and computes any particle's
//! light on the CPU ([`ParticleSettings::particle_at`], the GPU's twin); [`ParticleGrid`] is one
//! cascade's voxel grid, [`ParticleVolume`] where the cascades lie; [`ParticleSystem`] owns the GPU
//! buffers, the textures and the passes.

use glam::{UVec3, Vec3};

use crate::accel::structure::DynamicTargets;
use crate::gpu::{bindings, readback, shaders::ShaderDesc, GpuContext, GpuTimer};
use crate::scene::{Aabb, ParticleSettings};
use crate::settings::particles::{check_cascade_resolution, check_cascades, check_voxel_size};
use crate::settings::{Spelling, MAX_PARTICLE_CASCADES};
use crate::{Error, Result};

/// Most fixed-point steps per unit of the splat's sums: contributions are rounded (dithered) to 1/1024 at
/// best. Crowded or bright particles get fewer ([`SplatScales`]), so no voxel's i32 sum can wrap.
pub const MAX_SPLAT_SCALE: f32 = 1024.0;
/// Most voxels one particle may splat into (32³): beyond, the splat's cost per particle is out of
/// proportion to the light it carries, and a million particles would stall the GPU.
pub const MAX_SPLAT_VOXELS: u64 = 32 * 32 * 32;
/// Threads per workgroup of the per-particle passes.
const WORKGROUP: u32 = 256;
const VOXEL_WORKGROUP: u32 = 4;

/// The motion pass's parameters for `settings` at `time`.
fn gpu_params(settings: &ParticleSettings, time: f32, row_threads: u32) -> GpuParticleParams {
    GpuParticleParams {
        count: settings.count,
        emitter_count: settings.emitters.len().max(1) as u32,
        seed: settings.seed,
        row_threads,
        time,
        gravity: settings.gravity,
        swirl: settings.swirl,
        cos_cone: settings.cone_degrees.to_radians().cos(),
        lifetime_min: settings.lifetime.0,
        lifetime_max: settings.lifetime.1,
        radius_min: settings.radius.0,
        radius_max: settings.radius.1,
        intensity: settings.intensity,
        _pad: [0.0; 3],
    }
}

/// Keep in sync with `ParticleParams` in `particles/types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuParticleParams {
    count: u32,
    emitter_count: u32,
    seed: u32,
    row_threads: u32,
    time: f32,
    gravity: f32,
    swirl: f32,
    cos_cone: f32,
    lifetime_min: f32,
    lifetime_max: f32,
    radius_min: f32,
    radius_max: f32,
    intensity: f32,
    _pad: [f32; 3],
}

/// Keep in sync with `ParticleLight` in `particles/types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuParticleLight {
    pub position: [f32; 3],
    pub radius: f32,
    pub color: [f32; 3],
    pub _pad: f32,
}

/// Keep in sync with `ParticleVolume` in `particles/types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuParticleVolume {
    dims: [u32; 3],
    cascade_count: u32,
    fixed_scale: f32,
    texture_scale: f32,
    _pad: [f32; 2],
    /// Per cascade: corner (xyz) and voxel edge (w).
    cascades: [[f32; 4]; MAX_PARTICLE_CASCADES as usize],
}

/// One voxel grid particles are splatted into (a cascade): voxel (i, j, k) is centred on
/// `origin + (ijk + 0.5) × voxel_size`, one voxel per `voxel_size` of world (1 m by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleGrid {
    pub origin: Vec3,
    pub voxel_size: f32,
    pub dims: UVec3,
}

impl ParticleGrid {
    /// The grid of `voxel_size` covering `bounds`; errors when the size is not a positive finite
    /// length or the grid would exceed `max_dimension` voxels along an axis (the device's 3D texture
    /// limit).
    pub fn covering(bounds: &Aabb, voxel_size: f32, max_dimension: u32) -> Result<Self> {
        check_voxel_size(voxel_size, Spelling::Flag)?;
        if !bounds.is_valid() {
            return Err(Error::InvalidConfig("the particle grid needs finite bounds to cover".into()));
        }
        let extent = (bounds.max - bounds.min) / voxel_size;
        let dims = extent.ceil().max(Vec3::ONE);
        if dims.max_element() > max_dimension as f32 {
            return Err(Error::InvalidConfig(format!(
                "a particle grid of {voxel_size} m voxels over {:.1} × {:.1} × {:.1} m needs {} × {} × {} voxels, over this GPU's 3D texture limit of {max_dimension} per axis; use larger voxels, or camera-centred cascades (render's --particle-cascades, particle-error's --cascades, or `cascades` in a scene file's [particles])",
                bounds.max.x - bounds.min.x,
                bounds.max.y - bounds.min.y,
                bounds.max.z - bounds.min.z,
                dims.x,
                dims.y,
                dims.z
            )));
        }
        Ok(Self { origin: bounds.min, voxel_size, dims: dims.as_uvec3() })
    }

    pub fn voxel_count(&self) -> u64 {
        u64::from(self.dims.x) * u64::from(self.dims.y) * u64::from(self.dims.z)
    }

    /// Index of voxel (x, y, z), x fastest.
    pub fn index(&self, voxel: UVec3) -> usize {
        ((voxel.z * self.dims.y + voxel.y) * self.dims.x + voxel.x) as usize
    }

    pub fn centre(&self, voxel: UVec3) -> Vec3 {
        self.origin + (voxel.as_vec3() + 0.5) * self.voxel_size
    }

    /// The splat's weight at `distance` from a particle of `radius`, as `splat_falloff` in `splat.wgsl`.
    pub fn falloff(&self, distance: f32, radius: f32) -> f32 {
        let ratio_sq = distance * distance / (radius * radius);
        let window = (1.0 - ratio_sq * ratio_sq).clamp(0.0, 1.0);
        let near = 0.5 * self.voxel_size;
        window * window / (distance * distance).max(near * near)
    }
}

/// Where the particle grid lies: its cascades, all of the same voxel count, stacked along z in the
/// textures (cascade k's voxels follow cascade k − 1's in the sums, x fastest).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParticleVolume {
    /// One grid fixed over the scene, as in the paper: its memory grows with the world.
    World(ParticleGrid),
    /// A clipmap: `cascades` grids of `resolution`³ voxels centred on the camera, cascade k's voxels
    /// `voxel_size` × 2ᵏ: fine near the eye, coarse far away, the same memory whatever the world.
    Clipmap { voxel_size: f32, resolution: u32, cascades: u32 },
}

impl ParticleVolume {
    /// A clipmap, checked against the device's 3D texture limit (`max_dimension`): its cascades stack
    /// `resolution × cascades` voxels along z.
    pub fn clipmap(voxel_size: f32, resolution: u32, cascades: u32, max_dimension: u32) -> Result<Self> {
        check_voxel_size(voxel_size, Spelling::Flag)?;
        if cascades == 0 {
            return Err(Error::InvalidConfig("a clipmap needs at least 1 particle cascade".into()));
        }
        check_cascades(cascades, Spelling::Flag)?;
        check_cascade_resolution(resolution, Spelling::Flag)?;
        if u64::from(resolution) * u64::from(cascades) > u64::from(max_dimension) {
            return Err(Error::InvalidConfig(format!(
                "{cascades} particle cascades of {resolution}³ voxels stack {} voxels along z, over this GPU's 3D texture limit of {max_dimension}; use fewer cascades or a lower resolution",
                u64::from(resolution) * u64::from(cascades)
            )));
        }
        Ok(Self::Clipmap { voxel_size, resolution, cascades })
    }

    /// Voxels per axis of each cascade.
    pub fn dims(&self) -> UVec3 {
        match self {
            Self::World(grid) => grid.dims,
            Self::Clipmap { resolution, .. } => UVec3::splat(*resolution),
        }
    }

    pub fn cascade_count(&self) -> u32 {
        match self {
            Self::World(_) => 1,
            Self::Clipmap { cascades, .. } => *cascades,
        }
    }

    pub fn finest_voxel_size(&self) -> f32 {
        match self {
            Self::World(grid) => grid.voxel_size,
            Self::Clipmap { voxel_size, .. } => *voxel_size,
        }
    }

    /// Voxels of all cascades.
    pub fn voxel_count(&self) -> u64 {
        let dims = self.dims();
        u64::from(dims.x) * u64::from(dims.y) * u64::from(dims.z) * u64::from(self.cascade_count())
    }

    /// The cascades for a camera at `eye`, finest first. A clipmap's are centred on the eye with
    /// their corners on multiples of their voxel, so the voxels stay put in the world as it moves.
    pub fn cascades(&self, eye: Vec3) -> Vec<ParticleGrid> {
        match *self {
            Self::World(grid) => vec![grid],
            Self::Clipmap { voxel_size, resolution, cascades } => (0..cascades)
                .map(|k| {
                    let voxel = voxel_size * (1u32 << k) as f32;
                    let corner = ((eye / voxel).floor() - Vec3::splat((resolution / 2) as f32)) * voxel;
                    ParticleGrid { origin: corner, voxel_size: voxel, dims: UVec3::splat(resolution) }
                })
                .collect(),
        }
    }

    /// The cascades for a camera at `eye` as the GPU reads them: corner (xyz) and voxel edge (w),
    /// finest first, unused slots zero.
    pub fn gpu_cascades(&self, eye: Vec3) -> [[f32; 4]; MAX_PARTICLE_CASCADES as usize] {
        let mut cascades = [[0.0; 4]; MAX_PARTICLE_CASCADES as usize];
        for (slot, grid) in cascades.iter_mut().zip(self.cascades(eye)) {
            *slot = grid.origin.extend(grid.voxel_size).to_array();
        }
        cascades
    }

    fn gpu(&self, eye: Vec3, scales: SplatScales) -> GpuParticleVolume {
        GpuParticleVolume {
            dims: self.dims().to_array(),
            cascade_count: self.cascade_count(),
            fixed_scale: scales.fixed,
            texture_scale: scales.texture,
            _pad: [0.0; 2],
            cascades: self.gpu_cascades(eye),
        }
    }
}

/// How the splat stores its sums: i32 steps per unit (`fixed`), and the factor the RGBA16F textures
/// hold them at (`texture`, which shading divides out). Both are powers of two chosen from the
/// brightest any voxel can get — every particle at full intensity within half a voxel of its centre
/// — so no sum wraps and no texel overflows 65504, however crowded the emitters; the price is
/// coarser steps (2³⁰ / that brightest) for very many or very bright particles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplatScales {
    pub fixed: f32,
    pub texture: f32,
}

impl SplatScales {
    pub fn new(settings: &ParticleSettings, finest_voxel_size: f32) -> Self {
        let near = 0.5 * f64::from(finest_voxel_size);
        let brightest = (f64::from(settings.count.max(1)) * f64::from(settings.intensity) / (near * near)).max(1e-30);
        // Powers of two: scaling and unscaling are exact. Half the i32 range is left to the rounding.
        let power = |limit: f64, most: f64| (limit / brightest).log2().floor().clamp(-100.0, most.log2()).exp2() as f32;
        Self { fixed: power(2f64.powi(30), f64::from(MAX_SPLAT_SCALE)), texture: power(2f64.powi(15), 1.0) }
    }
}

/// The GPU side: particle lights, what they are turned into (the grid's textures, or lights in an
/// acceleration structure), and the passes.
pub struct ParticleSystem {
    settings: ParticleSettings,
    params: wgpu::Buffer,
    particles: wgpu::Buffer,
    motion: (wgpu::ComputePipeline, wgpu::BindGroup),
    output: Output,
}

enum Output {
    // Boxed: its handles outweigh the other variant's several times.
    Grid(Box<GridSplat>),
    /// Boxes and records for the lights' dynamic group (`particles/lights.wgsl`).
    Lights(LightOutput),
}

/// The two passes around the dynamic group's build: `particle_boxes` before it, `particle_lights`
/// (the records, in leaf order) after it.
struct LightOutput {
    boxes: wgpu::ComputePipeline,
    lights: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

/// The splat's sums, the two textures and its passes.
struct GridSplat {
    volume: ParticleVolume,
    scales: SplatScales,
    /// `GpuParticleVolume`: the cascades move with the camera.
    volume_uniform: wgpu::Buffer,
    /// Colour sums (rgb) and direction sums (xyz, unnormalised), RGBA16F, sampled by shading.
    color_texture: wgpu::Texture,
    direction_texture: wgpu::Texture,
    sums: wgpu::Buffer,
    splat: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
}

impl ParticleSystem {
    /// Particles splatted into `volume`'s cascades every frame. Errors when a particle would reach
    /// more than [`MAX_SPLAT_VOXELS`] voxels of the finest cascade.
    pub fn new(ctx: &GpuContext, settings: &ParticleSettings, volume: ParticleVolume) -> Result<Self> {
        let voxel = volume.finest_voxel_size();
        let reach = ((2.0 * f64::from(settings.radius.1) / f64::from(voxel)).floor() + 1.0).powi(3);
        if reach > MAX_SPLAT_VOXELS as f64 {
            return Err(Error::InvalidConfig(format!(
                "particles reaching {} m splat into up to {reach:.0} voxels of {voxel} m each, over the {MAX_SPLAT_VOXELS} a particle may reach; use larger voxels (--particle-voxel-size) or a smaller particle radius",
                settings.radius.1
            )));
        }
        let (params, particles, motion) = Self::motion(ctx, settings)?;
        let splat = GridSplat::new(ctx, volume, SplatScales::new(settings, voxel), &params, &particles)?;
        ctx.check_errors()?;
        Ok(Self { settings: settings.clone(), params, particles, motion, output: Output::Grid(Box::new(splat)) })
    }

    /// Particles written every frame as point lights into a light structure's dynamic group: their
    /// boxes by [`record`](Self::record), before the structure's build, and their records in leaf
    /// order by [`record_lights`](Self::record_lights), after it.
    pub fn with_lights(ctx: &GpuContext, settings: &ParticleSettings, targets: DynamicTargets) -> Result<Self> {
        let (params, particles, motion) = Self::motion(ctx, settings)?;
        let device = &ctx.device;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = bindings::layout(
            device,
            "particle lights",
            &[
                bindings::uniform(0, compute),
                bindings::storage_read(1, compute),
                bindings::storage_read_write(2, compute),
                bindings::storage_read_write(3, compute),
                bindings::storage_read(4, compute),
                bindings::uniform(5, compute),
                bindings::storage_read_write(6, compute),
            ],
        );
        let shader = ShaderDesc::new("particles/lights.wgsl");
        let constants = [("LIGHT_TREE", if targets.light_tree { 1.0 } else { 0.0 })];
        let boxes = bindings::compute_pipeline_with_constants(device, "particle_boxes", &shader, &[&layout], &constants)?;
        let lights = bindings::compute_pipeline_with_constants(device, "particle_lights", &shader, &[&layout], &constants)?;
        use wgpu::util::DeviceExt;
        let group = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("particle light group"),
            contents: bytemuck::cast_slice(&[targets.first_item, targets.first_primitive, 0, 0]),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind_group = bindings::bind_group(
            device,
            "particle lights",
            &layout,
            vec![
                params.as_entire_binding(),
                particles.as_entire_binding(),
                targets.items.as_entire_binding(),
                targets.boxes.as_entire_binding(),
                targets.primitives.as_entire_binding(),
                group.as_entire_binding(),
                targets.emitters.as_entire_binding(),
            ],
        );
        ctx.check_errors()?;
        let output = Output::Lights(LightOutput { boxes, lights, bind_group });
        Ok(Self { settings: settings.clone(), params, particles, motion, output })
    }

    /// The parameters, the particle lights and the motion pass, shared by both outputs.
    fn motion(
        ctx: &GpuContext,
        settings: &ParticleSettings,
    ) -> Result<(wgpu::Buffer, wgpu::Buffer, (wgpu::ComputePipeline, wgpu::BindGroup))> {
        settings.validate()?;
        let device = &ctx.device;
        let particle_bytes = u64::from(settings.count.max(1)) * std::mem::size_of::<GpuParticleLight>() as u64;
        check_binding("particle lights", particle_bytes, ctx)?;
        use wgpu::util::DeviceExt;
        use wgpu::BufferUsages as U;
        let buffer = |label: &str, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let params = buffer("particle params", std::mem::size_of::<GpuParticleParams>() as u64, U::UNIFORM | U::COPY_DST);
        let emitters: Vec<[f32; 4]> = settings.emitters.iter().map(|(p, s)| p.extend(*s).to_array()).collect();
        let emitters = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("particle emitters"),
            contents: bytemuck::cast_slice(if emitters.is_empty() { &[[0.0f32; 4]] } else { &emitters[..] }),
            usage: U::STORAGE,
        });
        let particles = buffer("particle lights", particle_bytes, U::STORAGE | U::COPY_SRC);
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = bindings::layout(
            device,
            "particle motion",
            &[bindings::uniform(0, compute), bindings::storage_read(1, compute), bindings::storage_read_write(2, compute)],
        );
        let pipeline = bindings::compute_pipeline(device, "particle_motion", &ShaderDesc::new("particles/motion.wgsl"), &[&layout])?;
        let bind_group = bindings::bind_group(
            device,
            "particle motion",
            &layout,
            vec![params.as_entire_binding(), emitters.as_entire_binding(), particles.as_entire_binding()],
        );
        Ok((params, particles, (pipeline, bind_group)))
    }

    /// Where the particles are splatted, with the method that has a grid.
    pub fn volume(&self) -> Option<&ParticleVolume> {
        match &self.output {
            Output::Grid(splat) => Some(&splat.volume),
            Output::Lights(..) => None,
        }
    }

    /// How the splat scales its sums, with the method that has a grid.
    pub fn scales(&self) -> Option<SplatScales> {
        match &self.output {
            Output::Grid(splat) => Some(splat.scales),
            Output::Lights(..) => None,
        }
    }

    /// The grid's colour and direction textures, with the method that has them.
    pub fn grid_textures(&self) -> Option<[&wgpu::Texture; 2]> {
        match &self.output {
            Output::Grid(splat) => Some([&splat.color_texture, &splat.direction_texture]),
            Output::Lights(..) => None,
        }
    }

    /// Workgroups of the per-particle passes, as (x, y): rows of at most 65535.
    fn dispatch(&self) -> (u32, u32) {
        let groups = self.settings.count.div_ceil(WORKGROUP).max(1);
        let x = groups.min(65535);
        (x, groups.div_ceil(x))
    }

    /// Records the particles' motion to `time`, timed as `particle_motion`, and what they become:
    /// the splat into the textures around a camera at `eye` (`particle_splat`), or the boxes of the
    /// lights' dynamic group (within `particle_motion`).
    pub fn record(&self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, time: f32, eye: Vec3) {
        let (x, y) = self.dispatch();
        ctx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&gpu_params(&self.settings, time, x * WORKGROUP)));
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("particle_motion"),
                timestamp_writes: timer.as_deref_mut().map(|t| t.compute_pass("particle_motion")),
            });
            if self.settings.count > 0 {
                pass.set_pipeline(&self.motion.0);
                pass.set_bind_group(0, &self.motion.1, &[]);
                pass.dispatch_workgroups(x, y, 1);
                if let Output::Lights(output) = &self.output {
                    pass.set_pipeline(&output.boxes);
                    pass.set_bind_group(0, &output.bind_group, &[]);
                    pass.dispatch_workgroups(x, y, 1);
                }
            }
        }
        if let Output::Grid(splat) = &self.output {
            ctx.queue.write_buffer(&splat.volume_uniform, 0, bytemuck::bytes_of(&splat.volume.gpu(eye, splat.scales)));
            splat.record(encoder, timer, self.settings.count > 0, (x, y));
        }
    }

    /// With the method that makes them lights, records their light records in the order of the
    /// dynamic group's leaves, timed as `particle_lights`: after the light structure's build.
    pub fn record_lights(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) {
        let Output::Lights(output) = &self.output else { return };
        if self.settings.count == 0 {
            return;
        }
        let (x, y) = self.dispatch();
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("particle_lights"),
            timestamp_writes: timer.map(|t| t.compute_pass("particle_lights")),
        });
        pass.set_pipeline(&output.lights);
        pass.set_bind_group(0, &output.bind_group, &[]);
        pass.dispatch_workgroups(x, y, 1);
    }

    /// The particle lights of the last recorded frame (for tests and the exact method's oracle).
    pub fn read_particles(&self, ctx: &GpuContext) -> Result<Vec<GpuParticleLight>> {
        readback::read_buffer(ctx, &self.particles)
    }

    /// The splat's sums per voxel, as floats: colour rgb, direction xyz (none without a grid), the
    /// cascades one after the other.
    pub fn read_sums(&self, ctx: &GpuContext) -> Result<Vec<[f32; 6]>> {
        let Output::Grid(splat) = &self.output else { return Ok(Vec::new()) };
        let raw: Vec<[i32; 6]> = readback::read_buffer(ctx, &splat.sums)?;
        Ok(raw.into_iter().map(|v| v.map(|x| x as f32 / splat.scales.fixed)).collect())
    }
}

fn check_binding(what: &str, bytes: u64, ctx: &GpuContext) -> Result<()> {
    ctx.check_storage_binding(what, bytes).map_err(|m| Error::InvalidConfig(format!("{m}; use fewer particles or larger voxels")))
}

impl GridSplat {
    fn new(ctx: &GpuContext, volume: ParticleVolume, scales: SplatScales, params: &wgpu::Buffer, particles: &wgpu::Buffer) -> Result<Self> {
        let device = &ctx.device;
        let sum_bytes = volume.voxel_count() * 6 * 4;
        check_binding("particle grid's sums", sum_bytes, ctx)?;
        use wgpu::BufferUsages as U;
        let sums = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("particle splat sums"),
            size: sum_bytes,
            usage: U::STORAGE | U::COPY_DST | U::COPY_SRC,
            mapped_at_creation: false,
        });
        let volume_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("particle volume"),
            size: std::mem::size_of::<GpuParticleVolume>() as u64,
            usage: U::UNIFORM | U::COPY_DST,
            mapped_at_creation: false,
        });
        let dims = volume.dims();
        let texture = |label: &str| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width: dims.x, height: dims.y, depth_or_array_layers: dims.z * volume.cascade_count() },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D3,
                format: wgpu::TextureFormat::Rgba16Float,
                usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        };
        let color_texture = texture("particle colour grid");
        let direction_texture = texture("particle direction grid");
        let compute = wgpu::ShaderStages::COMPUTE;
        let storage_3d = |binding| bindings::storage_texture_3d_write(binding, compute, wgpu::TextureFormat::Rgba16Float);
        let layout = bindings::layout(
            device,
            "particle splat",
            &[
                bindings::uniform(0, compute),
                bindings::uniform(1, compute),
                bindings::storage_read(2, compute),
                bindings::storage_read_write(3, compute),
                storage_3d(4),
                storage_3d(5),
            ],
        );
        let shader = ShaderDesc::new("particles/splat.wgsl");
        let splat = bindings::compute_pipeline(device, "particle_splat", &shader, &[&layout])?;
        let resolve = bindings::compute_pipeline(device, "particle_resolve", &shader, &[&layout])?;
        let color_view = color_texture.create_view(&Default::default());
        let direction_view = direction_texture.create_view(&Default::default());
        let bind_group = bindings::bind_group(
            device,
            "particle splat",
            &layout,
            vec![
                params.as_entire_binding(),
                volume_uniform.as_entire_binding(),
                particles.as_entire_binding(),
                sums.as_entire_binding(),
                wgpu::BindingResource::TextureView(&color_view),
                wgpu::BindingResource::TextureView(&direction_view),
            ],
        );
        Ok(Self { volume, scales, volume_uniform, color_texture, direction_texture, sums, splat, resolve, bind_group })
    }

    /// Clears the sums, splats every particle into every cascade (one dispatch row per cascade) and
    /// resolves the textures, timed as `particle_splat`.
    fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, any: bool, (x, y): (u32, u32)) {
        encoder.clear_buffer(&self.sums, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("particle_splat"),
            timestamp_writes: timer.map(|t| t.compute_pass("particle_splat")),
        });
        pass.set_bind_group(0, &self.bind_group, &[]);
        let cascades = self.volume.cascade_count();
        if any {
            pass.set_pipeline(&self.splat);
            pass.dispatch_workgroups(x, y, cascades);
        }
        pass.set_pipeline(&self.resolve);
        let voxels = (self.volume.dims() * UVec3::new(1, 1, cascades)).map(|d| d.div_ceil(VOXEL_WORKGROUP));
        pass.dispatch_workgroups(voxels.x, voxels.y, voxels.z);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each cascade holds the eye near its centre, its corner on a multiple of its voxel, and its
    /// voxels twice the size of the finer one's; moving the eye within a voxel moves nothing.
    #[test]
    fn cascades_centre_on_the_eye_snapped_to_their_voxels() {
        let volume = ParticleVolume::clipmap(0.25, 24, 4, 2048).unwrap();
        for eye in [Vec3::ZERO, Vec3::new(3.7, -120.2, 0.01), Vec3::new(-1e4, 5e3, 2.5e3)] {
            let cascades = volume.cascades(eye);
            assert_eq!(cascades.len(), 4);
            for (k, grid) in cascades.iter().enumerate() {
                assert_eq!(grid.voxel_size, 0.25 * (1 << k) as f32);
                assert_eq!(grid.dims, UVec3::splat(24));
                let steps = grid.origin / grid.voxel_size;
                assert!((steps - steps.round()).abs().max_element() < 1e-3, "cascade {k} corner {} is off its voxels", grid.origin);
                let offset = (eye - grid.origin) / grid.voxel_size;
                assert!(offset.min_element() >= 11.99 && offset.max_element() <= 13.01, "eye {eye} at {offset} voxels into cascade {k}");
            }
            let nudged = volume.cascades(eye.floor() + Vec3::splat(0.01));
            let moved = volume.cascades(eye.floor() + Vec3::splat(0.2));
            assert_eq!(nudged, moved, "a move within the finest voxel moved a cascade");
        }
    }

    #[test]
    fn splat_scales_shrink_with_crowds_and_fine_voxels() {
        let settings = |count, intensity| ParticleSettings { count, intensity, emitters: vec![(Vec3::ZERO, 1.0)], ..Default::default() };
        assert_eq!(SplatScales::new(&settings(1000, 0.2), 1.0), SplatScales { fixed: MAX_SPLAT_SCALE, texture: 1.0 });
        for (count, intensity, voxel) in [(1 << 20, 0.2, 0.5), (1 << 24, 10.0, 0.1), (1, 1e6, 0.01)] {
            let scales = SplatScales::new(&settings(count, intensity), voxel);
            let brightest = f64::from(count) * f64::from(intensity) / (0.5 * f64::from(voxel)).powi(2);
            assert!(brightest * f64::from(scales.fixed) <= 2f64.powi(30), "{count} × {intensity} at {voxel} m: {scales:?}");
            assert!(brightest * f64::from(scales.texture) <= 32768.0, "{count} × {intensity} at {voxel} m: {scales:?}");
            assert!(
                brightest * f64::from(scales.fixed) > 2f64.powi(28) || scales.fixed == MAX_SPLAT_SCALE,
                "needlessly coarse: {scales:?}"
            );
        }
    }
}
