//! Deforming meshes: a procedural travelling wave that moves a mesh's vertices along their normals
//! (curtains, flags, water), or a glTF skin and morph targets (`scene::pose`), evaluated every frame
//! on the GPU (`passes/deform.wgsl`) for the raster and the rays alike; the rays' hierarchy of a
//! deformed mesh is refitted on the GPU every frame (`rays/refit.rs`). This CPU twin is the tests'
//! reference.

use super::{animation::Animation, pose::Pose, pose::PoseBounds, Aabb, Vertex};
use glam::Vec3;

/// A sine wave travelling along `direction` (mesh space): each vertex moves along its normal by
/// `amplitude · sin(2π (p · direction − speed · t) / wavelength)`, and its normal tilts with the
/// wave's slope.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wave {
    pub amplitude: f32,
    pub wavelength: f32,
    /// Metres per second the crests travel.
    pub speed: f32,
    /// Unit direction of travel, in the mesh's space.
    pub direction: Vec3,
}

/// What moves a deformed mesh's vertices.
#[derive(Clone, Debug, PartialEq)]
pub enum Deformation {
    Wave(Wave),
    /// Skin and morph targets, posed by the scene's animation.
    Pose(Box<Pose>),
}

/// What bounds a deformed mesh (`Deformer::reach`): a wave stays within its rest box grown by its
/// amplitude; a pose's box follows its joints and weights.
#[derive(Clone, Debug, PartialEq)]
pub enum DeformedReach {
    Fixed(Aabb),
    Posed(PoseBounds),
}

impl DeformedReach {
    /// A box, in the mesh's space, holding the mesh `deformer` deforms as at `clock`.
    pub fn bounds(&self, deformer: &Deformer, clock: &PoseClock) -> Aabb {
        match (self, &deformer.deformation) {
            (Self::Posed(measures), Deformation::Pose(pose)) => pose.bounds(measures, &pose_state(pose, clock)),
            (Self::Fixed(bounds), _) => *bounds,
            (Self::Posed(measures), _) => measures.rest,
        }
    }

    /// Whether the box moves with the animation.
    pub fn is_posed(&self) -> bool {
        matches!(self, Self::Posed(_))
    }
}

/// A mesh (index into `Scene::meshes`) and what deforms it: every instance of it deforms alike.
#[derive(Clone, Debug, PartialEq)]
pub struct Deformer {
    pub mesh: usize,
    pub deformation: Deformation,
}

impl Deformer {
    pub fn wave(mesh: usize, wave: Wave) -> Self {
        Self { mesh, deformation: Deformation::Wave(wave) }
    }

    /// What bounds the mesh however it deforms, measured from its vertices at rest (`rest`).
    pub fn reach(&self, rest: &[Vertex]) -> DeformedReach {
        match &self.deformation {
            Deformation::Wave(wave) => {
                // Each vertex moves along its normal, as given, by at most the amplitude.
                let mut bounds = Aabb::EMPTY;
                for v in rest {
                    let (p, reach) = (Vec3::from(v.position), Vec3::from(v.normal).abs() * wave.amplitude.abs());
                    bounds.grow_point(p - reach);
                    bounds.grow_point(p + reach);
                }
                // Room for the GPU's rounding of the sine.
                let pad = Vec3::splat(1e-5 * bounds.min.abs().max(bounds.max.abs()).max_element());
                DeformedReach::Fixed(Aabb::new(bounds.min - pad, bounds.max + pad))
            }
            Deformation::Pose(pose) => DeformedReach::Posed(PoseBounds::of(pose, rest)),
        }
    }

