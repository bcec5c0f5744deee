//! Frame graphs: each pipeline orders the passes of one frame, read top to bottom in its own file:
//! `visbuffer.rs` (raster ids, shade in compute), `deferred.rs` (G-buffer, light in compute) and
//! `forward.rs` (depth prepass, shade in fragments).
//! Both call the same shading core; enumeration methods plug in through `LightMethod` and
//! `DecalMethod`.

pub mod deferred;
pub mod forward;
pub mod visbuffer;

pub use deferred::DeferredPipeline;
pub use forward::ForwardPipeline;
pub use visbuffer::VisbufferPipeline;

use crate::accel::VolumeStructure;
use crate::gpu::{GpuContext, GpuScene, GpuTimer};
use crate::passes::{visbuffer_raster::DEPTH_FORMAT, visbuffer_shade::HDR_FORMAT};
use crate::post::{tonemap::LDR_FORMAT, PostChain, PostSettings};
use crate::rays::SunShadows;
use crate::Result;

/// Which frame graph renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum PipelineKind {
    /// Visibility buffer, shading in compute (`visbuffer.rs`).
    #[default]
    Visbuffer,
    /// G-buffer raster, then decals and lights in compute (`deferred.rs`).
    Deferred,
    /// Depth prepass, then shading in the fragment stage (`forward.rs`).
    Forward,
}

impl PipelineKind {
    pub const ALL: [PipelineKind; 3] = [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward];

    pub fn name(self) -> &'static str {
        match self {
            PipelineKind::Visbuffer => "visbuffer",
            PipelineKind::Deferred => "deferred",
            PipelineKind::Forward => "forward",
        }
    }
}

/// The pipeline a renderer runs. Boxed: the variants hold hundreds of bytes of GPU handles each.
pub enum FramePipeline {
    Visbuffer(Box<VisbufferPipeline>),
    Deferred(Box<DeferredPipeline>),
    Forward(Box<ForwardPipeline>),
}

impl FramePipeline {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, kind: PipelineKind, setup: FrameSetup) -> Result<Self> {
        Ok(match kind {
            PipelineKind::Visbuffer => Self::Visbuffer(Box::new(VisbufferPipeline::new(ctx, scene, setup)?)),
            PipelineKind::Deferred => Self::Deferred(Box::new(DeferredPipeline::new(ctx, scene, setup)?)),
            PipelineKind::Forward => Self::Forward(Box::new(ForwardPipeline::new(ctx, scene, setup)?)),
        })
    }

    /// Records one frame. The frame uniforms must already be written.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, inputs: &FrameInputs) {
        match self {
            Self::Visbuffer(p) => p.record(encoder, timer, inputs),
            Self::Deferred(p) => p.record(encoder, timer, inputs),
            Self::Forward(p) => p.record(encoder, timer, inputs),
        }
    }

    pub fn targets(&self) -> &FrameTargets {
        match self {
            Self::Visbuffer(p) => &p.targets,
            Self::Deferred(p) => &p.targets,
            Self::Forward(p) => &p.targets,
        }
    }

    /// The post chain every pipeline ends with.
    pub fn post(&self) -> &PostChain {
        match self {
            Self::Visbuffer(p) => &p.post,
            Self::Deferred(p) => &p.post,
            Self::Forward(p) => &p.post,
        }
    }
}

/// What every pipeline is built for: the shading core's methods, how the sun's shadows are traced
/// (`passes::ray_shadows`; `Off`: not at all), the post effects (`post/`), the light and decal
/// structures, the image size.
#[derive(Clone, Copy)]
pub struct FrameSetup<'a> {
    pub methods: ShadingMethods,
    pub shadows: SunShadows,
    pub post: PostSettings,
    pub structures: (&'a VolumeStructure, &'a VolumeStructure),
    pub size: (u32, u32),
}

impl FrameSetup<'_> {
    /// The sun's shadow mode when it traces shadows.
    pub fn traced_shadows(&self) -> Option<SunShadows> {
        (self.shadows != SunShadows::Off).then_some(self.shadows)
    }
}

