//! The scene's environment on the GPU (`shading/environment.wgsl`): the radiance image seen in the
//! background and by missed reflection rays, its GGX-prefiltered mips and the BRDF table (the split
//! sum's scale and bias for specular image-based lighting, the sheen's albedo), and the irradiance harmonics, which go in the frame uniforms.
//! All of it is computed on the CPU once, at upload (`scene::ibl`).

use glam::{Vec3, Vec4};
use wgpu::util::DeviceExt;

use crate::scene::{
    ibl::{self, BRDF_TABLE_SIZE, SPECULAR_LEVELS},
    Environment, Scene,
};

/// The widest background image kept: 4096 × 2048 texels of RGBA16F are 64 MiB; larger environment
/// images are shrunk to it (the lighting is filtered from a smaller copy anyway).
const MAX_BACKGROUND_SIZE: u32 = 4096;

/// The environment's textures and sampler, bound in the scene's group 0.
pub struct GpuEnvironment {
    pub background: wgpu::TextureView,
    pub specular: wgpu::TextureView,
    pub brdf_table: wgpu::TextureView,
    /// Bilinear with mips, wrapping around the horizon, clamped at the poles.
    pub sampler: wgpu::Sampler,
    pub lighting: EnvironmentLighting,
}

/// What the frame uniforms carry of the environment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvironmentLighting {
    /// `scene::ibl::irradiance_sh`'s coefficients.
    pub irradiance: [Vec3; 9],
    /// Whether the background draws the sun's disc (`Environment::sun_disc`).
    pub sun_disc: bool,
}

impl GpuEnvironment {
    /// Uploads `scene`'s environment, or a uniform one of its ambient radiance; the background
    /// image is shrunk to the device's largest texture, and [`MAX_BACKGROUND_SIZE`], if larger.
    pub fn upload(device: &wgpu::Device, queue: &wgpu::Queue, scene: &Scene, max_texture_size: u32) -> Self {
        let max_size = max_texture_size.min(MAX_BACKGROUND_SIZE);
        let uniform;
        let environment = match &scene.environment {
            Some(environment) => environment,
            None => {
                uniform = Environment::uniform(scene.ambient);
                &uniform
            }
        };
        let pyramid = ibl::Pyramid::new(environment);
        let lighting = EnvironmentLighting { irradiance: ibl::irradiance_sh(&pyramid), sun_disc: environment.sun_disc };
        let shrunk;
        let background = if environment.width > max_size || environment.height > max_size {
            let scale = (max_size as f32 / environment.width as f32).min(max_size as f32 / environment.height as f32);
            let size = |n: u32| ((n as f32 * scale) as u32).clamp(1, max_size);
            shrunk = ibl::resample(environment, size(environment.width), size(environment.height));
            &shrunk
        } else {
            environment
        };
        let rgba16 = |levels: &[&Environment]| -> Vec<u8> {
            let halves: Vec<u16> = levels
                .iter()
                .flat_map(|l| l.radiance.iter().flat_map(|&[r, g, b]| [r, g, b, 1.0]))
                .map(|c| half::f16::from_f32(c.min(half::f16::MAX.to_f32())).to_bits())
                .collect();
            bytemuck::cast_slice(&halves).to_vec()
        };
        let texture = |label, width, height, levels, format, data: &[u8]| {
            let descriptor = wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: levels,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            };
            device
                .create_texture_with_data(queue, &descriptor, wgpu::util::TextureDataOrder::MipMajor, data)
                .create_view(&Default::default())
        };
        let half_float = wgpu::TextureFormat::Rgba16Float;
        let background_view = texture("environment", background.width, background.height, 1, half_float, &rgba16(&[background]));
        let specular = ibl::prefiltered_specular(&pyramid);
        let specular_levels: Vec<&Environment> = specular.iter().collect();
        let specular_view = texture(
            "prefiltered environment",
            specular[0].width,
            specular[0].height,
            SPECULAR_LEVELS,
            half_float,
            &rgba16(&specular_levels),
        );
        // The split sum's scale and bias, then the sheen's albedo.
        let table: Vec<u16> = ibl::brdf_table()
            .iter()
            .zip(ibl::sheen_albedo_table())
            .flat_map(|(&[scale, bias], &sheen)| [scale, bias, sheen, 0.0])
            .map(|c| half::f16::from_f32(c).to_bits())
            .collect();
        let brdf_view =
            texture("BRDF table", BRDF_TABLE_SIZE, BRDF_TABLE_SIZE, 1, wgpu::TextureFormat::Rgba16Float, bytemuck::cast_slice(&table));
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("environment sampler"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        Self { background: background_view, specular: specular_view, brdf_table: brdf_view, sampler, lighting }
    }
}

impl EnvironmentLighting {
    /// The frame uniforms' `environment_irradiance` and `environment` (`shading/types.wgsl`).
    pub fn uniforms(&self) -> ([[f32; 4]; 9], [f32; 4]) {
        let irradiance = self.irradiance.map(|c| c.extend(0.0).to_array());
        (irradiance, Vec4::new((SPECULAR_LEVELS - 1) as f32, if self.sun_disc { 1.0 } else { 0.0 }, 0.0, 0.0).to_array())
    }
}
