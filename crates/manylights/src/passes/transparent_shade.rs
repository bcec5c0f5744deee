//! Transparent surfaces over the shaded HDR image, after the opaque ones, in every pipeline, all
//! shaded in compute. Transmissive surfaces (`KHR_materials_transmission`) see through the opaque
//! image, which `transmission_background` first copies into a mip chain; those that do not blend are
//! shaded by `transmissive_shade` (each pixel its nearest, writing depth, so blended surfaces behind
//! it are hidden as they are behind opaque ones). Then `blended_shade` shades the alpha-blended
//! surfaces (glTF BLEND), each pixel's layers sorted far to near and blended over.

use super::blended_shade::BlendedShade;
use super::transmission_background::TransmissionBackground;
use super::transmissive_shade::TransmissiveShade;
use super::{FrameInputs, ShadedImage, Structures};
use crate::gpu::{GpuContext, GpuScene, GpuTimer};
use crate::plan::ShadingMethods;
use crate::Result;

pub struct TransparentShade {
    /// With transmissive draws or transmission, the image they see through.
    background: Option<TransmissionBackground>,
    /// Transmissive draws that do not blend, if any.
    transmissive: Option<TransmissiveShade>,
    /// Blended draws, if any.
    blended: Option<BlendedShade>,
}

impl TransparentShade {
    /// The passes for `scene`'s transparent draws over `hdr`, the frame's shaded image, in front of
    /// the surfaces in `depth`; `None` when it has none.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        methods: ShadingMethods,
        structures: Structures,
        (hdr, depth): (&wgpu::Texture, &wgpu::Texture),
    ) -> Result<Option<Self>> {
        let (blended, transmissive) = (!scene.transparent_draw_commands.is_empty(), !scene.transmissive_draw_commands.is_empty());
        if !blended && !transmissive {
            return Ok(None);
        }
        let sees_through = methods.transmission || transmissive;
        let background = sees_through.then(|| TransmissionBackground::new(ctx, hdr)).transpose()?;
        let transmissive = match &background {
            Some(background) if transmissive => Some(TransmissiveShade::new(ctx, scene, methods, structures, hdr, background)?),
            _ => None,
        };
        let blended = blended.then(|| BlendedShade::new(ctx, scene, methods, structures, (hdr, depth), background.as_ref())).transpose()?;
        Ok(Some(Self { background, transmissive, blended }))
    }

    /// Copies the opaque image that transmissive surfaces see through, shades the transmissive
    /// (their raster writing `image.depth`), then the blended surfaces, over the HDR image.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, inputs: &FrameInputs, image: ShadedImage) {
        if let Some(background) = &self.background {
            background.record(encoder, timer.as_deref_mut());
        }
        if let Some(transmissive) = &self.transmissive {
            transmissive.record(encoder, timer.as_deref_mut(), inputs, image.depth);
        }
        if let Some(blended) = &self.blended {
            blended.record(encoder, timer, inputs);
        }
    }

    /// Whether the blended surfaces' layers held every fragment since the last call; if not, they
    /// grow and the caller renders those frames again.
    pub fn fitted(&mut self, ctx: &GpuContext) -> Result<bool> {
        self.blended.as_mut().map_or(Ok(true), |blended| blended.fitted(ctx))
    }
}
