//! Cameras: a rigid transform plus a projection. Projections use reverse Z (near → 1, far → 0) for
//! depth precision; perspective projections without a far plane are infinite.

use glam::{Mat4, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    Perspective {
        /// Vertical field of view, radians.
        yfov: f32,
        znear: f32,
        zfar: Option<f32>,
    },
    Orthographic {
        /// Half extents of the view volume.
        xmag: f32,
        ymag: f32,
        znear: f32,
        zfar: f32,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub name: String,
    /// Rigid transform; the camera looks down its local -Z with +Y up.
    pub world_from_view: Mat4,
    pub projection: Projection,
}

/// Nearest near plane a perspective camera may have, in metres. Reverse-Z stores near / distance, and
/// positions are rebuilt from depth through the inverse projection, whose entries grow as 1 / near:
/// with near at 1e-30 the sky's gradient went flat, at 1e-38 (a denormal, flushed to zero) nothing
/// was drawn. A micrometre keeps both far inside f32's range, as the clustered grid's slices assume.
pub const MIN_ZNEAR: f32 = 1e-6;
/// Narrowest vertical field of view, in radians: the projection scales by 1 / tan(yfov / 2), and at
/// 1e-30 rad half the image showed the background; 1e-5 rad (a 0.0006° telephoto) is far narrower
/// than any lens.
pub const MIN_YFOV: f32 = 1e-5;

impl Projection {
    /// Checks what `clip_from_view` needs: a field of view between [`MIN_YFOV`] and π, non-zero
    /// orthographic extents, and finite planes with [`MIN_ZNEAR`] ≤ near < far (near ≥ 0 when
    /// orthographic).
    pub fn validate(&self) -> Result<(), String> {
        let finite = |v: f32| v.is_finite();
        match *self {
            Projection::Perspective { yfov, znear, zfar } => {
                if !(MIN_YFOV..std::f32::consts::PI).contains(&yfov) {
                    return Err(format!("perspective yfov {yfov} rad must lie between {MIN_YFOV} and π"));
                }
                if !(finite(znear) && znear >= MIN_ZNEAR) {
                    return Err(format!("perspective znear {znear} must be finite and at least {MIN_ZNEAR} (a micrometre)"));
                }
                if let Some(zfar) = zfar.filter(|&f| !(finite(f) && f > znear)) {
                    return Err(format!("perspective zfar {zfar} must be finite and beyond znear {znear}"));
                }
            }
            Projection::Orthographic { xmag, ymag, znear, zfar } => {
                if !(finite(xmag) && finite(ymag) && xmag != 0.0 && ymag != 0.0) {
                    return Err(format!("orthographic xmag {xmag} and ymag {ymag} must be finite and non-zero"));
                }
                if !(finite(znear) && finite(zfar) && znear >= 0.0 && zfar > znear) {
                    return Err(format!("orthographic znear {znear} and zfar {zfar} must be finite with 0 ≤ znear < zfar"));
                }
            }
        }
        Ok(())
    }
}

impl Camera {
    pub fn look_at(name: &str, eye: Vec3, target: Vec3, yfov: f32, znear: f32) -> Self {
        Self {
            name: name.into(),
            world_from_view: Mat4::look_at_rh(eye, target, Vec3::Y).inverse(),
            projection: Projection::Perspective { yfov, znear, zfar: None },
        }
    }

    pub fn position(&self) -> Vec3 {
        self.world_from_view.w_axis.truncate()
    }

    /// Reverse-Z clip-from-view matrix for the given aspect ratio (width / height).
    pub fn clip_from_view(&self, aspect: f32) -> Mat4 {
        match self.projection {
            Projection::Perspective { yfov, znear, zfar: None } => Mat4::perspective_infinite_reverse_rh(yfov, aspect, znear),
            // Swapping near and far turns glam's [0,1] depth into reverse Z.
            Projection::Perspective { yfov, znear, zfar: Some(zfar) } => Mat4::perspective_rh(yfov, aspect, zfar, znear),
            Projection::Orthographic { xmag, ymag, znear, zfar } => {
                // glTF's xmag is ignored in favour of the output aspect, as for yfov, so images are not stretched.
                let _ = xmag;
                let x = ymag * aspect;
                Mat4::orthographic_rh(-x, x, -ymag, ymag, zfar, znear)
            }
        }
    }

    /// World space to clip space for an image of `width` × `height` pixels.
    pub fn clip_from_world(&self, width: u32, height: u32) -> Mat4 {
        self.clip_from_view(width as f32 / height as f32) * self.world_from_view.inverse()
    }

    /// A camera that frames `bounds` from the front-right and above.
    pub fn framing(bounds: &super::Aabb) -> Self {
        let center = bounds.center();
        let radius = (bounds.diagonal() * 0.5).max(1e-3);
        let yfov = 50f32.to_radians();
        let distance = radius / (yfov * 0.5).sin();
        let eye = center + Vec3::new(0.6, 0.45, 1.0).normalize() * distance;
        Self::look_at("auto", eye, center, yfov, (distance - radius).max(radius * 1e-3).min(distance * 0.1))
    }
}