/// What a frame reads besides its pipeline's own images: the scene, the light and decal structures
/// (bound as groups 2 and 3 by the shading passes), and the eye, which orders draws front to back.
#[derive(Clone, Copy)]
pub struct FrameInputs<'a> {
    pub scene: &'a GpuScene,
    pub lights: &'a VolumeStructure,
    pub decals: &'a VolumeStructure,
    pub eye: glam::Vec3,
}

/// The images every pipeline writes; `hdr` and `ldr` can be read back.
pub struct FrameTargets {
    pub width: u32,
    pub height: u32,
    pub depth: wgpu::Texture,
    pub hdr: wgpu::Texture,
    pub ldr: wgpu::Texture,
}

impl FrameTargets {
    fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        use wgpu::TextureUsages as U;
        Self {
            width,
            height,
            depth: target(device, "depth", width, height, DEPTH_FORMAT, U::RENDER_ATTACHMENT | U::TEXTURE_BINDING),
            // Written by a compute pass (visibility buffer) or as a colour attachment (forward).
            hdr: target(
                device,
                "hdr",
                width,
                height,
                HDR_FORMAT,
                U::STORAGE_BINDING | U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC,
            ),
            // Sampled by the viewer to show it.
            ldr: target(device, "ldr", width, height, LDR_FORMAT, U::STORAGE_BINDING | U::COPY_SRC | U::TEXTURE_BINDING),
        }
    }
}

/// A 2D image a frame writes and reads, of one mip level and sample.
pub(crate) fn target(
    device: &wgpu::Device,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// How the shading core finds the local lights that reach a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum LightMethod {
    /// No local lights: the baseline the others are measured against.
    Off,
    /// Loop over every light.
    #[default]
    Brute,
    /// Point queries in a BVH over the lights' volumes (`accel`).
    Bvh,
    /// Per-froxel lists built every frame (`accel/clusters.rs`); view frustum only.
    Clustered,
}

impl LightMethod {
    pub const ALL: [LightMethod; 4] = [LightMethod::Off, LightMethod::Brute, LightMethod::Bvh, LightMethod::Clustered];

    /// The WGSL module that defines `shade_local_lights` for this method.
    pub fn enumeration_module(self) -> &'static str {
        match self {
            LightMethod::Off => "shading/enumerate/lights_off.wgsl",
            LightMethod::Brute => "shading/enumerate/lights_brute.wgsl",
            LightMethod::Bvh => "shading/enumerate/lights_bvh.wgsl",
            LightMethod::Clustered => "shading/enumerate/lights_clustered.wgsl",
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            LightMethod::Off => "off",
            LightMethod::Brute => "brute",
            LightMethod::Bvh => "bvh",
            LightMethod::Clustered => "clustered",
        }
    }
}

/// How the shading core finds the decals that cover a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum DecalMethod {
    /// No decals: the baseline the others are measured against.
    Off,
    /// Loop over every decal.
    #[default]
    Brute,
    /// Point queries in a BVH over the decals' boxes (`accel`).
    Bvh,
    /// Per-froxel lists built every frame (`accel/clusters.rs`); view frustum only.
    Clustered,
    /// Decal boxes rasterised into the G-buffer before lighting (Kim 2012); deferred pipeline only.
    DeferredDecals,
}

impl DecalMethod {
    pub const ALL: [DecalMethod; 5] =
        [DecalMethod::Off, DecalMethod::Brute, DecalMethod::Bvh, DecalMethod::Clustered, DecalMethod::DeferredDecals];

    /// Whether `pipeline` can apply decals this way: deferred decals need a G-buffer to blend into.
    pub fn works_in(self, pipeline: PipelineKind) -> bool {
        self != DecalMethod::DeferredDecals || pipeline == PipelineKind::Deferred
    }

