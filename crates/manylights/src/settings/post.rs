//! Post effects after shading: exposure, bloom, depth of field, motion blur and vignette.

use crate::{Error, Result};

/// Edge of the tiles depth of field and motion blur find their reach over (`POST_TILE` in WGSL).
pub const POST_TILE: u32 = 16;

/// Most samples per pixel of motion blur; the largest circle of confusion's radius and the longest
/// motion blur, in pixels: the gathers search the 3×3 tiles around a pixel, so nothing beyond a tile
/// (depth of field's radius) or two (motion blur's ±½ length) could reach it.
pub const MAX_MOTION_BLUR_SAMPLES: u32 = 64;
pub const MAX_COC_RADIUS: f32 = POST_TILE as f32;
pub const MAX_MOTION_BLUR_LENGTH: f32 = 2.0 * POST_TILE as f32;

/// Exposure measured from the image every frame (`exposure.wgsl`), instead of the scene's fixed one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutoExposure {
    /// Stops above (+) or below (−) mapping the image's mean luminance to middle grey.
    pub compensation_ev: f32,
    /// How fast the exposure follows the measurement, per second (the first frame takes it at once):
    /// after 1 / speed seconds it has moved 63 % of the way.
    pub adaptation_speed: f32,
}

impl Default for AutoExposure {
    fn default() -> Self {
        Self { compensation_ev: 0.0, adaptation_speed: 3.0 }
    }
}

/// How radiance is scaled before tonemapping.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exposure {
    /// Measured from every frame's luminance histogram of the surfaces in view (of the background
    /// where none is); a first frame takes it at once, so a still render is exposed from its own
    /// image.
    Auto(AutoExposure),
    /// A fixed linear scale ([`Exposure::from_ev100`] gives a camera's).
    Fixed(f32),
}

impl Default for Exposure {
    fn default() -> Self {
        Exposure::Auto(AutoExposure::default())
    }
}

/// The range `--exposure` accepts, in EV100: from a dark night to far past direct sunlight.
pub const EV100_RANGE: (f32, f32) = (-20.0, 30.0);

impl Exposure {
    /// The scale of a camera set to `ev100`: 1 / (1.2 · 2^EV100), the saturation-based sensitivity
    /// of ISO 12232 with the lens's 78 % transmission (Lagarde & de Rousiers, "Moving Frostbite to
    /// PBR", 2014), so 0 EV100 maps a luminance of 1.2 to white.
    pub fn from_ev100(ev100: f32) -> Self {
        Exposure::Fixed(1.0 / (1.2 * ev100.exp2()))
    }

    /// A caller's choice over a scene file's: a fixed EV100 (`--exposure`) first, then auto exposure
    /// asked for by name (`--auto-exposure`), then the scene file's fixed scale; auto otherwise.
    pub fn chosen(fixed_ev100: Option<f32>, auto_asked: bool, scene_scale: Option<f32>, auto: AutoExposure) -> Self {
        match (fixed_ev100, auto_asked, scene_scale) {
            (Some(ev100), _, _) => Exposure::from_ev100(ev100),
            (None, false, Some(scale)) => Exposure::Fixed(scale),
            _ => Exposure::Auto(auto),
        }
    }

    /// The auto exposure's settings, when metered.
    pub fn auto(self) -> Option<AutoExposure> {
        match self {
            Exposure::Auto(auto) => Some(auto),
            Exposure::Fixed(_) => None,
        }
    }

    /// The fixed scale; 1 when metered (the meter's result then scales the image).
    pub fn fixed_scale(self) -> f32 {
        match self {
            Exposure::Auto(_) => 1.0,
            Exposure::Fixed(scale) => scale,
        }
    }
}

/// Bloom (`bloom.wgsl`): the blurred image's share of the result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bloom {
    pub intensity: f32,
}

impl Default for Bloom {
    fn default() -> Self {
        Self { intensity: 0.05 }
    }
}

/// Depth of field of a thin lens (`depth_of_field.wgsl`) with the view's field of view on a
/// 24 mm-high sensor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DepthOfField {
    /// Distance in focus, in metres; `None` focuses on what the image's centre shows.
    pub focus_distance: Option<f32>,
    /// Focal length over aperture diameter: lower is shallower.
    pub f_number: f32,
    /// Largest circle of confusion's radius, in pixels.
    pub max_radius: f32,
}

impl Default for DepthOfField {
    fn default() -> Self {
        Self { focus_distance: None, f_number: 2.8, max_radius: 16.0 }
    }
}

