//! Node animation (glTF animations of node translation, rotation and scale): the node hierarchy
//! above the scene's mesh instances and keyframed channels, evaluated at a time into each moving
//! instance's transform and each skin joint's (`scene::pose`). The renderer moves draws and the rays'
//! top level with it every frame.
//!
//! Samplers interpolate as glTF defines: STEP, LINEAR (rotations by spherical linear interpolation)
//! and CUBICSPLINE (Hermite, with in- and out-tangents scaled by the keyframe interval); the animation
//! loops over its duration. No crate evaluates glTF samplers outside an engine (Bevy's and Fyrox's
//! are tied to their ECS), and this is small.

use glam::{Mat4, Quat, Vec3, Vec4};

/// Which part of a node's transform a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    Translation,
    Rotation,
    Scale,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    /// Each keyframe holds an in-tangent, a value and an out-tangent.
    CubicSpline,
}

/// One keyframed property of one node. Values are xyz (w unused) or quaternions (xyzw).
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub node: usize,
    pub property: Property,
    pub interpolation: Interpolation,
    /// Increasing keyframe times in seconds.
    pub times: Vec<f32>,
    /// One value per keyframe, or three (in-tangent, value, out-tangent) for cubic splines.
    pub values: Vec<Vec4>,
}

/// A node of the hierarchy: its parent (earlier in the list) and its transform relative to it at
/// rest, as a matrix and as the translation, rotation and scale that channels replace. glTF requires
/// animated nodes to be given as those, so they are kept as given: a scale of 0 at rest (a part that
/// grows in) cannot be recovered from its matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    pub parent: Option<usize>,
    pub rest: Mat4,
    pub rest_trs: Trs,
}

/// A transform as translation, rotation and scale, applied scale first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Trs {
    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

impl Node {
    /// A node given by its translation, rotation and scale.
    pub fn from_trs(parent: Option<usize>, trs: Trs) -> Self {
        Self { parent, rest: trs.matrix(), rest_trs: trs }
    }
}

/// A scene's node animation. Nodes are listed parents first; only instances under an animated node
/// move.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    pub name: String,
    pub nodes: Vec<Node>,
    pub channels: Vec<Channel>,
    /// Each moving mesh instance (index into `Scene::instances`) and the node it is placed by.
    pub instances: Vec<(usize, usize)>,
    /// The last keyframe's time: the animation loops over it.
    pub duration: f32,
}

impl Channel {
    /// The channel's value at `time` (clamped to its keyframes; a time that is not a number gives the
    /// first keyframe's value).
    pub fn sample(&self, time: f32) -> Vec4 {
        let keys = &self.times;
        let value = |k: usize| match self.interpolation {
            Interpolation::CubicSpline => self.values[3 * k + 1],
            _ => self.values[k],
        };
        if keys.len() == 1 || time <= keys[0] || time.is_nan() {
            return value(0);
        }
        let last = keys.len() - 1;
        if time >= keys[last] {
            return value(last);
        }
        // The keyframe interval [k, k + 1) holding the time.
        let k = keys.partition_point(|&t| t <= time) - 1;
        let interval = keys[k + 1] - keys[k];
        let s = (time - keys[k]) / interval;
        let rotation = self.property == Property::Rotation;
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear if rotation => Quat::from_vec4(value(k)).slerp(Quat::from_vec4(value(k + 1)), s).into(),
            Interpolation::Linear => value(k).lerp(value(k + 1), s),
            Interpolation::CubicSpline => {
                let (p0, m0) = (value(k), self.values[3 * k + 2] * interval);
                let (p1, m1) = (value(k + 1), self.values[3 * (k + 1)] * interval);
                let (s2, s3) = (s * s, s * s * s);
                let v = p0 * (2.0 * s3 - 3.0 * s2 + 1.0) + m0 * (s3 - 2.0 * s2 + s) + p1 * (-2.0 * s3 + 3.0 * s2) + m1 * (s3 - s2);
                if rotation {
                    v.normalize()
                } else {
                    v
                }
            }
        }
    }
}

impl Animation {
    /// The transform of every moving instance at `time` seconds (looping; a time that is not finite
    /// is the start), as (instance, world from local).
    pub fn instance_transforms(&self, time: f32) -> Vec<(usize, Mat4)> {
        let world = self.node_worlds(self.looped(time));
        self.instances.iter().map(|&(instance, node)| (instance, world[node])).collect()
    }

    /// `time` within the loop: seconds from its start (0 for a time that is not finite).
    pub fn looped(&self, time: f32) -> f32 {
        if self.duration > 0.0 && time.is_finite() {
            time.rem_euclid(self.duration)
        } else {
            0.0
        }
    }

