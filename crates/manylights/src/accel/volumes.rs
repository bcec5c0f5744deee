//! The volumes of influence of lights and decals and their boxes.
//!
//! A light's volume is the set of points it can light: the sphere of its `range` (the shader gives no
//! light at or beyond it) and, for a spot, the part of it inside the outer cone. [`light_aabb`] bounds
//! that volume for the BVH and [`light_contains`] is the exact test run on each AABB hit, so the pair
//! must agree: every point that passes [`light_contains`] lies in [`light_aabb`].

use glam::{Vec3, Vec3Swizzles};

pub use crate::scene::Aabb;
use crate::scene::{Decal, Light, LightKind};

/// The unit axis a spot points along, as the GPU uploads it (`GpuLight` normalises it too).
fn spot_axis(light: &Light) -> Vec3 {
    light.direction.normalize_or_zero()
}

/// A tight box around the light's volume: the sphere's box for a point light, the box of the
/// spherical sector (sphere ∩ outer cone) for a spot, which for narrow cones is far smaller.
///
/// The box is widened on each axis by a few f32 ulps of `|position| + range` so that it also contains
/// points that [`light_contains`] accepts only through rounding (without it, points on the rim of
/// far-away spots fall outside): the BVH query must never miss a light the exact test would keep.
pub fn light_aabb(light: &Light) -> Aabb {
    let p = light.position;
    let r = light.range;
    let tight = match light.kind {
        LightKind::Point => Aabb::new(p - Vec3::splat(r), p + Vec3::splat(r)),
        LightKind::Spot { outer_cone_angle, .. } => {
            let d = spot_axis(light);
            let (sin, cos) = outer_cone_angle.sin_cos();
            // The sector's extremes along each axis lie at the apex, on the rim of its spherical cap (a
            // circle of radius r·sinθ around p + d·r·cosθ, in the plane ⟂ d, whose extent along axis
            // a is r·sinθ·sqrt(1 − d_a²)), or at the cap's point furthest along ±a when that point is
            // on the cap, i.e. when ±a is within θ of d. sqrt(1 − d_a²) is computed as the length of d's
            // other two components: 1 − d_a² cancels catastrophically for spots close to an axis.
            let rim_center = p + d * (r * cos);
            let rim_extent = Vec3::new(d.yz().length(), d.xz().length(), d.xy().length()) * (r * sin);
            let mut b = Aabb::new(p, p).union(Aabb::new(rim_center - rim_extent, rim_center + rim_extent));
            for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                for e in [axis, -axis] {
                    if e.dot(d) >= cos {
                        b.grow_point(p + e * r);
                    }
                }
            }
            b
        }
    };
    let pad = 4.0 * f32::EPSILON * (p.abs() + Vec3::splat(r));
    Aabb::new(tight.min - pad, tight.max + pad)
}

/// The exact test behind [`light_aabb`]: whether `p` can receive light. Inside the sphere strictly
/// (`distance² < range²`, as the shader gives zero at `distance = range`) and, for a spot, within the
/// outer cone (the angle to the axis at most the outer angle; the apex counts as inside).
pub fn light_contains(light: &Light, p: Vec3) -> bool {
    let v = p - light.position;
    let distance_sq = v.length_squared();
    let in_sphere = distance_sq < light.range * light.range;
    match light.kind {
        LightKind::Point => in_sphere,
        LightKind::Spot { outer_cone_angle, .. } => in_sphere && v.dot(spot_axis(light)) >= outer_cone_angle.cos() * distance_sq.sqrt(),
    }
}

/// The box around a decal's oriented box, widened by a few ulps like [`light_aabb`] so that every
/// point [`decal_contains`] accepts is inside.
pub fn decal_aabb(decal: &Decal) -> Aabb {
    Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5)).transformed(&decal.world_from_decal)
}

/// The exact test behind [`decal_aabb`]: whether `p` lies in the decal's box (faces included).
/// The shader runs the same test in decal space (`shading/decals.wgsl`).
pub fn decal_contains(decal: &Decal, p: Vec3) -> bool {
    let local = decal.world_from_decal.inverse().transform_point3(p);
    local.abs().cmple(Vec3::splat(0.5)).all()
}

