//! A scene's environment: the radiance arriving from afar in every direction, as an
//! equirectangular image — the daylight sky (`scene::sky`) or an HDR image file. It is seen in the
//! background and where reflected rays leave the scene, and lights surfaces through image-based
//! lighting (`scene::ibl`).

use std::f32::consts::PI;
use std::path::Path;

use glam::Vec3;

use crate::files::{self, guard, InputKind, LoadBudget};
use crate::{Error, Result};

/// An equirectangular radiance image: row 0 looks at the zenith (+Y), the last row at the nadir;
/// column u of W looks along (sin φ, 0, −cos φ) at φ = 2π((u + ½) / W − ½), so the image's centre
/// is −Z and its right half +X. Any size is read; a width twice the height has square texels.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    pub width: u32,
    pub height: u32,
    /// Linear radiance in scene units, row by row.
    pub radiance: Vec<[f32; 3]>,
    /// Whether the background draws the scene's sun as a disc: the daylight sky leaves the sun out of
    /// its image, and lights with the directional sun instead.
    pub sun_disc: bool,
}

impl Environment {
    /// The same radiance from every direction.
    pub fn uniform(radiance: Vec3) -> Self {
        Self { width: 2, height: 1, radiance: vec![radiance.to_array(); 2], sun_disc: false }
    }

    /// The unit direction through the centre of texel (column, row).
    pub fn texel_direction(column: u32, row: u32, width: u32, height: u32) -> Vec3 {
        let u = (column as f32 + 0.5) / width as f32;
        let v = (row as f32 + 0.5) / height as f32;
        direction_at(u, v)
    }

    /// The solid angle a texel of `row` covers.
    pub fn texel_solid_angle(row: u32, width: u32, height: u32) -> f32 {
        let top = row as f32 / height as f32 * PI;
        let bottom = (row + 1) as f32 / height as f32 * PI;
        (top.cos() - bottom.cos()) * 2.0 * PI / width as f32
    }

    /// The radiance along unit `dir`, filtered bilinearly (wrapping around, clamped at the poles).
    pub fn sample(&self, dir: Vec3) -> Vec3 {
        let (u, v) = uv_of(dir);
        let x = u * self.width as f32 - 0.5;
        let y = (v * self.height as f32 - 0.5).clamp(0.0, (self.height - 1) as f32);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |column: f32, row: f32| {
            let column = (column as i64).rem_euclid(i64::from(self.width)) as u32;
            let row = (row as u32).min(self.height - 1);
            Vec3::from(self.radiance[(row * self.width + column) as usize])
        };
        let top = texel(x0, y0).lerp(texel(x0 + 1.0, y0), fx);
        let bottom = texel(x0, y0 + 1.0).lerp(texel(x0 + 1.0, y0 + 1.0), fx);
        top.lerp(bottom, fy)
    }

    /// Reads an equirectangular Radiance HDR (`.hdr`) or OpenEXR image; the message says what is
    /// wrong with the file and what to give instead.
    pub fn load(path: &Path, budget: &LoadBudget) -> Result<Self> {
        let fail = |reason: String| Error::Input { path: path.to_owned(), reason };
        let bytes = files::read_input(path, InputKind::Image, None, budget)?;
        let format = image::guess_format(&bytes)
            .ok()
            .filter(|f| matches!(f, image::ImageFormat::Hdr | image::ImageFormat::OpenExr))
            .ok_or_else(|| fail("not a Radiance HDR (.hdr) or OpenEXR (.exr) image; give an equirectangular HDR environment".into()))?;
        let image = guard::contain_panics(|| decode(&bytes, format, budget))
            .unwrap_or_else(|message| Err(format!("the image decoder failed on it ({message}); re-save the image")))
            .map_err(|e| fail(format!("not a readable environment image: {e}")))?;
        let (width, height) = image.dimensions();
        if width < 2 || height < 1 {
            return Err(fail(format!("it is {width}×{height} pixels; an equirectangular environment needs at least 2×1")));
        }
        let radiance: Vec<[f32; 3]> = image.pixels().map(|p| p.0.map(|c| if c.is_finite() { c.max(0.0) } else { 0.0 })).collect();
        Ok(Self { width, height, radiance, sun_disc: false })
    }
}

