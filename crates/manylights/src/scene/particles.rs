//! The particles of a scene (the particle-light paper's emitters): how many, where they are launched
//! from, how they fly and shine. [`ParticleSettings::particle_at`] computes any particle's light on
//! the CPU, the twin of the GPU's motion pass (`particles/motion.wgsl`).

use glam::Vec3;

use super::Aabb;
use crate::{Error, Result};

/// Most particles one system holds (about 2²⁴: as many as one row of 65535 workgroups of 256 threads,
/// which the exact method's LBVH build dispatches): their lights take 32 bytes each.
pub const MAX_PARTICLES: u32 = 65535 * 256;

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
}

/// As `hue_color` in `motion.wgsl`.
fn hue_color(hue: f32) -> Vec3 {
    let channel = |n: f32| {
        let k = (n + hue * 6.0) % 6.0;
        1.0 - k.min(4.0 - k).clamp(0.0, 1.0)
    };
    Vec3::new(channel(5.0), channel(3.0), channel(1.0))
}
