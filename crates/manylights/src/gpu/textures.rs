//! Material textures as two 2D texture arrays (colour in sRGB, data in linear), one layer per image,
//! every layer resampled to one size with a full mip chain. Arrays rather than binding arrays because
//! lavapipe and much of the hardware we target lack the latter.

use std::collections::BTreeMap;

use image::{imageops::FilterType, Rgba32FImage, RgbaImage};

use crate::{scene::Texture, Error, Result};

/// Which array a texture goes to, by how materials use it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureSpace {
    /// Base colour and emissive: sRGB-encoded, filtered in linear.
    Srgb,
    /// Normal and metallic-roughness maps: linear data.
    Linear,
}

pub struct TextureArray {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    /// Scene texture index → layer.
    pub layers: BTreeMap<usize, i32>,
}

impl TextureArray {
    /// Uploads `used` scene textures into one array whose layer size is the largest image's, capped at
    /// `max_size`. An empty set still gets one white layer so the binding is valid.
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        textures: &[Texture],
        used: &[usize],
        space: TextureSpace,
        max_size: u32,
    ) -> Result<Self> {
        let limits = device.limits();
        if used.len() as u32 > limits.max_texture_array_layers {
            return Err(Error::InvalidScene(format!(
                "the scene uses {} {space:?} textures but the GPU allows {} layers per texture array",
                used.len(),
                limits.max_texture_array_layers
            )));
        }
        let largest = used.iter().map(|&t| textures[t].width.max(textures[t].height)).max().unwrap_or(1);
        let size = largest.min(max_size).min(limits.max_texture_dimension_2d).max(1);
        let mip_count = size.ilog2() + 1;
        let format = match space {
            TextureSpace::Srgb => wgpu::TextureFormat::Rgba8UnormSrgb,
            TextureSpace::Linear => wgpu::TextureFormat::Rgba8Unorm,
        };
        let layer_count = used.len().max(1) as u32;
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some(match space {
                TextureSpace::Srgb => "color textures",
                TextureSpace::Linear => "data textures",
            }),
            size: wgpu::Extent3d { width: size, height: size, depth_or_array_layers: layer_count },
            mip_level_count: mip_count,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });

        let white = Texture { name: "white".into(), width: 1, height: 1, rgba8: vec![255; 4] };
        let sources: Vec<&Texture> = if used.is_empty() { vec![&white] } else { used.iter().map(|&t| &textures[t]).collect() };
        for (layer, source) in sources.iter().enumerate() {
            for (mip, level) in mip_chain(source, size, mip_count, space)?.iter().enumerate() {
                queue.write_texture(
                    wgpu::TexelCopyTextureInfo {
                        texture: &texture,
                        mip_level: mip as u32,
                        origin: wgpu::Origin3d { x: 0, y: 0, z: layer as u32 },
                        aspect: wgpu::TextureAspect::All,
                    },
                    level.as_raw(),
                    wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(level.width() * 4), rows_per_image: Some(level.height()) },
                    wgpu::Extent3d { width: level.width(), height: level.height(), depth_or_array_layers: 1 },
                );
            }
        }
        let view = texture
            .create_view(&wgpu::TextureViewDescriptor { dimension: Some(wgpu::TextureViewDimension::D2Array), ..Default::default() });
        let layers = used.iter().enumerate().map(|(layer, &t)| (t, layer as i32)).collect();
        Ok(Self { texture, view, layers })
    }
}

/// The image resampled to `size`² and its mips, filtered in linear light for sRGB images.
fn mip_chain(source: &Texture, size: u32, mip_count: u32, space: TextureSpace) -> Result<Vec<RgbaImage>> {
    let image = RgbaImage::from_raw(source.width, source.height, source.rgba8.clone()).ok_or_else(|| {
        Error::InvalidScene(format!("texture `{}`: pixel data does not match {}×{}", source.name, source.width, source.height))
    })?;
    let mut level = to_linear(&image, space);
    let mut chain = Vec::with_capacity(mip_count as usize);
    for mip in 0..mip_count {
        let s = (size >> mip).max(1);
        if level.dimensions() != (s, s) {
            level = image::imageops::resize(&level, s, s, FilterType::Triangle);
        }
        chain.push(from_linear(&level, space));
    }
    Ok(chain)
}

fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

fn to_linear(image: &RgbaImage, space: TextureSpace) -> Rgba32FImage {
    let lut: Vec<f32> = (0..256)
        .map(|i| {
            let c = i as f32 / 255.0;
            if space == TextureSpace::Srgb {
                srgb_to_linear(c)
            } else {
                c
            }
        })
        .collect();
    let mut out = Rgba32FImage::new(image.width(), image.height());
    for (dst, src) in out.pixels_mut().zip(image.pixels()) {
        dst.0 = [lut[src[0] as usize], lut[src[1] as usize], lut[src[2] as usize], src[3] as f32 / 255.0];
    }
    out
}

fn from_linear(image: &Rgba32FImage, space: TextureSpace) -> RgbaImage {
    let encode = |c: f32| {
        let c = if space == TextureSpace::Srgb { linear_to_srgb(c.clamp(0.0, 1.0)) } else { c.clamp(0.0, 1.0) };
        (c * 255.0 + 0.5) as u8
    };
    let mut out = RgbaImage::new(image.width(), image.height());
    for (dst, src) in out.pixels_mut().zip(image.pixels()) {
        dst.0 = [encode(src[0]), encode(src[1]), encode(src[2]), (src[3].clamp(0.0, 1.0) * 255.0 + 0.5) as u8];
    }
    out
}

/// A 2D image a frame writes and reads, of one mip level and sample.
pub fn target(
    device: &wgpu::Device,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_mips_average_in_linear_light() {
        // A black/white checker averages to 50% linear, which is sRGB 188, not 128.
        let rgba8 = (0..4 * 4).flat_map(|i| if (i % 4 + i / 4) % 2 == 0 { [0, 0, 0, 255] } else { [255, 255, 255, 255] }).collect();
        let texture = Texture { name: "checker".into(), width: 4, height: 4, rgba8 };
        let chain = mip_chain(&texture, 4, 3, TextureSpace::Srgb).unwrap();
        assert_eq!(chain.len(), 3);
        let last = chain[2].get_pixel(0, 0);
        assert!((185..=191).contains(&last[0]), "{last:?}");
        let linear = mip_chain(&texture, 4, 3, TextureSpace::Linear).unwrap();
        assert!((126..=129).contains(&linear[2].get_pixel(0, 0)[0]));
    }

    #[test]
    fn mismatched_pixel_data_is_an_error() {
        let texture = Texture { name: "bad".into(), width: 4, height: 4, rgba8: vec![0; 7] };
        assert!(mip_chain(&texture, 4, 3, TextureSpace::Linear).is_err());
    }
}
