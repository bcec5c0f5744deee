//! Render settings chosen by the caller (the CLI's flags), validated against the device.

use crate::{
    accel::BvhBuild,
    gpu::GpuContext,
    particles::{ParticleFilter, MAX_PARTICLE_SAMPLES},
    pipelines::{DecalMethod, LightMethod, ParticleMethod, PipelineKind},
    post::PostSettings,
    rays::RaySettings,
    Error, Result,
};

/// Keep the discriminants in sync with `TONEMAP_*` in `shading/types.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Tonemapper {
    #[default]
    Aces = 0,
    Agx = 1,
    /// Clamp only: for inspecting linear values.
    None = 2,
}

/// What a frame shows instead of its radiance, for looking inside the methods (the viewer's debug
/// views). Keep the discriminants in sync with `DEBUG_VIEW_*` in `shading/debug_view.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DebugView {
    #[default]
    Off = 0,
    /// Lights reaching each point, as a heat map up to 16.
    LightsReaching = 1,
    /// The light method's work at each point: BVH nodes visited, the froxel's list length (cluster
    /// occupancy) or lights tested, up to 128.
    LightWork = 2,
    /// Decals covering each point, up to 16.
    DecalsCovering = 3,
    /// The particle lights' radiance alone (exposed and tonemapped as usual).
    ParticleLight = 4,
    /// A horizontal slice through the particle grid (`RenderConfig::debug_slice_height`): the grid's
    /// colour sums where pixels' rays cross it before their surface, the scene dimmed elsewhere.
    ParticleGridSlice = 5,
}

impl DebugView {
    pub const ALL: [DebugView; 6] = [
        DebugView::Off,
        DebugView::LightsReaching,
        DebugView::LightWork,
        DebugView::DecalsCovering,
        DebugView::ParticleLight,
        DebugView::ParticleGridSlice,
    ];

    pub fn name(self) -> &'static str {
        match self {
            DebugView::Off => "off",
            DebugView::LightsReaching => "lights-reaching",
            DebugView::LightWork => "light-work",
            DebugView::DecalsCovering => "decals-covering",
            DebugView::ParticleLight => "particle-light",
            DebugView::ParticleGridSlice => "particle-grid-slice",
        }
    }

    /// The count a heat map tops out at; 0 for views that are not heat maps.
    pub fn scale(self) -> u32 {
        match self {
            DebugView::LightsReaching | DebugView::DecalsCovering => 16,
            DebugView::LightWork => 128,
            DebugView::Off | DebugView::ParticleLight | DebugView::ParticleGridSlice => 0,
        }
    }

    /// The frame uniforms' `debug_view`, with the slice's height (metres) for the grid slice.
    pub fn uniform(self, slice_height: f32) -> [u32; 4] {
        [self as u32, self.scale(), slice_height.to_bits(), 0]
    }
}

/// The heat map of `count` out of `scale` as the shaders draw it (`heat_map` in
/// `shading/debug_view.wgsl`): black for none, then blue, cyan, green, yellow, red.
pub fn heat_map(count: u32, scale: u32) -> [f32; 3] {
    if count == 0 {
        return [0.0; 3];
    }
    let stops = [[0.0, 0.0, 1.0], [0.0, 1.0, 1.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 0.0]];
    let t = (count as f32 / scale.max(1) as f32).clamp(0.0, 1.0) * 4.0;
    let i = (t as usize).min(3);
    let f = t - i as f32;
    std::array::from_fn(|c| stops[i][c] + (stops[i + 1][c] - stops[i][c]) * f)
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
    /// Maximum anisotropy of texture filtering, 1 (trilinear) to 16. Software rasterisers are many
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
            light_method: LightMethod::Brute,
            light_bvh_build: BvhBuild::CpuOnce,
            decal_method: DecalMethod::Brute,
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
    /// Checks the settings against what the device supports.
    pub fn validate(&self, ctx: &GpuContext) -> Result<()> {
        let max = ctx.limits.max_texture_dimension_2d;
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
        if hdr_bytes > ctx.limits.max_buffer_size {
            return Err(Error::InvalidConfig(format!(
                "resolution {}×{} needs a {} MiB readback buffer, over this GPU's {} MiB limit; choose a smaller --width/--height",
                self.width,
                self.height,
                hdr_bytes >> 20,
                ctx.limits.max_buffer_size >> 20
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
        if !(self.particle_voxel_size.is_finite() && self.particle_voxel_size > 0.0) {
            return Err(Error::InvalidConfig(format!(
                "particle voxel size {} must be a finite length > 0, in metres",
                self.particle_voxel_size
            )));
        }
        if !(1..=MAX_PARTICLE_SAMPLES).contains(&self.particle_samples) {
            return Err(Error::InvalidConfig(format!(
                "{} particle samples per point: give 1 to {MAX_PARTICLE_SAMPLES}",
                self.particle_samples
            )));
        }
        // The resolution is checked without cascades too: a bad one given with none is still a mistake.
        crate::particles::check_clipmap(self.particle_cascade_resolution, self.particle_cascades)?;
        self.rays.validate()?;
        if let Some(height) = self.debug_slice_height.filter(|h| !h.is_finite()) {
            return Err(Error::InvalidConfig(format!(
                "debug slice height {height} must be a finite height in metres (--debug-slice-height)"
            )));
        }
        self.post.validate()?;
        if !(1..=16).contains(&self.anisotropy) {
            return Err(Error::InvalidConfig(format!("anisotropy {} must be between 1 and 16", self.anisotropy)));
        }
        Ok(())
    }
}
