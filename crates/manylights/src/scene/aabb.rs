//! Axis-aligned boxes: scene bounds and the volumes of the acceleration structures.

use glam::{Affine3A, Mat4, Vec3, Vec4};

/// An axis-aligned box, closed on all faces. A box with `min > max` on some axis is empty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    /// The empty box: the identity of [`Aabb::union`] and [`Aabb::grow_point`]; it contains nothing.
    pub const EMPTY: Aabb = Aabb { min: Vec3::splat(f32::INFINITY), max: Vec3::splat(f32::NEG_INFINITY) };

    pub fn new(min: Vec3, max: Vec3) -> Aabb {
        Aabb { min, max }
    }

    /// Extends the box to contain `p`.
    pub fn grow_point(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The smallest box containing both.
    pub fn union(self, other: Aabb) -> Aabb {
        Aabb { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    /// The box around this box's image under `transform` (empty stays empty), widened by a few ulps
    /// so that points transformed the other way with rounding still land inside.
    pub fn transformed(&self, transform: &Affine3A) -> Aabb {
        if self.is_empty() {
            return Aabb::EMPTY;
        }
        let centre = transform.transform_point3(self.center());
        let m = transform.matrix3;
        let half = (self.max - self.min) * 0.5;
        let extent = m.x_axis.abs() * half.x + m.y_axis.abs() * half.y + m.z_axis.abs() * half.z;
        let pad = 8.0 * f32::EPSILON * (centre.abs() + Vec3::from(extent));
        Aabb::new(centre - Vec3::from(extent) - pad, centre + Vec3::from(extent) + pad)
    }

    /// Inclusive on every face (`min ≤ p ≤ max`), as the GPU query tests, so a point on a shared face
    /// or a flat box's plane is found.
    pub fn contains(&self, p: Vec3) -> bool {
        self.min.cmple(p).all() && p.cmple(self.max).all()
    }

    /// Whether `other` lies inside this box (faces may touch).
    pub fn contains_box(&self, other: &Aabb) -> bool {
        self.min.cmple(other.min).all() && other.max.cmple(self.max).all()
    }

    /// No NaN or infinite bound.
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// Finite and non-empty (`min ≤ max` on every axis; zero thickness is allowed): what the BVH
    /// builder accepts.
    pub fn is_valid(&self) -> bool {
        self.is_finite() && self.min.cmple(self.max).all()
    }

    /// True when `min > max` on some axis, like `EMPTY`.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    pub fn diagonal(&self) -> f32 {
        (self.max - self.min).length()
    }

    /// Computed as `min / 2 + max / 2` so that boxes near `f32::MAX` do not overflow.
    pub fn center(&self) -> Vec3 {
        self.min * 0.5 + self.max * 0.5
    }

    /// Whether the box lies wholly outside the view of `clip_from_world` (reverse-Z, any far plane):
    /// past one of its side planes or behind its near plane. Boxes it cannot tell (straddling a
    /// corner's two planes) count as inside, so this only ever errs towards drawing.
    pub fn outside_view(&self, clip_from_world: &Mat4) -> bool {
        let [x, y, z, w] = [0, 1, 2, 3].map(|i| clip_from_world.row(i));
        // Inside where each plane · (p, 1) ≥ 0: −w ≤ x ≤ w, −w ≤ y ≤ w, z ≤ w (the near plane).
        let planes: [Vec4; 5] = [w + x, w - x, w + y, w - y, w - z];
        planes.iter().any(|plane| {
            let normal = plane.truncate();
            // The corner furthest along the plane's normal.
            let corner = Vec3::select(normal.cmpge(Vec3::ZERO), self.max, self.min);
            normal.dot(corner) + plane.w < 0.0
        })
    }

    /// Surface area in f64: the SAH compares areas of boxes from 1e-30 to 1e30 in size, whose squares
    /// underflow or overflow f32. Zero for an invalid box.
    pub fn surface_area(&self) -> f64 {
        if !self.is_valid() {
            return 0.0;
        }
        let e = self.max.as_dvec3() - self.min.as_dvec3();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Projection};

    #[test]
    fn boxes_wholly_outside_the_view_and_only_those_are_outside_it() {
        // From 5 m up +z, looking down −z with a 60° vertical field of view over a square image:
        // the view spans ±tan 30° × distance on both axes (boxes are 1 m deep: their far face
        // reaches 0.29 m further out); with a far plane too, and orthographic, as wide at 5 m.
        let camera = Camera::look_at("test", Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, 60f32.to_radians(), 0.1);
        let edge = 5.0 * 30f32.to_radians().tan();
        let far =
            Camera { projection: Projection::Perspective { yfov: 60f32.to_radians(), znear: 0.1, zfar: Some(1.0e5) }, ..camera.clone() };
        let orthographic = Camera {
            projection: Projection::Orthographic { xmag: edge + 0.29, ymag: edge + 0.29, znear: 0.1, zfar: 1.0e5 },
            ..camera.clone()
        };
        for camera in [camera, far, orthographic] {
            check_view(&camera, edge);
        }
    }

    fn check_view(camera: &Camera, edge: f32) {
        let view = camera.clip_from_world(100, 100);
        let at = |centre: Vec3, half: f32| Aabb::new(centre - half, centre + half);
        for (name, b) in [
            ("at the centre", at(Vec3::ZERO, 0.5)),
            ("straddling the right edge", at(Vec3::new(edge + 0.4, 0.0, 0.0), 0.5)),
            ("straddling a corner", at(Vec3::new(edge + 0.3, edge + 0.3, 0.0), 0.5)),
            ("around the eye", at(Vec3::new(0.0, 0.0, 5.0), 1.0)),
            ("far away ahead", at(Vec3::new(0.0, 0.0, -1.0e4), 1.0)),
            ("a huge box behind and ahead", Aabb::new(Vec3::splat(-1.0e3), Vec3::splat(1.0e3))),
        ] {
            assert!(!b.outside_view(&view), "{:?}: {name}", camera.projection);
        }
        for (name, b) in [
            ("right of the view", at(Vec3::new(edge + 1.0, 0.0, 0.0), 0.5)),
            ("left of it", at(Vec3::new(-edge - 1.0, 0.0, 0.0), 0.5)),
            ("above it", at(Vec3::new(0.0, edge + 1.0, 0.0), 0.5)),
            ("below it", at(Vec3::new(0.0, -edge - 1.0, 0.0), 0.5)),
            ("behind the eye", at(Vec3::new(0.0, 0.0, 7.0), 0.5)),
            ("between the eye and the near plane", at(Vec3::new(0.0, 0.0, 4.95), 0.01)),
        ] {
            assert!(b.outside_view(&view), "{:?}: {name}", camera.projection);
        }
    }
}