    /// The WGSL module that defines `apply_decals` for this method.
    pub fn enumeration_module(self) -> &'static str {
        match self {
            DecalMethod::Off => "shading/enumerate/decals_off.wgsl",
            DecalMethod::Brute => "shading/enumerate/decals_brute.wgsl",
            DecalMethod::Bvh => "shading/enumerate/decals_bvh.wgsl",
            DecalMethod::Clustered => "shading/enumerate/decals_clustered.wgsl",
            // Already blended into the G-buffer when shading runs.
            DecalMethod::DeferredDecals => "shading/enumerate/decals_off.wgsl",
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            DecalMethod::Off => "off",
            DecalMethod::Brute => "brute",
            DecalMethod::Bvh => "bvh",
            DecalMethod::Clustered => "clustered",
            DecalMethod::DeferredDecals => "deferred-decals",
        }
    }
}

/// How the shading core lights a point with the particle lights (`particles/`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum ParticleMethod {
    /// No particle lights.
    #[default]
    Off,
    /// Sample the two 3D textures the particles are splatted into every frame.
    Grid,
    /// Exact: every particle a point light in the lights' BVH, rebuilt on the GPU every frame (needs
    /// `LightMethod::Bvh`, which then shades them).
    Bvh,
}

impl ParticleMethod {
    pub const ALL: [ParticleMethod; 3] = [ParticleMethod::Off, ParticleMethod::Grid, ParticleMethod::Bvh];

    /// The WGSL module that defines `shade_particle_lights` for this method.
    pub fn lighting_module(self) -> &'static str {
        match self {
            ParticleMethod::Off => "shading/enumerate/particles_off.wgsl",
            ParticleMethod::Grid => "shading/enumerate/particles_grid.wgsl",
            // The particles are among the lights: `shade_local_lights` reaches them.
            ParticleMethod::Bvh => "shading/enumerate/particles_off.wgsl",
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            ParticleMethod::Off => "off",
            ParticleMethod::Grid => "grid",
            ParticleMethod::Bvh => "bvh",
        }
    }
}

/// The methods a shading core is composed with: one per kind of light source and for decals, whether
/// glossy surfaces trace reflections (`shading/reflections.wgsl`) and points trace shadow rays towards
/// lamps (`shading/light_shadows.wgsl`), and whether point queries may walk a subgroup at a time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct ShadingMethods {
    pub lights: LightMethod,
    pub decals: DecalMethod,
    pub particles: ParticleMethod,
    pub reflections: bool,
    /// Shadow rays towards local lights that cast them (`--light-shadow-rays` above 0).
    pub light_shadows: bool,
    /// The device has subgroup operations: passes may walk BVHs a subgroup at a time
    /// (`accel/volume_query_subgroup.wgsl`), where that is faster (`passes::query_walks`).
    pub subgroups: bool,
    /// The decals crowd: their structure's [`centre_overlap`](crate::accel::VolumeStructure::centre_overlap)
    /// reaches [`crate::passes::DENSE_DECAL_OVERLAP`], so its CPU-built groups have wide leaves
    /// ([`crate::accel::VolumeStructure::wide_leaves`]), and queries walk them a subgroup at a time,
    /// sharing each leaf's decals out among the lanes (`passes::query_walks`).
    pub dense_decals: bool,
    /// The decals' structure is one crowded group placed once, with cell lists
    /// ([`crate::accel::VolumeStructure::cell_lists`]): `bvh` decals are read from the list of a
    /// point's cell instead of walked (`shading/enumerate/decals_bvh_cells.wgsl`).
    pub decal_cell_lists: bool,
    /// A debug view is shown: the shading core counts its work (`DEBUG_VIEWS` in
    /// `shading/debug_view.wgsl`, a pipeline constant: `ShadingMethods::debug_views_constant`).
    pub debug_views: bool,
}

impl ShadingMethods {
    /// The shading core's pipeline constant for its debug views' counters.
    pub fn debug_views_constant(&self) -> (&'static str, f64) {
        ("DEBUG_VIEWS", f64::from(u8::from(self.debug_views)))
    }
}
