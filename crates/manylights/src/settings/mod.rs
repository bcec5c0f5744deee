//! Every choice a caller makes about rendering, at the bottom of the library: the option enums
//! (each spelled once, [`named_enum!`](crate::named_enum)), [`RenderConfig`] and its validation
//! against the device's limits, and the overlays a scene file's hints make. The CLI, the viewer, the
//! scene file and the bench use these types directly.

pub mod display;
pub mod methods;
#[macro_use]
pub mod named;
pub mod environment;
pub mod particles;
pub mod post;
pub mod rays;

pub use display::{heat_map, DebugView, Tonemapper};
pub use environment::Sky;
pub use methods::{BvhBuild, DecalMethod, LightMethod, MethodOverlay, ParticleMethod, PipelineKind};
pub use named::Named;
pub use particles::{ParticleFilter, ParticleOverlay, MAX_PARTICLE_CASCADES, MAX_PARTICLE_SAMPLES, MIN_CASCADE_RESOLUTION};
pub use post::{
    AutoExposure, Bloom, DepthOfField, Exposure, MotionBlur, PostSettings, EV100_RANGE, MAX_COC_RADIUS, MAX_MOTION_BLUR_LENGTH,
    MAX_MOTION_BLUR_SAMPLES, POST_TILE,
};
pub use rays::{
    Denoise, DirectLighting, RayBackend, RayOverlay, RaySettings, RestirCandidates, RestirReuse, SunShadows, MAX_REFLECTION_BOUNCES,
    MAX_RESTIR_SHADOW_RAYS, MAX_SHADOW_RAYS,
};

use crate::{Error, Result};

/// Most anisotropy of texture filtering.
pub const MAX_ANISOTROPY: u16 = 16;

/// How an error message names an option: as its command-line flag, or as its scene-file key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Spelling {
    Flag,
    Key,
}

impl Spelling {
    pub fn pick(self, flag: &'static str, key: &'static str) -> &'static str {
        match self {
            Spelling::Flag => flag,
            Spelling::Key => key,
        }
    }
}

/// What a scene file asks of the renderer besides its scene: its `[methods]`, `[rays]` and
/// `[particles]` rendering keys, its `sky` and its fixed `exposure` (a linear scale), each taken unless the
/// command line makes its own choice.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SettingsOverlay {
    pub methods: MethodOverlay,
    pub rays: RayOverlay,
    pub particles: ParticleOverlay,
    pub exposure: Option<f32>,
    pub sky: Option<Sky>,
}

/// The device limits the settings are checked against (`GpuContext::device_limits`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeviceLimits {
    pub max_texture_dimension_2d: u32,
    pub max_texture_dimension_3d: u32,
    pub max_buffer_size: u64,
}

#[derive(Clone, Debug)]
pub struct RenderConfig {
    pub width: u32,
    pub height: u32,
    pub pipeline: PipelineKind,
    pub light_method: LightMethod,
    /// How the light groups' BVHs are built, for `LightMethod::Bvh`.
    pub light_bvh_build: BvhBuild,
    pub decal_method: DecalMethod,
    /// How the decal groups' BVHs are built, for `DecalMethod::Bvh`.
    pub decal_bvh_build: BvhBuild,
    /// How shading finds the particle lights, when the scene has particles.
    pub particle_method: ParticleMethod,
    /// Edge of the particle grid's voxels, in metres (`ParticleMethod::Grid`).
    pub particle_voxel_size: f32,
    /// How shading filters the particle grid, and at how many jittered points per shading point
    /// (1 to [`MAX_PARTICLE_SAMPLES`]; 1 samples at the point itself).
    pub particle_filter: ParticleFilter,
    pub particle_samples: u32,
    /// Camera-centred cascades of the particle grid (`particles::ParticleVolume::Clipmap`), each of
    /// `particle_cascade_resolution`³ voxels; 0 for one grid fixed over the scene.
    pub particle_cascades: u32,
    pub particle_cascade_resolution: u32,
    pub tonemapper: Tonemapper,
    /// Largest texture layer size; larger images are downsampled at upload.
    pub max_texture_size: u32,
    /// Maximum anisotropy of texture filtering, 1 (trilinear) to [`MAX_ANISOTROPY`]. Software rasterisers are many
    /// times slower with anisotropic filtering, so the tests use 1.
    pub anisotropy: u16,
    /// Ray-traced effects: sun shadows and reflections, and their budgets (`rays/`).
    pub rays: RaySettings,
    /// Post effects after shading: exposure, bloom, depth of field, motion blur, vignette (`post/`).
    pub post: PostSettings,
    /// What the frame shows instead of its radiance (`Off`: its radiance).
    pub debug_view: DebugView,
    /// Height of `DebugView::ParticleGridSlice`'s plane in metres; `None`: a metre below the eye.
    pub debug_slice_height: Option<f32>,
}