    /// Every node's world matrix at `time` seconds into the loop.
    pub fn node_worlds(&self, time: f32) -> Vec<Mat4> {
        let mut locals: Vec<Mat4> = self.nodes.iter().map(|n| n.rest).collect();
        let mut animated: Vec<Option<Trs>> = vec![None; self.nodes.len()];
        for channel in &self.channels {
            let v = channel.sample(time);
            let trs = animated[channel.node].get_or_insert(self.nodes[channel.node].rest_trs);
            match channel.property {
                Property::Translation => trs.translation = v.truncate(),
                Property::Rotation => trs.rotation = Quat::from_vec4(v).normalize(),
                Property::Scale => trs.scale = v.truncate(),
            }
        }
        for (local, trs) in locals.iter_mut().zip(&animated) {
            if let Some(trs) = trs {
                *local = trs.matrix();
            }
        }
        let mut world: Vec<Mat4> = Vec::with_capacity(self.nodes.len());
        for (node, local) in self.nodes.iter().zip(&locals) {
            world.push(node.parent.map_or(*local, |p| world[p] * *local));
        }
        world
    }

    /// Whether the loop starts over after `earlier` and by `later` (seconds): poses across it are not a
    /// motion.
    pub fn loops_between(&self, earlier: f32, later: f32) -> bool {
        self.duration > 0.0 && (earlier / self.duration).floor() != (later / self.duration).floor()
    }

