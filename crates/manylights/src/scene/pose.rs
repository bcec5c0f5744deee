//! Skinned and morphed meshes (glTF skins and morph targets), posed at the animation's time every
//! frame on the GPU (`passes/deform.wgsl`) for the raster and the rays alike. This CPU twin is the
//! tests' reference and bounds the posed mesh for the rays' top level.
//!
//! As glTF defines: morph targets add their weighted offsets to the vertex at rest, then the skin
//! blends its joints' matrices (joint world × inverse bind) by the vertex's weights. A skinned mesh is
//! posed in world space (its own node's transform is ignored); a mesh only morphed stays in its
//! node's space.

use super::{aabb::Aabb, animation::Interpolation, Vertex};
use glam::{Mat3, Mat4, Vec3, Vec4};

/// One morph target's offsets of one vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MorphOffset {
    pub position: Vec3,
    pub normal: Vec3,
    pub tangent: Vec3,
}

/// Keyframed morph weights: each keyframe holds one weight per target (three per target for cubic
/// splines: in-tangents, values, out-tangents, each a run of `targets`).
#[derive(Clone, Debug, PartialEq)]
pub struct WeightKeys {
    pub interpolation: Interpolation,
    pub times: Vec<f32>,
    pub values: Vec<f32>,
}

/// A skin: its joints (indices into `Animation::nodes`), each with the inverse bind matrix taking the
/// mesh's space to the joint's at bind time, and every vertex's influences.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    pub joints: Vec<usize>,
    pub inverse_bind: Vec<Mat4>,
    /// Influences per vertex: `sets` runs of four (joint, weight), vertex after vertex (glTF's
    /// JOINTS_n / WEIGHTS_n), weights summing to 1.
    pub sets: usize,
    pub joint_indices: Vec<[u32; 4]>,
    pub weights: Vec<[f32; 4]>,
}

/// What poses one mesh: morph targets (each a run of offsets, one per vertex of the mesh, primitive
/// after primitive), their weights, and a skin.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    pub targets: Vec<Vec<MorphOffset>>,
    /// The weights without animation (the node's or the mesh's).
    pub rest_weights: Vec<f32>,
    pub weight_keys: Option<WeightKeys>,
    pub skin: Option<Skin>,
}

/// What the frame poses a mesh with: the morph weights and each joint's skinning matrix.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoseState {
    pub weights: Vec<f32>,
    pub joints: Vec<Mat4>,
}

