//! How particle lights are rendered: the method, and the grid's voxels, filter and cascades.

use super::{ParticleMethod, Spelling};
use crate::{Error, Result};

/// Most cascades of a particle clipmap (`particles::ParticleVolume::Clipmap`).
pub const MAX_PARTICLE_CASCADES: u32 = 8;
/// Most jittered points one shading point samples the grid at (`RenderConfig::particle_samples`).
pub const MAX_PARTICLE_SAMPLES: u32 = 64;
/// Fewest voxels per axis of a clipmap cascade: a point that the finer cascade's edge hands over lies
/// deep enough in the coarser one (past its own blend band) that the switch leaves no seam.
pub const MIN_CASCADE_RESOLUTION: u32 = 24;

named_enum! {
    /// How shading reads the particle grid; the paper's remedies for its blocks are the filters past
    /// nearest, and supersampling (`RenderConfig::particle_samples`). Keep in sync with
    /// `PARTICLE_FILTER_*` in `shading/types.wgsl`.
    pub enum ParticleFilter {
        /// The voxel the point lies in.
        Nearest(0) = "nearest",
        /// The eight voxels around the point, by the hardware.
        #[default]
        Trilinear(1) = "trilinear",
        /// A cubic B-spline over the 64 voxels around it, as eight trilinear taps (Sigg & Hadwiger
        /// 2005): smooth across voxel faces, slightly blurred.
        Tricubic(2) = "tricubic",
    }
}

/// Choices of how particles render that override others field by field: a scene file's
/// `[particles]`, and the command line's flags over it ([`ParticleOverlay::over`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ParticleOverlay {
    pub method: Option<ParticleMethod>,
    pub voxel_size: Option<f32>,
    pub filter: Option<ParticleFilter>,
    pub samples: Option<u32>,
    pub cascades: Option<u32>,
    pub cascade_resolution: Option<u32>,
}

impl ParticleOverlay {
    /// This overlay's choices over `below`'s.
    pub fn over(self, below: ParticleOverlay) -> ParticleOverlay {
        ParticleOverlay {
            method: self.method.or(below.method),
            voxel_size: self.voxel_size.or(below.voxel_size),
            filter: self.filter.or(below.filter),
            samples: self.samples.or(below.samples),
            cascades: self.cascades.or(below.cascades),
            cascade_resolution: self.cascade_resolution.or(below.cascade_resolution),
        }
    }

    /// Checks the choices it makes; messages name them as `spelling` spells them.
    pub fn validate(&self, spelling: Spelling) -> Result<()> {
        if let Some(size) = self.voxel_size {
            check_voxel_size(size, spelling)?;
        }
        if let Some(samples) = self.samples {
            check_samples(samples, spelling)?;
        }
        if let Some(cascades) = self.cascades {
            check_cascades(cascades, spelling)?;
        }
        if let Some(resolution) = self.cascade_resolution {
            check_cascade_resolution(resolution, spelling)?;
        }
        Ok(())
    }
}

/// The particle grid's voxel edge, in metres: finite and above 0.
pub fn check_voxel_size(voxel_size: f32, spelling: Spelling) -> Result<()> {
    if voxel_size.is_finite() && voxel_size > 0.0 {
        return Ok(());
    }
    let name = spelling.pick("particle voxel size", "voxel_size");
    Err(Error::InvalidConfig(format!("{name} {voxel_size} must be a finite length > 0, in metres")))
}

/// Jittered grid samples per shading point: 1 to [`MAX_PARTICLE_SAMPLES`].
pub fn check_samples(samples: u32, spelling: Spelling) -> Result<()> {
    if (1..=MAX_PARTICLE_SAMPLES).contains(&samples) {
        return Ok(());
    }
    let name = spelling.pick("particle samples", "samples");
    Err(Error::InvalidConfig(format!("{samples} {name} per point: give 1 to {MAX_PARTICLE_SAMPLES}")))
}

/// Clipmap cascades: 0 (one grid over the scene) to [`MAX_PARTICLE_CASCADES`].
pub fn check_cascades(cascades: u32, spelling: Spelling) -> Result<()> {
    if cascades <= MAX_PARTICLE_CASCADES {
        return Ok(());
    }
    let name = spelling.pick("particle cascades", "cascades");
    Err(Error::InvalidConfig(format!("{cascades} {name}: give 1 to {MAX_PARTICLE_CASCADES}, or 0 for one grid over the scene")))
}

/// Voxels per axis of a cascade: even, at least [`MIN_CASCADE_RESOLUTION`].
pub fn check_cascade_resolution(resolution: u32, spelling: Spelling) -> Result<()> {
    if resolution >= MIN_CASCADE_RESOLUTION && resolution.is_multiple_of(2) {
        return Ok(());
    }
    let name = spelling.pick("particle cascade resolution", "cascade_resolution");
    Err(Error::InvalidConfig(format!("{name} {resolution}: give an even number of voxels per axis, at least {MIN_CASCADE_RESOLUTION}")))
}