    /// The mesh's vertices (`rest`, primitive after primitive) deformed to `time` (seconds of scene
    /// time; a pose loops over `animation`'s duration).
    pub fn deformed(&self, rest: &[Vertex], time: f32, animation: Option<&Animation>) -> Vec<Vertex> {
        match &self.deformation {
            Deformation::Wave(wave) => rest
                .iter()
                .map(|v| {
                    let (position, normal) = wave.displace(Vec3::from(v.position), Vec3::from(v.normal), time);
                    Vertex { position: position.into(), normal: normal.into(), ..*v }
                })
                .collect(),
            Deformation::Pose(pose) => {
                let state = pose_state(pose, &PoseClock::at(time, animation));
                rest.iter().enumerate().map(|(i, v)| pose.pose_vertex(i, v, &state)).collect()
            }
        }
    }
}

/// What poses read from the animation at a scene time, computed once a frame for them all: the
/// time within its loop and every node's world matrix there; without an animation (and so without
/// skins), the time itself.
pub struct PoseClock {
    time: f32,
    node_worlds: Vec<glam::Mat4>,
}

impl PoseClock {
    pub fn at(time: f32, animation: Option<&Animation>) -> Self {
        match animation {
            Some(animation) => {
                let time = animation.looped(time);
                Self { time, node_worlds: animation.node_worlds(time) }
            }
            None => Self { time, node_worlds: Vec::new() },
        }
    }
}

/// A pose's state at the clock's time.
pub fn pose_state(pose: &Pose, clock: &PoseClock) -> super::pose::PoseState {
    pose.state(clock.time, &clock.node_worlds)
}

impl Wave {
    /// A vertex at rest (`position`, unit `normal`) moved to `time`: its position and normal.
    pub fn displace(&self, position: Vec3, normal: Vec3, time: f32) -> (Vec3, Vec3) {
        let k = std::f32::consts::TAU / self.wavelength;
        let phase = k * (position.dot(self.direction) - self.speed * time);
        let moved = position + normal * (self.amplitude * phase.sin());
        // The surface's slope along the direction of travel, within the tangent plane.
        let along = self.direction - normal * normal.dot(self.direction);
        let tilted = (normal - along * (self.amplitude * k * phase.cos())).normalize_or(normal);
        (moved, tilted)
    }

    /// Checks the numbers; the message names the bad one.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.amplitude.is_finite() && self.amplitude >= 0.0) {
            return Err(format!("wave amplitude {} must be a finite length ≥ 0", self.amplitude));
        }
        if !(self.wavelength.is_finite() && self.wavelength > 0.0) {
            return Err(format!("wavelength {} must be a finite length > 0", self.wavelength));
        }
        if !self.speed.is_finite() {
            return Err(format!("wave speed {} must be finite", self.speed));
        }
        if !(self.direction.is_finite() && (self.direction.length() - 1.0).abs() < 1e-3) {
            return Err(format!("wave direction {} must be a unit vector", self.direction));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wave_moves_vertices_along_their_normals_and_tilts_them_with_its_slope() {
        let wave = Wave { amplitude: 0.1, wavelength: 2.0, speed: 1.0, direction: Vec3::X };
        // A quarter wavelength ahead of the crest's start at t = 0: the crest itself.
        let (p, n) = wave.displace(Vec3::new(0.5, 0.0, 0.0), Vec3::Y, 0.0);
        assert!((p - Vec3::new(0.5, 0.1, 0.0)).length() < 1e-6 && (n - Vec3::Y).length() < 1e-6);
        // Where it crosses zero rising, the slope tilts the normal back against the travel.
        let (p, n) = wave.displace(Vec3::ZERO, Vec3::Y, 0.0);
        let slope = 0.1 * std::f32::consts::PI;
        assert!(p.length() < 1e-6);
        assert!((n - Vec3::new(-slope, 1.0, 0.0).normalize()).length() < 1e-6, "{n}");
        // Half a second later the crest has travelled half a metre.
        let (p, _) = wave.displace(Vec3::new(1.0, 0.0, 0.0), Vec3::Y, 0.5);
        assert!((p.y - 0.1).abs() < 1e-6);
        assert!(Wave { wavelength: 0.0, ..wave }.validate().unwrap_err().contains("wavelength"));
        assert!(Wave { direction: Vec3::ZERO, ..wave }.validate().unwrap_err().contains("direction"));
    }
}