impl Pose {
    /// The morph weights at `time` (seconds into the animation, already looped).
    pub fn weights_at(&self, time: f32) -> Vec<f32> {
        let Some(keys) = &self.weight_keys else { return self.rest_weights.clone() };
        let n = self.targets.len();
        let cubic = keys.interpolation == Interpolation::CubicSpline;
        // Keyframe k's run `part` (0 in-tangent, 1 value, 2 out-tangent for cubic splines).
        let run = |k: usize, part: usize| {
            let start = if cubic { (3 * k + part) * n } else { k * n };
            &keys.values[start..start + n]
        };
        let value = |k: usize| run(k, 1).to_vec();
        let times = &keys.times;
        let last = times.len() - 1;
        if times.len() == 1 || time <= times[0] || time.is_nan() {
            return value(0);
        }
        if time >= times[last] {
            return value(last);
        }
        let k = times.partition_point(|&t| t <= time) - 1;
        let interval = times[k + 1] - times[k];
        let s = (time - times[k]) / interval;
        match keys.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear => run(k, 0).iter().zip(run(k + 1, 0)).map(|(a, b)| a + (b - a) * s).collect(),
            Interpolation::CubicSpline => {
                let (s2, s3) = (s * s, s * s * s);
                let (h00, h10, h01, h11) = (2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2);
                (0..n)
                    .map(|i| {
                        let (p0, m0) = (run(k, 1)[i], run(k, 2)[i] * interval);
                        let (p1, m1) = (run(k + 1, 1)[i], run(k + 1, 0)[i] * interval);
                        p0 * h00 + m0 * h10 + p1 * h01 + m1 * h11
                    })
                    .collect()
            }
        }
    }

    /// The frame's state at `time` (looped), from the animation's node world matrices at that time.
    pub fn state(&self, time: f32, node_worlds: &[Mat4]) -> PoseState {
        let joints = self.skin.as_ref().map_or_else(Vec::new, |skin| {
            skin.joints.iter().zip(&skin.inverse_bind).map(|(&node, inverse_bind)| node_worlds[node] * *inverse_bind).collect()
        });
        PoseState { weights: self.weights_at(time), joints }
    }

    /// Vertex `index` of the mesh (`rest` at rest) posed by `state`.
    pub fn pose_vertex(&self, index: usize, rest: &Vertex, state: &PoseState) -> Vertex {
        let mut position = Vec3::from(rest.position);
        let mut normal = Vec3::from(rest.normal);
        let mut tangent = Vec4::from(rest.tangent);
        for (target, &w) in self.targets.iter().zip(&state.weights) {
            let offset = target[index];
            position += offset.position * w;
            normal += offset.normal * w;
            tangent += (offset.tangent * w).extend(0.0);
        }
        if let Some(skin) = &self.skin {
            let mut m = Mat4::ZERO;
            for set in 0..skin.sets {
                let (joints, weights) = (skin.joint_indices[index * skin.sets + set], skin.weights[index * skin.sets + set]);
                for (j, w) in joints.iter().zip(weights) {
                    if w != 0.0 {
                        m += state.joints[*j as usize] * w;
                    }
                }
            }
            // A mirroring blend (negative determinant) turns the cofactor's normal around and the
            // tangent frame's handedness over.
            let mirrored = Mat3::from_mat4(m).determinant() < 0.0;
            let flip = if mirrored { -1.0 } else { 1.0 };
            position = m.transform_point3(position);
            normal = normal_matrix(m) * normal * flip;
            tangent = (m.transform_vector3(tangent.truncate())).extend(tangent.w * flip);
        }
        let normal = normal.normalize_or(Vec3::from(rest.normal));
        let tangent = tangent.truncate().normalize_or(Vec3::from_slice(&rest.tangent[..3])).extend(tangent.w);
        Vertex { position: position.into(), normal: normal.into(), tangent: tangent.into(), ..*rest }
    }

    /// A box holding the mesh posed by `state`, from `bounds` (`PoseBounds::of` the same mesh): each
    /// joint's box of the vertices it moves, grown by the morph offsets' reach and taken through its
    /// matrix. A skinned vertex is a weighted mean of its joints' images, so it lies in their union's
    /// box; without a skin, the rest box grown.
    pub fn bounds(&self, bounds: &PoseBounds, state: &PoseState) -> Aabb {
        let reach: Vec3 = bounds.reach.iter().zip(&state.weights).map(|(r, w)| *r * w.abs()).sum();
        let grow = |b: &Aabb| Aabb::new(b.min - reach, b.max + reach);
        if self.skin.is_none() {
            return grow(&bounds.rest);
        }
        let mut posed = Aabb::EMPTY;
        for (joint, b) in state.joints.iter().zip(&bounds.joints).filter(|(_, b)| !b.is_empty()) {
            posed = posed.union(grow(b).transformed(&glam::Affine3A::from_mat4(*joint)));
        }
        // Vertices whose weights are all zero collapse to the origin.
        if bounds.unweighted {
            posed.grow_point(Vec3::ZERO);
        }
        // Room for the GPU's rounding of the blended matrices.
        let pad = Vec3::splat(1e-5 * posed.diagonal().max(posed.min.abs().max(posed.max.abs()).max_element()));
        Aabb::new(posed.min - pad, posed.max + pad)
    }

    /// Checks sizes and numbers against the mesh's `vertex_count` and the animation's `node_count`.
    pub fn validate(&self, vertex_count: usize, node_count: usize) -> Result<(), String> {
        if let Some(t) = self.targets.iter().position(|t| t.len() != vertex_count) {
            return Err(format!("morph target {t} has {} offsets for {vertex_count} vertices", self.targets[t].len()));
        }
        if self.rest_weights.len() != self.targets.len() || !self.rest_weights.iter().all(|w| w.is_finite()) {
            return Err(format!("{} morph weights for {} targets, or one is not finite", self.rest_weights.len(), self.targets.len()));
        }
        if let Some(keys) = &self.weight_keys {
            let per_key = self.targets.len() * if keys.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
            if keys.times.is_empty() || keys.values.len() != per_key * keys.times.len() {
                return Err(format!(
                    "{} morph weight keyframes for {} values ({per_key} per keyframe)",
                    keys.times.len(),
                    keys.values.len()
                ));
            }
            if !keys.times.iter().all(|t| t.is_finite()) || keys.times.windows(2).any(|w| w[1] <= w[0]) {
                return Err("morph weight keyframe times must be finite and increasing".into());
            }
            if !keys.values.iter().all(|v| v.is_finite()) {
                return Err("a morph weight keyframe is NaN or infinite".into());
            }
        }
        if let Some(skin) = &self.skin {
            if skin.joints.is_empty() || skin.inverse_bind.len() != skin.joints.len() {
                return Err(format!("skin has {} joints and {} inverse bind matrices", skin.joints.len(), skin.inverse_bind.len()));
            }
            if let Some(&node) = skin.joints.iter().find(|&&n| n >= node_count) {
                return Err(format!("skin joint node {node} is not in the animation's {node_count} nodes"));
            }
            if !skin.inverse_bind.iter().all(Mat4::is_finite) {
                return Err("an inverse bind matrix is NaN or infinite".into());
            }
            let influences = vertex_count * skin.sets;
            if skin.sets == 0 || skin.joint_indices.len() != influences || skin.weights.len() != influences {
                return Err(format!("skin influences are not {} sets of four per vertex", skin.sets));
            }
            if let Some(&bad) = skin.joint_indices.iter().flatten().find(|&&j| j as usize >= skin.joints.len()) {
                return Err(format!("a vertex names joint {bad} of a skin with {}", skin.joints.len()));
            }
            if !skin.weights.iter().flatten().all(|w| w.is_finite() && *w >= 0.0) {
                return Err("a skin weight is negative, NaN or infinite".into());
            }
            // A vertex is a weighted mean of its joints' images, inside their boxes (`bounds`), only
            // where its weights sum to 1 (within the rounding `bounds` pads for).
            let sums = skin.weights.chunks(skin.sets).map(|vertex| vertex.iter().flatten().sum::<f32>());
            if let Some((v, sum)) = sums.enumerate().find(|(_, sum)| *sum != 0.0 && (sum - 1.0).abs() > 1e-6) {
                return Err(format!("vertex {v}'s skin weights sum to {sum}; normalise them to sum to 1 (or make them all 0)"));
            }
        }
        Ok(())
    }
}