#[cfg(test)]
mod tests {
    use std::f32::consts::{FRAC_PI_2, PI};

    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    use super::*;

    #[test]
    fn decal_boxes_hold_their_oriented_boxes() {
        let mut rng = Pcg64::seed_from_u64(11);
        for _ in 0..200 {
            let rotation = glam::Quat::from_euler(
                glam::EulerRot::XYZ,
                rng.random::<f32>() * 6.3,
                rng.random::<f32>() * 6.3,
                rng.random::<f32>() * 6.3,
            );
            let scale = Vec3::new(rng.random_range(0.01..3.0), rng.random_range(0.01..3.0), rng.random_range(0.001..1.0));
            let centre = Vec3::new(rng.random_range(-1e3..1e3), rng.random_range(-1e3..1e3), rng.random_range(-1e3..1e3));
            let decal = Decal {
                world_from_decal: glam::Affine3A::from_scale_rotation_translation(scale, rotation, centre),
                material: 0,
                layer: 0,
                weight: 1.0,
            };
            let aabb = decal_aabb(&decal);
            for _ in 0..50 {
                // Points inside the box, including its faces and corners.
                let local = Vec3::new(rng.random_range(-0.5..=0.5), rng.random_range(-0.5..=0.5), rng.random_range(-0.5..=0.5));
                let snapped = local.map(|c| if c.abs() > 0.45 { 0.5f32.copysign(c) } else { c });
                for point in [local, snapped] {
                    let p = decal.world_from_decal.transform_point3(point);
                    if decal_contains(&decal, p) {
                        assert!(aabb.contains(p), "{p} passes the decal test but is outside {aabb:?}");
                    }
                }
            }
            assert!(decal_contains(&decal, centre));
            let outside = decal.world_from_decal.transform_point3(Vec3::new(0.0, 0.0, 0.6));
            assert!(!decal_contains(&decal, outside));
        }
    }

    fn spot(position: Vec3, direction: Vec3, outer: f32, range: f32) -> Light {
        Light {
            kind: LightKind::Spot { inner_cone_angle: outer * 0.5, outer_cone_angle: outer },
            position,
            direction: direction.normalize(),
            color: Vec3::ONE,
            intensity: 1.0,
            range,
            cast_shadows: false,
        }
    }

    fn point(position: Vec3, range: f32) -> Light {
        Light { kind: LightKind::Point, position, direction: Vec3::NEG_Z, color: Vec3::ONE, intensity: 1.0, range, cast_shadows: false }
    }

    fn random_unit(rng: &mut Pcg64) -> Vec3 {
        loop {
            let v = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let len_sq = v.length_squared();
            if len_sq > 1e-4 && len_sq <= 1.0 {
                return v / len_sq.sqrt();
            }
        }
    }

    fn volume(b: &Aabb) -> f32 {
        (b.max - b.min).element_product()
    }

    fn assert_close(actual: Aabb, expected: Aabb, tolerance: f32) {
        assert!(
            (actual.min - expected.min).abs().max_element() <= tolerance && (actual.max - expected.max).abs().max_element() <= tolerance,
            "{actual:?} != {expected:?}"
        );
    }

