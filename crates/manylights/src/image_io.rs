//! Writing rendered images: PNG for the tonemapped frame, OpenEXR for linear radiance.

use std::path::Path;

use crate::{renderer::Image, Error, Result};

fn output_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Output { path: path.to_path_buf(), reason: e.to_string() }
}

pub fn save_png(path: &Path, image: &Image<[u8; 4]>) -> Result<()> {
    let buffer = image::RgbaImage::from_raw(image.width, image.height, image.pixels.concat())
        .ok_or_else(|| output_error(path, "image size mismatch"))?;
    buffer.save_with_format(path, image::ImageFormat::Png).map_err(|e| output_error(path, e))
}

pub fn save_exr(path: &Path, image: &Image<[f32; 4]>) -> Result<()> {
    let buffer = image::Rgba32FImage::from_raw(image.width, image.height, image.pixels.concat())
        .ok_or_else(|| output_error(path, "image size mismatch"))?;
    buffer.save_with_format(path, image::ImageFormat::OpenExr).map_err(|e| output_error(path, e))
}
