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
use crate::scene::Aabb;
use crate::{Error, Result};

/// Most particles one system holds (about 2²⁴: as many as one row of 65535 workgroups of 256 threads,
/// which the exact method's LBVH build dispatches): their lights take 32 bytes each.
pub const MAX_PARTICLES: u32 = 65535 * 256;
/// Most fixed-point steps per unit of the splat's sums: contributions are rounded (dithered) to 1/1024 at
/// best. Crowded or bright particles get fewer ([`SplatScales`]), so no voxel's i32 sum can wrap.
pub const MAX_SPLAT_SCALE: f32 = 1024.0;
/// Most voxels one particle may splat into (32³): beyond, the splat's cost per particle is out of
/// proportion to the light it carries, and a million particles would stall the GPU.
pub const MAX_SPLAT_VOXELS: u64 = 32 * 32 * 32;
/// Most cascades of a clipmap ([`ParticleVolume::Clipmap`]).
pub const MAX_PARTICLE_CASCADES: u32 = 8;
/// Most jittered points one shading point samples the grid at (`RenderConfig::particle_samples`).
pub const MAX_PARTICLE_SAMPLES: u32 = 64;

/// How shading reads the grid; the paper's remedies for its blocks are the filters past nearest, and
/// supersampling (`RenderConfig::particle_samples`). Keep in sync with `PARTICLE_FILTER_*` in
/// `shading/types.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum ParticleFilter {
    /// The voxel the point lies in.
    Nearest = 0,
    /// The eight voxels around the point, by the hardware.
    #[default]
    Trilinear = 1,
    /// A cubic B-spline over the 64 voxels around it, as eight trilinear taps (Sigg & Hadwiger 2005):
    /// smooth across voxel faces, slightly blurred.
    Tricubic = 2,
}

impl ParticleFilter {
    pub fn name(self) -> &'static str {
        match self {
            ParticleFilter::Nearest => "nearest",
            ParticleFilter::Trilinear => "trilinear",
            ParticleFilter::Tricubic => "tricubic",
        }
    }
}

/// Threads per workgroup of the per-particle passes.
const WORKGROUP: u32 = 256;
const VOXEL_WORKGROUP: u32 = 4;

/// How a scene file asks for its particles to be rendered; each unset field, and each one a
/// command-line flag overrides, falls back to `RenderConfig`'s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ParticleRendering {
    pub method: Option<crate::pipelines::ParticleMethod>,
    pub voxel_size: Option<f32>,
    pub filter: Option<ParticleFilter>,
    pub samples: Option<u32>,
    pub cascades: Option<u32>,
    pub cascade_resolution: Option<u32>,
}

/// The particles of a scene: how many, their emitters, and how they move and shine.
#[derive(Clone, Debug, PartialEq)]
pub struct ParticleSettings {
    pub count: u32,
    pub seed: u32,
    /// Launch points (world space) with their launch speed in m/s; particle `i` uses emitter
    /// `i % emitters.len()`.
    pub emitters: Vec<(Vec3, f32)>,
    /// Seconds a particle flies before it is launched again, uniform in [min, max] per particle.
    pub lifetime: (f32, f32),
    /// Light radius (range) in metres, uniform in [min, max] per launch.
    pub radius: (f32, f32),
    /// Intensity (candela) of the brightest channel; colours are saturated hues.
    pub intensity: f32,
    /// Downward acceleration, m/s².
    pub gravity: f32,
    /// Turn about the emitter's vertical axis, radians per second of flight.
    pub swirl: f32,
    /// Launch directions lie within this angle of +Y, in degrees.
    pub cone_degrees: f32,
    /// The scene file's rendering choices for them.
    pub rendering: ParticleRendering,
}

impl Default for ParticleSettings {
    fn default() -> Self {
        Self {
            count: 0,
            seed: 1,
            emitters: Vec::new(),
            lifetime: (2.0, 4.0),
            radius: (0.5, 1.5),
            intensity: 0.2,
            gravity: 3.0,
            swirl: 1.0,
            cone_degrees: 25.0,
            rendering: ParticleRendering::default(),
        }
    }
}