    #[test]
    fn aabb_basics() {
        let mut b = Aabb::EMPTY;
        assert!(!b.is_valid() && !b.contains(Vec3::ZERO) && b.surface_area() == 0.0);
        b.grow_point(Vec3::new(1.0, 2.0, 3.0));
        assert!(b.is_valid() && b.contains(Vec3::new(1.0, 2.0, 3.0)), "a single point is a valid, flat box");
        let b = b.union(Aabb::new(Vec3::ZERO, Vec3::ONE));
        assert_eq!(b, Aabb::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!(b.center(), Vec3::new(0.5, 1.0, 1.5));
        assert_eq!(b.surface_area(), 2.0 * (2.0 + 6.0 + 3.0));
        // Inclusive on faces and corners, exclusive just outside.
        assert!(b.contains(Vec3::ZERO) && b.contains(Vec3::new(1.0, 2.0, 3.0)) && b.contains(Vec3::new(0.5, 2.0, 0.0)));
        assert!(!b.contains(Vec3::new(1.0f32.next_up(), 1.0, 1.0)) && !b.contains(Vec3::new(0.5, 1.0, (-0.0f32).next_down())));
        assert!(b.contains_box(&Aabb::new(Vec3::ZERO, Vec3::ONE)) && !Aabb::new(Vec3::ZERO, Vec3::ONE).contains_box(&b));
        assert!(!Aabb::new(Vec3::ZERO, Vec3::new(f32::NAN, 1.0, 1.0)).is_valid());
        assert!(!Aabb::new(Vec3::splat(f32::NEG_INFINITY), Vec3::ZERO).is_finite());
        // Extreme scales neither overflow nor underflow.
        let huge = Aabb::new(Vec3::splat(-f32::MAX), Vec3::splat(f32::MAX));
        assert!(huge.center() == Vec3::ZERO && huge.surface_area().is_finite());
        assert!(Aabb::new(Vec3::ZERO, Vec3::splat(1e-30)).surface_area() > 0.0);
    }

    #[test]
    fn point_light_box_is_the_sphere_box() {
        let l = point(Vec3::new(1.0, -2.0, 3.0), 4.0);
        assert_close(light_aabb(&l), Aabb::new(Vec3::new(-3.0, -6.0, -1.0), Vec3::new(5.0, 2.0, 7.0)), 1e-5);
        assert!(light_contains(&l, l.position) && light_contains(&l, l.position + Vec3::X * 3.999));
        assert!(!light_contains(&l, l.position + Vec3::X * 4.0), "zero light at distance = range");
    }

    #[test]
    fn axis_aligned_spot_boxes_are_exact() {
        let p = Vec3::new(1.0, 2.0, -3.0);
        let r = 2.0;
        for outer in [1f32.to_radians(), 0.3, 0.7, PI / 4.0, 1.2, FRAC_PI_2] {
            let s = outer.sin();
            for axis in 0..3 {
                for sign in [1.0, -1.0] {
                    let d = Vec3::AXES[axis] * sign;
                    // Across the axis: ±r·sinθ; along it: from the apex to the cap's tip at distance r.
                    let mut min = p - Vec3::splat(r * s);
                    let mut max = p + Vec3::splat(r * s);
                    min[axis] = p[axis] + if sign > 0.0 { 0.0 } else { -r };
                    max[axis] = p[axis] + if sign > 0.0 { r } else { 0.0 };
                    let b = light_aabb(&spot(p, d, outer, r));
                    assert_close(b, Aabb::new(min, max), 1e-5);
                    assert!(b.contains_box(&Aabb::new(min, max)), "the padding widens, never narrows");
                }
            }
        }
    }

    #[test]
    fn spot_boxes_contain_their_volume_and_are_tight() {
        let mut rng = Pcg64::seed_from_u64(7);
        for case in 0..200 {
            let outer = match case % 4 {
                0 => 1f32.to_radians(),
                1 => FRAC_PI_2,
                _ => rng.random_range(0.02..FRAC_PI_2),
            };
            let position = Vec3::new(rng.random_range(-100.0..100.0), rng.random_range(-100.0..100.0), rng.random_range(-100.0..100.0));
            let range = rng.random_range(0.1..20.0);
            let l = spot(position, random_unit(&mut rng), outer, range);
            let b = light_aabb(&l);
            let sphere_box = light_aabb(&point(position, range));
            assert!(sphere_box.contains_box(&b), "{l:?}");
            if outer <= 1f32.to_radians() {
                // A 1° cone is a needle of length r: its box is at most r·|d_x|·r·|d_y|·r·|d_z| ≈ r³/5.2
                // (along a diagonal), against 8r³ for the sphere's.
                assert!(volume(&b) < 0.03 * volume(&sphere_box), "a 1° cone's box is a sliver of the sphere's: {l:?}");
            }
            // Points from the sphere's box that pass the exact test, points in the sector and on its
            // boundary (the apex, the cap and the cone) all lie in the box. The box is tight: the sampled points
            // come close to each of its faces.
            let mut reached = Aabb::EMPTY;
            let mut inside = 0;
            for i in 0..3000 {
                let q = match i % 3 {
                    _ if i == 0 => position,
                    0 => sphere_box.min + (sphere_box.max - sphere_box.min) * Vec3::new(rng.random(), rng.random(), rng.random()),
                    1 => {
                        // Anywhere along a ray inside the sector.
                        let t: f32 = rng.random();
                        position + sector_direction(&mut rng, &l, outer) * (range * t)
                    }
                    _ => position + sector_direction(&mut rng, &l, outer) * range.next_down(),
                };
                if light_contains(&l, q) {
                    inside += 1;
                    reached.grow_point(q);
                    assert!(b.contains(q), "{q:?} is lit by {l:?} but not in its box {b:?}");
                }
            }
            assert!(inside > 800, "{inside} of 3000 samples inside {l:?}");
            let slack = (b.max - b.min).max_element() * 0.05 + 1e-4;
            assert!((reached.min - b.min).max_element() <= slack && (b.max - reached.max).max_element() <= slack, "{reached:?} vs {b:?}");
        }
    }

    #[test]
    fn boxes_contain_boundary_points_at_every_scale() {
        // Points on the sphere and the cone, a few ulps either way, for lights from 1e-3 to 1e7 in size
        // and position: f32 rounding in either function must not put a lit point outside the box.
        let mut rng = Pcg64::seed_from_u64(9);
        let mut lit = 0;
        for case in 0..5000 {
            let scale = [1e-3, 1.0, 1e3, 1e5, 1e7][case % 5];
            let position = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * scale;
            let range = scale * if rng.random_bool(0.5) { rng.random_range(0.001..2.0) } else { 1e-4 };
            // Nearly axis-aligned spots are the hard case for the rim's extent.
            let direction = (random_unit(&mut rng) + Vec3::AXES[case % 3] * [0.0, 1.0, 100.0][case % 3]).normalize();
            let outer = [FRAC_PI_2, 1f32.to_radians(), rng.random_range(0.01..FRAC_PI_2)][rng.random_range(0..3)];
            let l = if case % 7 == 0 { point(position, range) } else { spot(position, direction, outer, range) };
            let b = light_aabb(&l);
            for _ in 0..50 {
                let mut q = position + sector_direction(&mut rng, &l, outer) * range;
                for axis in 0..3 {
                    for _ in 0..rng.random_range(0..4) {
                        q[axis] = if rng.random_bool(0.5) { q[axis].next_up() } else { q[axis].next_down() };
                    }
                }
                if light_contains(&l, q) {
                    lit += 1;
                    assert!(b.contains(q), "{q:?} is lit by {l:?} but not in its box {b:?}");
                }
            }
        }
        assert!(lit > 10_000, "{lit}");
    }

    /// A random direction within `outer` of the spot's axis, the rim included.
    fn sector_direction(rng: &mut Pcg64, l: &Light, outer: f32) -> Vec3 {
        let d = l.direction;
        let (u, v) = d.any_orthonormal_pair();
        let angle = if rng.random_bool(0.3) { outer } else { outer * rng.random::<f32>() };
        let phi = rng.random_range(0.0..2.0 * PI);
        d * angle.cos() + (u * phi.cos() + v * phi.sin()) * angle.sin()
    }

    #[test]
    fn spot_contains_respects_the_cone() {
        let l = spot(Vec3::ZERO, Vec3::Z, 0.5, 10.0);
        assert!(light_contains(&l, Vec3::ZERO), "the apex is inside");
        assert!(light_contains(&l, Vec3::new(0.0, 0.0, 9.0)));
        assert!(light_contains(&l, Vec3::new(0.49f32.tan(), 0.0, 1.0)));
        assert!(!light_contains(&l, Vec3::new(0.51f32.tan(), 0.0, 1.0)));
        assert!(!light_contains(&l, Vec3::new(0.0, 0.0, -1.0)));
        assert!(!light_contains(&l, Vec3::new(0.0, 0.0, 10.0)));
        // A hemisphere (outer = π/2) reaches the plane through the apex but not behind it.
        let h = spot(Vec3::ZERO, Vec3::Z, FRAC_PI_2, 10.0);
        assert!(light_contains(&h, Vec3::new(5.0, 0.0, 0.0)) && !light_contains(&h, Vec3::new(5.0, 0.0, -0.01)));
    }
}