impl Default for RenderConfig {
    fn default() -> Self {
        Self {
            width: 1280,
            height: 720,
            pipeline: PipelineKind::Visbuffer,
            light_method: LightMethod::Auto,
            light_bvh_build: BvhBuild::CpuOnce,
            decal_method: DecalMethod::Auto,
            decal_bvh_build: BvhBuild::CpuOnce,
            particle_method: ParticleMethod::Grid,
            particle_voxel_size: 1.0,
            particle_filter: ParticleFilter::Trilinear,
            particle_samples: 1,
            particle_cascades: 0,
            particle_cascade_resolution: 64,
            tonemapper: Tonemapper::Aces,
            max_texture_size: 1024,
            anisotropy: 8,
            rays: RaySettings::default(),
            post: PostSettings::default(),
            debug_view: DebugView::Off,
            debug_slice_height: None,
        }
    }
}

impl RenderConfig {
    /// The particle settings `overlay` chooses over these.
    pub fn with_particles(self, overlay: ParticleOverlay) -> Self {
        Self {
            particle_method: overlay.method.unwrap_or(self.particle_method),
            particle_voxel_size: overlay.voxel_size.unwrap_or(self.particle_voxel_size),
            particle_filter: overlay.filter.unwrap_or(self.particle_filter),
            particle_samples: overlay.samples.unwrap_or(self.particle_samples),
            particle_cascades: overlay.cascades.unwrap_or(self.particle_cascades),
            particle_cascade_resolution: overlay.cascade_resolution.unwrap_or(self.particle_cascade_resolution),
            ..self
        }
    }

    /// Checks the settings against each other and against what the device supports.
    pub fn validate(&self, limits: &DeviceLimits) -> Result<()> {
        let max = limits.max_texture_dimension_2d;
        if self.width == 0 || self.height == 0 {
            return Err(Error::InvalidConfig(format!(
                "resolution {}×{} is empty; width and height must be at least 1",
                self.width, self.height
            )));
        }
        if self.width > max || self.height > max {
            return Err(Error::InvalidConfig(format!(
                "resolution {}×{} is over this GPU's limit of {max} pixels per side; choose a smaller --width/--height",
                self.width, self.height
            )));
        }
        // The HDR image (16 bytes a pixel) must fit one buffer to be read back.
        let hdr_bytes = u64::from(self.width) * u64::from(self.height) * 16;
        if hdr_bytes > limits.max_buffer_size {
            return Err(Error::InvalidConfig(format!(
                "resolution {}×{} needs a {} MiB readback buffer, over this GPU's {} MiB limit; choose a smaller --width/--height",
                self.width,
                self.height,
                hdr_bytes >> 20,
                limits.max_buffer_size >> 20
            )));
        }
        if !self.decal_method.works_in(self.pipeline) {
            return Err(Error::InvalidConfig(format!(
                "deferred decals are rasterised into the G-buffer, which only --pipeline deferred has (not {}); \
                 use --pipeline deferred, or --decal-method bvh, clustered or brute",
                self.pipeline.name()
            )));
        }
        if self.max_texture_size == 0 {
            return Err(Error::InvalidConfig("the maximum texture size must be at least 1".into()));
        }
        particles::check_voxel_size(self.particle_voxel_size, Spelling::Flag)?;
        particles::check_samples(self.particle_samples, Spelling::Flag)?;
        particles::check_cascades(self.particle_cascades, Spelling::Flag)?;
        // The resolution is checked without cascades too: a bad one given with none is still a mistake.
        particles::check_cascade_resolution(self.particle_cascade_resolution, Spelling::Flag)?;
        self.rays.validate(Spelling::Flag)?;
        if let Some(height) = self.debug_slice_height.filter(|h| !h.is_finite()) {
            return Err(Error::InvalidConfig(format!(
                "debug slice height {height} must be a finite height in metres (--debug-slice-height)"
            )));
        }
        self.post.validate()?;
        if !(1..=MAX_ANISOTROPY).contains(&self.anisotropy) {
            return Err(Error::InvalidConfig(format!("anisotropy {} must be between 1 and {MAX_ANISOTROPY}", self.anisotropy)));
        }
        Ok(())
    }
}
