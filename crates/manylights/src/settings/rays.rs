//! Ray-traced effects: sun shadows, reflections, shadow rays towards lamps and how local lights are
//! shadowed (`DirectLighting`), and their budgets.

use super::Spelling;
use crate::{Error, Result};

named_enum! {
    /// How the sun's shadows are made. Keep the discriminants in sync with `RAY_SHADOWS_*` in
    /// `shading/types.wgsl`.
    pub enum SunShadows {
        /// The sun lights every surface facing it.
        #[default]
        Off(0) = "off",
        /// One ray per pixel towards the sun's centre (`passes/ray_shadows.rs`).
        Hard(1) = "hard",
        /// Rays to points of the sun's disc, jittered per pixel, then a depth-aware spatial filter
        /// (`passes/shadow_filter.rs`): penumbrae from the sun's angular size.
        Soft(2) = "soft",
    }
}

named_enum! {
    /// How local lights — scattered, glTF, scene-file and exact particle lights, whichever method
    /// enumerates them — light a shading point. The sun, the environment, decals and the particle grid
    /// are the same in every mode.
    pub enum DirectLighting {
        /// Every enumerated light, unshadowed but for the lights that cast shadows, within the point's
        /// budget of `light_shadow_rays`.
        #[default]
        Exact = "exact",
        /// Every enumerated light with a shadow ray of its own: the ground truth, whatever it costs.
        Reference = "reference",
        /// Resampled importance sampling of the enumerated lights by their unshadowed contribution,
        /// a shadow ray for each of `restir_shadow_rays` samples (`shading/direct/restir.wgsl`).
        Restir = "restir",
    }
}

named_enum! {
    /// Which earlier samples `restir` reuses at a pixel's surface (`shading/direct/restir.wgsl`). Keep
    /// the discriminants in sync with `RESTIR_REUSE_*` there.
    pub enum RestirReuse {
        /// None: each frame samples afresh.
        Off(0) = "off",
        /// The previous frame's reservoir at the surface, found by reprojection: no ray beyond the
        /// pixel's own under a still camera.
        #[default]
        Temporal(1) = "temporal",
        /// That one and a few of its neighbours' (`RESTIR_REUSED`), each neighbour asked with a ray
        /// whether it sees the light chosen: four rays a pixel more, which cost more than the
        /// reference's ray per light at 6 lights a point, and rare high-weight samples spread
        /// (BENCHMARKS.md, "Shadowed local lights").
        Spatiotemporal(2) = "spatiotemporal",
    }
}

named_enum! {
    /// Where `restir` finds its candidates at a point.
    pub enum RestirCandidates {
        /// By the light density the scene's statistics show: the enumeration where few lights reach
        /// a point, the tree where many do (`plan::restir_light_tree`).
        #[default]
        Auto = "auto",
        /// Every light the light method enumerates there: the cost grows with the lights reaching.
        Enumeration = "enumeration",
        /// A few lights drawn through the lights' BVH by their estimated contribution (a light tree,
        /// `accel/light_tree.rs`): a cost that stays the same however many lights reach. Needs
        /// `bvh` lights (built on the CPU or rebuilt on the GPU; particle lights too).
        Tree = "tree",
    }
}

named_enum! {
    /// Whether sampled direct lighting (`restir`) is denoised at the pixels' opaque surfaces
    /// (`passes/denoise/`).
    pub enum Denoise {
        /// The samples as they are: for error studies.
        Off = "off",
        /// Temporal accumulation with per-pixel moments, then a variance-guided à-trous filter on
        /// demodulated diffuse and specular light, guided by depth and normals (Schied et al. 2017).
        #[default]
        Svgf = "svgf",
    }
}

named_enum! {
    /// What traces the renderer's point queries and rays: the `bvh` lights' and decals' queries (a ray
    /// query of minimal length whose box candidates get the exact test) and every ray against the
    /// triangles (shadows, reflections, restir's).
    pub enum RayBackend {
        /// The GPU's ray queries where the GPU runs them (`wgpu::Features::EXPERIMENTAL_RAY_QUERY`),
        /// the software BVHs elsewhere, also where a CPU adapter emulates them (`plan::RayTracer::resolve`).
        #[default]
        Auto = "auto",
        /// The GPU's ray queries through acceleration structures wgpu builds (`accel/hardware.rs`,
        /// `rays/hardware.rs`), emulated ones too: an error on adapters without them.
        Hardware = "hardware",
        /// manylights' own BVHs, walked in WGSL (`accel/`, `rays/`): every adapter.
        Software = "software",
    }
}