    /// Checks indices and numbers; the message names the bad channel or node.
    pub fn validate(&self, instance_count: usize) -> Result<(), String> {
        for (i, node) in self.nodes.iter().enumerate() {
            if node.parent.is_some_and(|p| p >= i) {
                return Err(format!("animation node {i}: its parent must come before it"));
            }
            let trs = &node.rest_trs;
            if !(node.rest.is_finite() && trs.translation.is_finite() && trs.rotation.is_finite() && trs.scale.is_finite()) {
                return Err(format!("animation node {i}: its transform is NaN or infinite"));
            }
        }
        for (c, channel) in self.channels.iter().enumerate() {
            let per_key = if channel.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
            if channel.node >= self.nodes.len() {
                return Err(format!("animation channel {c}: node {} does not exist", channel.node));
            }
            if channel.times.is_empty() || channel.values.len() != per_key * channel.times.len() {
                return Err(format!(
                    "animation channel {c}: {} keyframe times for {} values ({per_key} per keyframe)",
                    channel.times.len(),
                    channel.values.len()
                ));
            }
            if !channel.times.iter().all(|t| t.is_finite()) || channel.times.windows(2).any(|w| w[1] <= w[0]) {
                return Err(format!("animation channel {c}: keyframe times must be finite and increasing"));
            }
            if !channel.values.iter().all(|v| v.is_finite()) {
                return Err(format!("animation channel {c}: a keyframe value is NaN or infinite"));
            }
            // Tangents of cubic splines may be zero; rotation values may not.
            let value_keys = channel.values.iter().skip(per_key / 3).step_by(per_key);
            if channel.property == Property::Rotation && value_keys.clone().any(|q| q.length_squared() < 1e-12) {
                return Err(format!("animation channel {c}: a rotation keyframe is a zero-length quaternion, which is no rotation"));
            }
        }
        if let Some(&(instance, node)) = self.instances.iter().find(|&&(i, n)| i >= instance_count || n >= self.nodes.len()) {
            return Err(format!("animated instance {instance} (node {node}) does not exist"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(property: Property, interpolation: Interpolation, times: &[f32], values: &[Vec4]) -> Channel {
        Channel { node: 0, property, interpolation, times: times.to_vec(), values: values.to_vec() }
    }

    #[test]
    fn samplers_interpolate_as_gltf_defines() {
        let (a, b) = (Vec4::new(0.0, 0.0, 0.0, 0.0), Vec4::new(2.0, 4.0, 6.0, 0.0));
        let linear = channel(Property::Translation, Interpolation::Linear, &[1.0, 3.0], &[a, b]);
        assert_eq!(linear.sample(0.0), a, "clamped before the first key");
        assert_eq!(linear.sample(2.0), Vec4::new(1.0, 2.0, 3.0, 0.0));
        assert_eq!(linear.sample(5.0), b, "clamped after the last key");
        let step = channel(Property::Translation, Interpolation::Step, &[1.0, 3.0], &[a, b]);
        assert_eq!(step.sample(2.9), a);
        assert_eq!(step.sample(3.0), b);
        // A quarter turn about Y, halfway: an eighth, by slerp (not a normalised lerp of the ends).
        let turn = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let rotation = channel(Property::Rotation, Interpolation::Linear, &[0.0, 1.0], &[Quat::IDENTITY.into(), turn.into()]);
        let half = Quat::from_vec4(rotation.sample(0.25));
        assert!(half.angle_between(Quat::from_rotation_y(std::f32::consts::FRAC_PI_8)) < 1e-5, "{half}");
        // Cubic Hermite with zero tangents eases: at a quarter of the interval, 3s² − 2s³ of the way.
        let zero = Vec4::ZERO;
        let cubic = channel(Property::Scale, Interpolation::CubicSpline, &[0.0, 2.0], &[zero, a, zero, zero, b, zero]);
        let s: f32 = 0.25;
        assert!((cubic.sample(0.5) - b * (3.0 * s * s - 2.0 * s * s * s)).length() < 1e-6);
        // Tangents are per second: a constant slope of 1 per second over 2 s reproduces a line.
        let slope = Vec4::new(1.0, 1.0, 1.0, 0.0);
        let line =
            channel(Property::Translation, Interpolation::CubicSpline, &[0.0, 2.0], &[slope, zero, slope, slope, slope * 2.0, slope]);
        assert!((line.sample(0.5) - slope * 0.5).length() < 1e-6);
    }

    #[test]
    fn instances_follow_their_node_and_its_parents_and_the_animation_loops() {
        let node = |parent, translation| Node::from_trs(parent, Trs { translation, rotation: Quat::IDENTITY, scale: Vec3::ONE });
        let animation = Animation {
            name: "test".into(),
            nodes: vec![node(None, Vec3::ZERO), node(Some(0), Vec3::new(1.0, 0.0, 0.0))],
            channels: vec![Channel {
                node: 0,
                property: Property::Rotation,
                interpolation: Interpolation::Linear,
                times: vec![0.0, 4.0],
                values: vec![Quat::IDENTITY.into(), Quat::from_rotation_y(std::f32::consts::FRAC_PI_2).into()],
            }],
            instances: vec![(3, 1)],
            duration: 4.0,
        };
        animation.validate(4).unwrap();
        // At 2 s the parent has turned an eighth about Y: the child's (1, 0, 0) goes to (c, 0, -c).
        let [(instance, world)] = animation.instance_transforms(2.0)[..] else { panic!() };
        assert_eq!(instance, 3);
        let c = std::f32::consts::FRAC_1_SQRT_2;
        assert!((world.transform_point3(Vec3::ZERO) - Vec3::new(c, 0.0, -c)).length() < 1e-6);
        let looped = animation.instance_transforms(6.0)[0].1;
        assert!(looped.abs_diff_eq(world, 1e-6), "the animation loops over its duration");
        let bad = Animation { instances: vec![(9, 1)], ..animation.clone() };
        assert!(bad.validate(4).unwrap_err().contains("instance 9"));
        let backwards = Animation { nodes: vec![node(Some(1), Vec3::ZERO), node(None, Vec3::ZERO)], ..animation };
        assert!(backwards.validate(4).unwrap_err().contains("parent"));
    }

    #[test]
    fn a_node_flat_at_rest_grows_and_bad_times_and_keys_are_handled() {
        // Scale 0 at rest: its matrix has no rotation to recover, so the channel starts from the
        // node's own decomposition.
        let rotation = Quat::from_rotation_z(0.5);
        let rest = Trs { translation: Vec3::new(1.0, 2.0, 3.0), rotation, scale: Vec3::ZERO };
        let grow = Channel {
            node: 0,
            property: Property::Scale,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: vec![Vec4::ZERO, Vec4::new(2.0, 2.0, 2.0, 0.0)],
        };
        let animation = Animation {
            name: "grow".into(),
            nodes: vec![Node::from_trs(None, rest)],
            channels: vec![grow],
            instances: vec![(0, 0)],
            duration: 1.0,
        };
        animation.validate(1).unwrap();
        let world = animation.instance_transforms(0.5)[0].1;
        let expected = Trs { scale: Vec3::ONE, ..rest }.matrix();
        assert!(world.abs_diff_eq(expected, 1e-6), "{world} != {expected}");
        // Times that are not finite sample the start instead of panicking.
        for time in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert!(animation.instance_transforms(time)[0].1.is_finite());
            assert!(animation.channels[0].sample(time).is_finite());
        }
        let zero_rotation = Channel {
            node: 0,
            property: Property::Rotation,
            interpolation: Interpolation::Step,
            times: vec![0.0],
            values: vec![Vec4::ZERO],
        };
        let bad = Animation { channels: vec![zero_rotation], ..animation };
        assert!(bad.validate(1).unwrap_err().contains("zero-length quaternion"));
    }
}
