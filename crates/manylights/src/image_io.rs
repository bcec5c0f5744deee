//! Encoding rendered images: PNG or JPEG for the tonemapped frame, OpenEXR for linear radiance. The
//! bytes are written by `files::write`, whole or not at all.

use std::io::Cursor;

use image::error::{ParameterError, ParameterErrorKind};
use image::{ImageEncoder, ImageError, ImageResult};

use crate::files::OutputFormat;
use crate::gpu::readback::Image;

/// JPEG quality: high enough that the encoding's blocks do not show on smooth gradients.
const JPEG_QUALITY: u8 = 95;

/// The tonemapped image as PNG (with alpha) or JPEG (without).
pub fn encode_ldr(image: &Image<[u8; 4]>, format: OutputFormat) -> ImageResult<Vec<u8>> {
    let mut bytes = Vec::new();
    match format {
        OutputFormat::Png => image::codecs::png::PngEncoder::new(&mut bytes).write_image(
            image.pixels.as_flattened(),
            image.width,
            image.height,
            image::ExtendedColorType::Rgba8,
        )?,
        OutputFormat::Jpeg => {
            let rgb: Vec<u8> = image.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect();
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, JPEG_QUALITY).write_image(
                &rgb,
                image.width,
                image.height,
                image::ExtendedColorType::Rgb8,
            )?
        }
        other => {
            let kind = ParameterErrorKind::Generic(format!("{other:?} is not an 8-bit image format"));
            return Err(ImageError::Parameter(ParameterError::from_kind(kind)));
        }
    }
    Ok(bytes)
}

/// Linear radiance as 32-bit float OpenEXR.
pub fn encode_exr(image: &Image<[f32; 4]>) -> ImageResult<Vec<u8>> {
    let mut bytes = Cursor::new(Vec::new());
    image::codecs::openexr::OpenExrEncoder::new(&mut bytes).write_image(
        bytemuck::cast_slice(image.pixels.as_flattened()),
        image.width,
        image.height,
        image::ExtendedColorType::Rgba32F,
    )?;
    Ok(bytes.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_format_decodes_back_to_the_image() {
        let pixels: Vec<[u8; 4]> = (0..64u32).map(|i| [(i * 4) as u8, 255 - (i * 4) as u8, 128, 255]).collect();
        let ldr = Image { width: 8, height: 8, pixels };
        let png = image::load_from_memory_with_format(&encode_ldr(&ldr, OutputFormat::Png).unwrap(), image::ImageFormat::Png).unwrap();
        assert_eq!(png.to_rgba8().into_raw(), ldr.pixels.as_flattened());
        let jpeg = encode_ldr(&ldr, OutputFormat::Jpeg).unwrap();
        assert!(jpeg.starts_with(&[0xFF, 0xD8]), "JPEG files start with SOI");
        let decoded = image::load_from_memory_with_format(&jpeg, image::ImageFormat::Jpeg).unwrap().to_rgb8();
        let worst = decoded.pixels().zip(&ldr.pixels).flat_map(|(a, b)| (0..3).map(move |c| a[c].abs_diff(b[c]))).max().unwrap();
        assert!(worst <= 24, "JPEG at quality {JPEG_QUALITY} is off by {worst}");
        let hdr = Image { width: 2, height: 1, pixels: vec![[0.5, 2.0, 1e6, 1.0], [0.0, 0.25, 3.0, 1.0]] };
        let exr = image::load_from_memory_with_format(&encode_exr(&hdr).unwrap(), image::ImageFormat::OpenExr).unwrap();
        assert_eq!(exr.to_rgba32f().into_raw(), hdr.pixels.as_flattened());
        assert!(encode_ldr(&ldr, OutputFormat::Exr).is_err());
    }
}