fn decode(bytes: &[u8], format: image::ImageFormat, budget: &LoadBudget) -> std::result::Result<image::Rgb32FImage, String> {
    use image::ImageDecoder;
    let message = |e: image::ImageError| crate::error::one_line(&e.to_string());
    let mut decoder = image::ImageReader::with_format(std::io::Cursor::new(bytes), format).into_decoder().map_err(message)?;
    let (width, height) = decoder.dimensions();
    let mut limits = image::Limits::default();
    limits.reserve(decoder.total_bytes()).map_err(message)?;
    decoder.set_limits(limits).map_err(message)?;
    // The decoded image and its RGB f32 copy.
    budget.take_decoded(decoder.total_bytes().saturating_add(u64::from(width) * u64::from(height) * 12))?;
    Ok(image::DynamicImage::from_decoder(decoder).map_err(message)?.into_rgb32f())
}

/// The unit direction at equirectangular coordinates (u, v) in [0, 1]².
pub fn direction_at(u: f32, v: f32) -> Vec3 {
    let phi = (u - 0.5) * 2.0 * PI;
    let theta = v * PI;
    Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

/// The equirectangular coordinates of unit `dir`; the inverse of [`direction_at`]. Keep in sync with
/// `environment_uv` in `shading/environment.wgsl`.
pub fn uv_of(dir: Vec3) -> (f32, f32) {
    (dir.x.atan2(-dir.z) / (2.0 * PI) + 0.5, dir.y.clamp(-1.0, 1.0).acos() / PI)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::test_support::temp_dir;

    #[test]
    fn directions_and_coordinates_invert_each_other() {
        for (u, v) in [(0.5, 0.5), (0.25, 0.3), (0.9, 0.7)] {
            let (back_u, back_v) = uv_of(direction_at(u, v));
            assert!((back_u - u).abs() < 1e-5 && (back_v - v).abs() < 1e-5, "{u} {v}");
        }
        assert!(direction_at(0.5, 0.5).abs_diff_eq(Vec3::NEG_Z, 1e-6));
        assert!(direction_at(0.75, 0.5).abs_diff_eq(Vec3::X, 1e-6));
        let total: f32 = (0..8).map(|row| Environment::texel_solid_angle(row, 16, 8) * 16.0).sum();
        assert!((total - 4.0 * PI).abs() < 1e-4);
    }

    #[test]
    fn hdr_files_load_and_other_files_are_refused_with_a_reason() {
        let dir = temp_dir("environment_load");
        let path = dir.join("sky.hdr");
        let pixels: Vec<image::Rgb<f32>> = (0..8).map(|i| image::Rgb([i as f32, 1.0, 0.5])).collect();
        let file = std::fs::File::create(&path).unwrap();
        image::codecs::hdr::HdrEncoder::new(file).encode(&pixels, 4, 2).unwrap();
        let environment = Environment::load(&path, &LoadBudget::new()).unwrap();
        assert_eq!((environment.width, environment.height, environment.radiance[3]), (4, 2, [3.0, 1.0, 0.5]));

        let png = dir.join("flat.png");
        image::RgbImage::new(4, 2).save(&png).unwrap();
        let e = Environment::load(&png, &LoadBudget::new()).unwrap_err().to_string();
        assert!(e.contains("not a Radiance HDR (.hdr) or OpenEXR (.exr) image"), "{e}");
        let truncated = dir.join("truncated.hdr");
        std::fs::write(&truncated, &std::fs::read(&path).unwrap()[..40]).unwrap();
        let e = Environment::load(&truncated, &LoadBudget::new()).unwrap_err().to_string();
        assert!(e.contains("not a readable environment image"), "{e}");
        let e = Environment::load(&dir.join("missing.hdr"), &LoadBudget::new()).unwrap_err().to_string();
        assert!(e.contains("check that the path exists"), "{e}");
    }
}