/// Most rays per pixel towards the sun's disc, and most reflection bounces.
pub const MAX_SHADOW_RAYS: u32 = 64;
pub const MAX_REFLECTION_BOUNCES: u32 = 8;
/// Most samples, each with its shadow ray, that `restir` draws per shading point. Keep in sync with
/// `RESTIR_MAX_SAMPLES` in `shading/direct/restir.wgsl`.
pub const MAX_RESTIR_SHADOW_RAYS: u32 = 4;

/// The ray-traced effects a frame renders, and their budgets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RaySettings {
    pub sun_shadows: SunShadows,
    /// The sun's angular diameter in degrees (the real sun's is about 0.53): the penumbrae of soft
    /// shadows.
    pub sun_angle_degrees: f32,
    /// Rays per pixel towards the sun's disc with soft shadows, 1 to [`MAX_SHADOW_RAYS`].
    pub shadow_rays: u32,
    /// Reflection bounces traced from glossy surfaces, 0 (no reflections) to
    /// [`MAX_REFLECTION_BOUNCES`]: each hit is shaded by the shading core and, if glossy itself,
    /// reflects again.
    pub reflection_bounces: u32,
    /// Surfaces whose perceptual roughness is below this reflect (fading out over the last quarter).
    pub reflection_roughness: f32,
    /// Shadow rays each shading point may trace towards local lights that cast shadows
    /// (`Light::cast_shadows`), 0 (none) to [`MAX_SHADOW_RAYS`]: lights beyond the budget, in the
    /// order the light method enumerates them, light the point unshadowed.
    pub light_shadow_rays: u32,
    /// How local lights light a point, and whether they cast shadows.
    pub direct_lighting: DirectLighting,
    /// Samples per shading point with `DirectLighting::Restir`, each with one shadow ray, 1 to
    /// [`MAX_RESTIR_SHADOW_RAYS`].
    pub restir_shadow_rays: u32,
    /// What `restir` reuses at the pixels' surfaces from earlier frames.
    pub restir_reuse: RestirReuse,
    /// Where `restir` finds its candidates.
    pub restir_candidates: RestirCandidates,
    /// How `restir`'s lighting is denoised.
    pub denoise: Denoise,
    /// What traces rays and point queries.
    pub backend: RayBackend,
}

impl Default for RaySettings {
    fn default() -> Self {
        Self {
            sun_shadows: SunShadows::Off,
            sun_angle_degrees: 0.53,
            shadow_rays: 4,
            reflection_bounces: 0,
            reflection_roughness: 0.3,
            light_shadow_rays: 0,
            direct_lighting: DirectLighting::Exact,
            restir_shadow_rays: 1,
            restir_reuse: RestirReuse::Temporal,
            restir_candidates: RestirCandidates::Auto,
            denoise: Denoise::Svgf,
            backend: RayBackend::Auto,
        }
    }
}

/// Choices of ray-traced effects that override others field by field: a scene file's `[rays]`, and
/// the command line's flags over it ([`RayOverlay::over`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayOverlay {
    pub sun_shadows: Option<SunShadows>,
    pub sun_angle_degrees: Option<f32>,
    pub shadow_rays: Option<u32>,
    pub reflection_bounces: Option<u32>,
    pub reflection_roughness: Option<f32>,
    pub light_shadow_rays: Option<u32>,
    pub direct_lighting: Option<DirectLighting>,
    pub restir_shadow_rays: Option<u32>,
    pub restir_reuse: Option<RestirReuse>,
    pub restir_candidates: Option<RestirCandidates>,
    pub denoise: Option<Denoise>,
    pub backend: Option<RayBackend>,
}

impl RayOverlay {
    /// This overlay's choices over `below`'s.
    pub fn over(self, below: RayOverlay) -> RayOverlay {
        RayOverlay {
            sun_shadows: self.sun_shadows.or(below.sun_shadows),
            sun_angle_degrees: self.sun_angle_degrees.or(below.sun_angle_degrees),
            shadow_rays: self.shadow_rays.or(below.shadow_rays),
            reflection_bounces: self.reflection_bounces.or(below.reflection_bounces),
            reflection_roughness: self.reflection_roughness.or(below.reflection_roughness),
            light_shadow_rays: self.light_shadow_rays.or(below.light_shadow_rays),
            direct_lighting: self.direct_lighting.or(below.direct_lighting),
            restir_shadow_rays: self.restir_shadow_rays.or(below.restir_shadow_rays),
            restir_reuse: self.restir_reuse.or(below.restir_reuse),
            restir_candidates: self.restir_candidates.or(below.restir_candidates),
            denoise: self.denoise.or(below.denoise),
            backend: self.backend.or(below.backend),
        }
    }