/// One particle at one time: a point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleLight {
    pub position: Vec3,
    pub radius: f32,
    pub color: Vec3,
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

/// PCG hash, as `pcg` in `motion.wgsl`.
fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747796405).wrapping_add(2891336453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277803737);
    (word >> 22) ^ word
}

impl ParticleSettings {
    /// Checks what the GPU relies on; errors name the setting and the fix.
    pub fn validate(&self) -> Result<()> {
        let invalid = |m: String| Err(Error::InvalidConfig(format!("particles: {m}")));
        if self.count > MAX_PARTICLES {
            return invalid(format!("{} particles exceed the maximum of {MAX_PARTICLES}", self.count));
        }
        if self.count > 0 && self.emitters.is_empty() {
            return invalid("particles need at least one emitter".into());
        }
        if let Some((p, s)) = self.emitters.iter().find(|(p, s)| !p.is_finite() || !s.is_finite() || *s < 0.0) {
            return invalid(format!("emitter at {p} with speed {s}: positions must be finite and speeds finite and ≥ 0"));
        }
        let range = |name: &str, (min, max): (f32, f32), low: f32| {
            if min.is_finite() && max.is_finite() && min > low && min <= max {
                Ok(())
            } else {
                invalid(format!("{name} [{min}, {max}] must be finite with {low} < min ≤ max"))
            }
        };
        range("lifetime", self.lifetime, 0.0)?;
        range("radius", self.radius, 0.0)?;
        for (name, value) in [("intensity", self.intensity), ("gravity", self.gravity), ("swirl", self.swirl)] {
            if !value.is_finite() {
                return invalid(format!("{name} {value} must be finite"));
            }
        }
        if !(self.intensity >= 0.0 && (0.0..=180.0).contains(&self.cone_degrees)) {
            return invalid(format!("intensity {} must be ≥ 0 and the cone {}° within 0–180°", self.intensity, self.cone_degrees));
        }
        Ok(())
    }

    /// A uniform value in [0, 1), as `random01` in `motion.wgsl`.
    fn random01(&self, particle: u32, generation: u32, k: u32) -> f32 {
        let h = pcg(pcg(pcg(particle ^ self.seed).wrapping_add(generation)).wrapping_add(k));
        (h >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Particle `i`'s light at `time` seconds: the CPU twin of `particle_motion`.
    pub fn particle_at(&self, i: u32, time: f32) -> ParticleLight {
        let (emitter, emitter_speed) = self.emitters[i as usize % self.emitters.len()];
        let mix = |(a, b): (f32, f32), t: f32| a + (b - a) * t;
        let lifetime = mix(self.lifetime, self.random01(i, 0, 0));
        let clock = time + lifetime * self.random01(i, 0, 1);
        let generation = (clock / lifetime).floor() as u32;
        // Rounding can put the difference a hair outside the lifetime.
        let age = (clock - generation as f32 * lifetime).clamp(0.0, lifetime);
        let angle = std::f32::consts::TAU * self.random01(i, generation, 2);
        let cos_tilt = mix((1.0, self.cone_degrees.to_radians().cos()), self.random01(i, generation, 3));
        let sin_tilt = (1.0 - cos_tilt * cos_tilt).max(0.0).sqrt();
        let speed = emitter_speed * mix((0.6, 1.0), self.random01(i, generation, 4));
        let velocity = Vec3::new(angle.cos() * sin_tilt, cos_tilt, angle.sin() * sin_tilt) * speed;
        let offset = velocity * age - Vec3::new(0.0, 0.5 * self.gravity * age * age, 0.0);
        let (sin, cos) = (self.swirl * age).sin_cos();
        let offset = Vec3::new(offset.x * cos - offset.z * sin, offset.y, offset.x * sin + offset.z * cos);
        let hue = self.random01(i, generation, 6);
        ParticleLight {
            position: emitter + offset,
            radius: mix(self.radius, self.random01(i, generation, 5)),
            color: hue_color(hue) * self.intensity,
        }
    }

    /// Bounds every particle light stays within, at any time: the emitters' bounds grown by the
    /// furthest flight (launch speed and gravity over the longest lifetime) and the largest radius.
    pub fn bounds(&self) -> Aabb {
        let speed = self.emitters.iter().map(|(_, s)| *s).fold(0.0f32, f32::max);
        let t = self.lifetime.1;
        let reach = Vec3::splat(speed * t + 0.5 * self.gravity.abs() * t * t + self.radius.1);
        let (low, high) = self.emitters.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), (p, _)| (l.min(*p), h.max(*p)));
        Aabb::new(low - reach, high + reach)
    }