/// Motion blur (`motion_blur.wgsl`) from per-pixel velocities (`velocity.wgsl`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionBlur {
    /// Shutter time as a fraction of the frame interval (0.5: a 180° shutter).
    pub shutter: f32,
    /// Samples per pixel along the blur.
    pub samples: u32,
    /// Longest blur, in pixels.
    pub max_length: f32,
}

impl Default for MotionBlur {
    fn default() -> Self {
        Self { shutter: 0.5, samples: 16, max_length: 32.0 }
    }
}

/// Which post effects a frame runs, and how. Tonemapping is always on (`RenderConfig::tonemapper`
/// picks its curve, `None` clamps).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PostSettings {
    pub exposure: Exposure,
    pub bloom: Option<Bloom>,
    pub depth_of_field: Option<DepthOfField>,
    pub motion_blur: Option<MotionBlur>,
    /// Natural vignetting's strength: 0 none, 1 the cos⁴ law of a real lens.
    pub vignette: f32,
}

impl PostSettings {
    /// Checks every setting; messages name the command-line flag.
    pub fn validate(&self) -> Result<()> {
        let invalid = |m: String| Err(Error::InvalidConfig(m));
        let in_range = |v: f32, low: f32, high: f32| v.is_finite() && v >= low && v <= high;
        if !in_range(self.vignette, 0.0, 1.0) {
            return invalid(format!("vignette strength {} must be between 0 (none) and 1 (the cos⁴ law) (--vignette)", self.vignette));
        }
        if let Exposure::Fixed(scale) = self.exposure {
            if !(scale.is_finite() && scale > 0.0) {
                return invalid(format!(
                    "exposure scale {scale} must be finite and above 0 (--exposure takes EV100 from {} to {})",
                    EV100_RANGE.0, EV100_RANGE.1
                ));
            }
        }
        if let Exposure::Auto(auto) = self.exposure {
            if !in_range(auto.compensation_ev, -16.0, 16.0) {
                return invalid(format!(
                    "exposure compensation {} EV must be between -16 and 16 (--exposure-compensation)",
                    auto.compensation_ev
                ));
            }
            if !in_range(auto.adaptation_speed, 0.0, 1000.0) || auto.adaptation_speed == 0.0 {
                return invalid(format!(
                    "exposure adaptation speed {} per second must be above 0 and at most 1000 (--exposure-adaptation)",
                    auto.adaptation_speed
                ));
            }
        }
        if let Some(bloom) = self.bloom {
            if !in_range(bloom.intensity, 0.0, 1.0) || bloom.intensity == 0.0 {
                return invalid(format!("bloom intensity {} must be above 0 and at most 1 (--bloom-intensity)", bloom.intensity));
            }
        }
        if let Some(dof) = self.depth_of_field {
            if let Some(focus) = dof.focus_distance {
                if !(focus.is_finite() && focus > 0.0) {
                    return invalid(format!("focus distance {focus} m must be a finite distance above 0 (--focus-distance)"));
                }
            }
            if !in_range(dof.f_number, 0.1, 1000.0) {
                return invalid(format!("f-number {} must be between 0.1 and 1000 (--f-number)", dof.f_number));
            }
            if !in_range(dof.max_radius, 1.0, MAX_COC_RADIUS) {
                return invalid(format!(
                    "largest circle of confusion {} px must be between 1 and {MAX_COC_RADIUS} pixels in radius (--max-coc)",
                    dof.max_radius
                ));
            }
        }
        if let Some(blur) = self.motion_blur {
            if !in_range(blur.shutter, 0.0, 1.0) || blur.shutter == 0.0 {
                return invalid(format!("shutter {} must be above 0 and at most 1 frame interval (--shutter)", blur.shutter));
            }
            if !(1..=MAX_MOTION_BLUR_SAMPLES).contains(&blur.samples) {
                return invalid(format!(
                    "{} motion blur samples: give 1 to {MAX_MOTION_BLUR_SAMPLES} (--motion-blur-samples)",
                    blur.samples
                ));
            }
            if !in_range(blur.max_length, 1.0, MAX_MOTION_BLUR_LENGTH) {
                return invalid(format!(
                    "longest motion blur {} px must be between 1 and {MAX_MOTION_BLUR_LENGTH} pixels (--max-motion-blur)",
                    blur.max_length
                ));
            }
        }
        Ok(())
    }
}