    /// The choices over the defaults.
    pub fn settings(&self) -> RaySettings {
        let defaults = RaySettings::default();
        RaySettings {
            sun_shadows: self.sun_shadows.unwrap_or(defaults.sun_shadows),
            sun_angle_degrees: self.sun_angle_degrees.unwrap_or(defaults.sun_angle_degrees),
            shadow_rays: self.shadow_rays.unwrap_or(defaults.shadow_rays),
            reflection_bounces: self.reflection_bounces.unwrap_or(defaults.reflection_bounces),
            reflection_roughness: self.reflection_roughness.unwrap_or(defaults.reflection_roughness),
            light_shadow_rays: self.light_shadow_rays.unwrap_or(defaults.light_shadow_rays),
            direct_lighting: self.direct_lighting.unwrap_or(defaults.direct_lighting),
            restir_shadow_rays: self.restir_shadow_rays.unwrap_or(defaults.restir_shadow_rays),
            restir_reuse: self.restir_reuse.unwrap_or(defaults.restir_reuse),
            restir_candidates: self.restir_candidates.unwrap_or(defaults.restir_candidates),
            denoise: self.denoise.unwrap_or(defaults.denoise),
            backend: self.backend.unwrap_or(defaults.backend),
        }
    }
}

impl RaySettings {
    /// Whether `restir` keeps each pixel's reservoir for the next frame.
    pub fn keeps_reservoirs(&self) -> bool {
        self.direct_lighting == DirectLighting::Restir && self.restir_reuse != RestirReuse::Off
    }

    /// Whether `restir`'s lighting is to be denoised.
    pub fn denoises(&self) -> bool {
        self.direct_lighting == DirectLighting::Restir && self.denoise != Denoise::Off
    }

    /// Whether any effect traces rays, so the scene needs its ray hierarchy.
    pub fn traces_rays(&self) -> bool {
        self.sun_shadows != SunShadows::Off
            || self.reflection_bounces > 0
            || self.light_shadow_rays > 0
            || self.direct_lighting != DirectLighting::Exact
    }

    /// Checks every setting; messages name the option as `spelling` spells it.
    pub fn validate(&self, spelling: Spelling) -> Result<()> {
        let invalid = |m: String| Err(Error::InvalidConfig(m));
        let name = |flag, key| spelling.pick(flag, key);
        if !(self.sun_angle_degrees.is_finite() && (0.0..=90.0).contains(&self.sun_angle_degrees)) {
            return invalid(format!(
                "sun angle {}° must be between 0 and 90 degrees ({})",
                self.sun_angle_degrees,
                name("--sun-angle", "sun_angle")
            ));
        }
        if !(1..=MAX_SHADOW_RAYS).contains(&self.shadow_rays) {
            return invalid(format!(
                "{} shadow rays per pixel: give 1 to {MAX_SHADOW_RAYS} ({})",
                self.shadow_rays,
                name("--shadow-rays", "shadow_rays")
            ));
        }
        if self.light_shadow_rays > MAX_SHADOW_RAYS {
            return invalid(format!(
                "{} shadow rays per point towards lights: give 0 (none) to {MAX_SHADOW_RAYS} ({})",
                self.light_shadow_rays,
                name("--light-shadow-rays", "light_shadow_rays")
            ));
        }
        if !(1..=MAX_RESTIR_SHADOW_RAYS).contains(&self.restir_shadow_rays) {
            return invalid(format!(
                "{} restir shadow rays per point: give 1 to {MAX_RESTIR_SHADOW_RAYS} ({})",
                self.restir_shadow_rays,
                name("--restir-shadow-rays", "restir_shadow_rays")
            ));
        }
        if self.reflection_bounces > MAX_REFLECTION_BOUNCES {
            return invalid(format!(
                "{} reflection bounces: give 0 (no reflections) to {MAX_REFLECTION_BOUNCES} ({})",
                self.reflection_bounces,
                name("--bounces", "reflections")
            ));
        }
        if !(self.reflection_roughness.is_finite() && self.reflection_roughness > 0.0 && self.reflection_roughness <= 1.0) {
            return invalid(format!(
                "reflection roughness threshold {} must be above 0 and at most 1 ({})",
                self.reflection_roughness,
                name("--reflection-roughness", "reflection_roughness")
            ));
        }
        Ok(())
    }
}
