//! Ray-traced effects: sun shadows, reflections and shadow rays towards lamps, and their budgets.

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

/// Most rays per pixel towards the sun's disc, and most reflection bounces.
pub const MAX_SHADOW_RAYS: u32 = 64;
pub const MAX_REFLECTION_BOUNCES: u32 = 8;

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
        }
    }
}

impl RaySettings {
    /// Whether any effect traces rays, so the scene needs its ray hierarchy.
    pub fn traces_rays(&self) -> bool {
        self.sun_shadows != SunShadows::Off || self.reflection_bounces > 0 || self.light_shadow_rays > 0
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