/// What bounds a posed mesh, measured at load: the rest box, each joint's box of the vertices it
/// moves (empty for none), whether some vertex has no weight, and each target's largest offset per
/// axis.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseBounds {
    pub rest: Aabb,
    pub joints: Vec<Aabb>,
    pub unweighted: bool,
    pub reach: Vec<Vec3>,
}

impl PoseBounds {
    pub fn of(pose: &Pose, vertices: &[Vertex]) -> Self {
        let mut rest = Aabb::EMPTY;
        for v in vertices {
            rest.grow_point(Vec3::from(v.position));
        }
        let reach = pose.targets.iter().map(|t| t.iter().fold(Vec3::ZERO, |r, o| r.max(o.position.abs()))).collect();
        let mut joints = Vec::new();
        let mut unweighted = false;
        if let Some(skin) = &pose.skin {
            joints = vec![Aabb::EMPTY; skin.joints.len()];
            for (i, v) in vertices.iter().enumerate() {
                let mut total = 0.0;
                for set in 0..skin.sets {
                    let (js, ws) = (skin.joint_indices[i * skin.sets + set], skin.weights[i * skin.sets + set]);
                    for (j, w) in js.iter().zip(ws).filter(|(_, w)| *w != 0.0) {
                        joints[*j as usize].grow_point(Vec3::from(v.position));
                        total += w.abs();
                    }
                }
                unweighted |= total == 0.0;
            }
        }
        Self { rest, joints, unweighted, reach }
    }
}