    fn gpu_params(&self, time: f32, row_threads: u32) -> GpuParticleParams {
        GpuParticleParams {
            count: self.count,
            emitter_count: self.emitters.len().max(1) as u32,
            seed: self.seed,
            row_threads,
            time,
            gravity: self.gravity,
            swirl: self.swirl,
            cos_cone: self.cone_degrees.to_radians().cos(),
            lifetime_min: self.lifetime.0,
            lifetime_max: self.lifetime.1,
            radius_min: self.radius.0,
            radius_max: self.radius.1,
            intensity: self.intensity,
            _pad: [0.0; 3],
        }
    }
}

/// As `hue_color` in `motion.wgsl`.
fn hue_color(hue: f32) -> Vec3 {
    let channel = |n: f32| {
        let k = (n + hue * 6.0) % 6.0;
        1.0 - k.min(4.0 - k).clamp(0.0, 1.0)
    };
    Vec3::new(channel(5.0), channel(3.0), channel(1.0))
}

/// One voxel grid particles are splatted into (a cascade): voxel (i, j, k) is centred on
/// `origin + (ijk + 0.5) × voxel_size`, one voxel per `voxel_size` of world (1 m by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParticleGrid {
    pub origin: Vec3,
    pub voxel_size: f32,
    pub dims: UVec3,
}

fn check_voxel_size(voxel_size: f32) -> Result<()> {
    if voxel_size.is_finite() && voxel_size > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidConfig(format!("particle voxel size {voxel_size} must be a finite length > 0, in metres")))
    }
}

impl ParticleGrid {
    /// The grid of `voxel_size` covering `bounds`; errors when the size is not a positive finite
    /// length or the grid would exceed `max_dimension` voxels along an axis (the device's 3D texture
    /// limit).
    pub fn covering(bounds: &Aabb, voxel_size: f32, max_dimension: u32) -> Result<Self> {
        check_voxel_size(voxel_size)?;
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

/// Fewest voxels per axis of a clipmap cascade: a point that the finer cascade's edge hands over lies
/// deep enough in the coarser one (past its own blend band) that the switch leaves no seam.
pub const MIN_CASCADE_RESOLUTION: u32 = 24;

/// Checks a clipmap's cascade count (0, one grid over the scene, allowed) and resolution.
pub fn check_clipmap(resolution: u32, cascades: u32) -> Result<()> {
    if cascades > MAX_PARTICLE_CASCADES {
        return Err(Error::InvalidConfig(format!(
            "{cascades} particle cascades: give 1 to {MAX_PARTICLE_CASCADES}, or 0 for one grid over the scene"
        )));
    }
    if resolution < MIN_CASCADE_RESOLUTION || !resolution.is_multiple_of(2) {
        return Err(Error::InvalidConfig(format!(
            "particle cascade resolution {resolution}: give an even number of voxels per axis, at least {MIN_CASCADE_RESOLUTION}"
        )));
    }
    Ok(())
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
        check_voxel_size(voxel_size)?;
        if cascades == 0 {
            return Err(Error::InvalidConfig("a clipmap needs at least 1 particle cascade".into()));
        }
        check_clipmap(resolution, cascades)?;
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
            ],
        );
        let shader = ShaderDesc::new("particles/lights.wgsl");
        let boxes = bindings::compute_pipeline(device, "particle_boxes", &shader, &[&layout])?;
        let lights = bindings::compute_pipeline(device, "particle_lights", &shader, &[&layout])?;
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
        ctx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&self.settings.gpu_params(time, x * WORKGROUP)));
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