/// Normals go through the inverse transpose of a matrix's upper 3×3; its cofactor matrix is that up
/// to scale, and exists for singular matrices too.
pub fn normal_matrix(m: Mat4) -> Mat3 {
    let a = Mat3::from_mat4(m);
    Mat3::from_cols(a.y_axis.cross(a.z_axis), a.z_axis.cross(a.x_axis), a.x_axis.cross(a.y_axis))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    fn vertex(position: Vec3) -> Vertex {
        Vertex { position: position.into(), normal: [0.0, 1.0, 0.0], tangent: [1.0, 0.0, 0.0, 1.0], ..Vertex::default() }
    }

    #[test]
    fn morph_targets_add_weighted_offsets_and_skins_blend_their_joints() {
        let up = MorphOffset { position: Vec3::Y, ..Default::default() };
        let rest = [vertex(Vec3::ZERO), vertex(Vec3::X)];
        let pose = Pose {
            targets: vec![vec![up, MorphOffset::default()]],
            rest_weights: vec![0.0],
            weight_keys: Some(WeightKeys { interpolation: Interpolation::Linear, times: vec![0.0, 2.0], values: vec![0.0, 1.0] }),
            skin: Some(Skin {
                joints: vec![0, 1],
                inverse_bind: vec![Mat4::IDENTITY; 2],
                sets: 1,
                joint_indices: vec![[0, 1, 0, 0], [1, 0, 0, 0]],
                weights: vec![[0.5, 0.5, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]],
            }),
        };
        pose.validate(2, 2).unwrap();
        // Joint 1 moved up by 2 and turned a quarter about Z.
        let turned = Mat4::from_rotation_translation(Quat::from_rotation_z(std::f32::consts::FRAC_PI_2), Vec3::new(0.0, 2.0, 0.0));
        let state = pose.state(1.0, &[Mat4::IDENTITY, turned]);
        assert_eq!(state.weights, vec![0.5]);
        // Vertex 0 morphed to (0, 0.5, 0), then half at rest and half through joint 1: (−0.25, 1.25, 0).
        let v0 = pose.pose_vertex(0, &rest[0], &state);
        assert!((Vec3::from(v0.position) - Vec3::new(-0.25, 1.25, 0.0)).length() < 1e-6, "{:?}", v0.position);
        let v1 = pose.pose_vertex(1, &rest[1], &state);
        assert!((Vec3::from(v1.position) - Vec3::new(0.0, 3.0, 0.0)).length() < 1e-6);
        assert!((Vec3::from(v1.normal) - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-6, "normals turn with the joint");
        let bounds = PoseBounds::of(&pose, &rest);
        let posed = pose.bounds(&bounds, &state);
        for v in [v0, v1] {
            assert!(posed.contains(Vec3::from(v.position)), "{posed:?} misses {:?}", v.position);
        }
        let bad = Pose { rest_weights: vec![], ..pose.clone() };
        assert!(bad.validate(2, 2).unwrap_err().contains("morph weights"));
        let reweighted = |weights: [f32; 4]| {
            let mut skin = pose.skin.clone().unwrap();
            skin.weights[1] = weights;
            Pose { skin: Some(skin), ..pose.clone() }.validate(2, 2)
        };
        assert!(reweighted([1.5, -0.5, 0.0, 0.0]).unwrap_err().contains("negative"));
        assert!(reweighted([0.5, 0.25, 0.0, 0.0]).unwrap_err().contains("sum to 0.75"));
        assert!(reweighted([0.0; 4]).is_ok() && reweighted([0.25, 0.75, 0.0, 0.0]).is_ok());
        assert!(pose.validate(2, 1).unwrap_err().contains("joint node 1"));
    }

    #[test]
    fn a_mirroring_joint_mirrors_normals_and_the_tangent_frame() {
        let skin = Skin {
            joints: vec![0],
            inverse_bind: vec![Mat4::IDENTITY],
            sets: 1,
            joint_indices: vec![[0; 4]],
            weights: vec![[1.0, 0.0, 0.0, 0.0]],
        };
        let pose = Pose { targets: Vec::new(), rest_weights: Vec::new(), weight_keys: None, skin: Some(skin) };
        let rest = Vertex { position: [1.0, 2.0, 3.0], normal: [1.0, 0.0, 0.0], tangent: [0.0, 1.0, 0.0, 1.0], ..Vertex::default() };
        let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let posed = pose.pose_vertex(0, &rest, &pose.state(0.0, &[mirror]));
        assert_eq!(posed.position, [-1.0, 2.0, 3.0]);
        assert_eq!(posed.normal, [-1.0, 0.0, 0.0], "the normal is mirrored with the surface");
        assert_eq!(posed.tangent, [0.0, 1.0, 0.0, -1.0], "the bitangent's handedness flips");
    }

    #[test]
    fn cubic_and_step_weights_follow_the_samplers() {
        let step = WeightKeys { interpolation: Interpolation::Step, times: vec![0.0, 1.0], values: vec![0.0, 1.0, 1.0, 0.0] };
        let pose = Pose { targets: vec![vec![], vec![]], rest_weights: vec![0.0, 0.0], weight_keys: Some(step), skin: None };
        assert_eq!(pose.weights_at(0.5), vec![0.0, 1.0]);
        assert_eq!(pose.weights_at(1.0), vec![1.0, 0.0]);
        // Zero tangents: 3s² − 2s³ of the way at s = 0.25.
        let cubic = WeightKeys {
            interpolation: Interpolation::CubicSpline,
            times: vec![0.0, 1.0],
            values: vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 0.0, 0.0],
        };
        let pose = Pose { weight_keys: Some(cubic), ..pose };
        let w = pose.weights_at(0.25);
        let e = 3.0 * 0.0625 - 2.0 * 0.015625;
        assert!((w[0] - e).abs() < 1e-6 && (w[1] - 2.0 * e).abs() < 1e-6, "{w:?}");
    }
}
