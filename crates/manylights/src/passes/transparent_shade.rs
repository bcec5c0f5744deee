//! Transparent surfaces (`transparent_shade.wgsl`): the scene's alpha-blended draws (glTF BLEND),
//! drawn back to front over the shaded HDR image after the opaque surfaces, in every pipeline, depth
//! tested against the opaque surfaces and not written; each fragment is lit and decaled by the
//! shading core through the frame's methods, so decals and lights reach transparent surfaces too.
//! The fragment stage is the only place for them: no G-buffer or visibility buffer holds more than
//! one surface per pixel. Transmissive surfaces (`KHR_materials_transmission`) are drawn here too,
//! after `transmission_background` copies the opaque image into a mip chain they see through: those
//! that do not blend first, front to back, writing depth (each pixel shows the nearest, and blended
//! surfaces behind it are hidden as they are behind opaque ones), then the blended ones.

use std::collections::HashMap;

use super::builder::{depth_test, Fragment, Raster};
use super::transmission_background::TransmissionBackground;
use super::{visbuffer_shade::HDR_FORMAT, FrameInputs, ShadedImage, Structures};
use crate::gpu::scene::RasterState;
use crate::gpu::{bindings, shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::plan::ShadingMethods;
use crate::{Error, Result};

/// The shader for a set of shading methods: with `transmission`, light behind transmissive surfaces
/// comes from the background's mip chain.
pub fn shader(methods: ShadingMethods) -> ShaderDesc {
    let desc = super::shading_core_shader("passes/transparent_shade.wgsl", methods, crate::plan::ShadingStage::Fragment);
    if methods.transmission {
        desc.with("TRANSMITTED_LIGHT", "shading/transmitted_screen.wgsl")
    } else {
        desc
    }
}

pub struct TransparentShade {
    /// Blended draws: depth tested, not written.
    blended: HashMap<RasterState, wgpu::RenderPipeline>,
    /// Transmissive draws that do not blend: depth written, so only the nearest is seen.
    nearest: HashMap<RasterState, wgpu::RenderPipeline>,
    /// With transmissive draws, the image they see through.
    background: Option<TransmissionBackground>,
    /// Group 1: the background and its sampler, or empty (the shading core's light and decal
    /// bindings are groups 2 and 3 everywhere).
    group: wgpu::BindGroup,
}

impl TransparentShade {
    /// The pass for `scene`'s transparent draws over `hdr`, the frame's shaded image; `None` when
    /// it has none.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        methods: ShadingMethods,
        structures: Structures,
        hdr: &wgpu::Texture,
    ) -> Result<Option<Self>> {
        if scene.transparent_draw_commands.is_empty() && scene.transmissive_draw_commands.is_empty() {
            return Ok(None);
        }
        if !scene.transparent_draw_commands.is_empty() && !ctx.features.contains(wgpu::Features::FLOAT32_BLENDABLE) {
            return Err(Error::InvalidScene(format!(
                "the scene has alpha-blended (glTF BLEND) materials, and {} cannot blend into the renderer's 32-bit float HDR \
                 image (no float32-blendable feature); use a GPU or driver that has it, or make those materials OPAQUE or MASK",
                ctx.info.name
            )));
        }
        let device = &ctx.device;
        let desc = shader(methods);
        let module = shaders::create_module(device, &desc)?;
        let fragment_stage = wgpu::ShaderStages::FRAGMENT;
        let background_entries = [
            bindings::texture(0, fragment_stage, wgpu::TextureSampleType::Float { filterable: true }, wgpu::TextureViewDimension::D2),
            bindings::sampler(1, fragment_stage),
        ];
        let entries: &[wgpu::BindGroupLayoutEntry] = if methods.transmission { &background_entries } else { &[] };
        let group_layout = bindings::layout(device, "transparent_shade background", entries);
        let layout = bindings::pipeline_layout(
            device,
            "transparent_shade",
            &[&scene.bind_group_layout, &group_layout, &structures.lights.bind_group_layout, &structures.decals.bind_group_layout],
        );
        let over = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::SrcAlpha,
            dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
            operation: wgpu::BlendOperation::Add,
        };
        // The HDR image's alpha stays 1.
        let keep = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Zero,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let flag = |on: bool| f64::from(u8::from(on));
        let constants = |masked| {
            let own = [methods.debug_views_constant(), ("TRANSMISSION", flag(methods.transmission)), ("ALPHA_MASKED", flag(masked))];
            [&own[..], &methods.material_constants()].concat()
        };
        let (unmasked_constants, masked_constants) = (constants(false), constants(true));
        let module_with = |constants: &[(&str, f64)]| {
            shaders::create_stage_module(device, &desc, naga::ShaderStage::Fragment, "transparent_shade", constants)
        };
        let unmasked_module = module_with(&unmasked_constants)?;
        let any_masked = scene.transparent_draw_commands.iter().chain(&scene.transmissive_draw_commands).any(|c| c.state.alpha_mask);
        let masked_module = any_masked.then(|| module_with(&masked_constants)).transpose()?;
        // The states present, each also mirrored: an animated instance may turn mirrored.
        let states = |commands: &[crate::gpu::scene::DrawCommand]| -> std::collections::BTreeSet<RasterState> {
            commands.iter().flat_map(|c| [c.state, RasterState { mirrored: !c.state.mirrored, ..c.state }]).collect()
        };
        let blended_targets = [Some(wgpu::ColorTargetState {
            format: HDR_FORMAT,
            blend: Some(wgpu::BlendState { color: over, alpha: keep }),
            write_mask: wgpu::ColorWrites::ALL,
        })];
        // Unblended transmissive surfaces replace what they cover (and need no float32 blending).
        let covering_targets = [Some(wgpu::ColorTargetState { format: HDR_FORMAT, blend: None, write_mask: wgpu::ColorWrites::COLOR })];
        let fragment = |state: RasterState, targets| {
            let (module, constants) = match &masked_module {
                Some(module) if state.alpha_mask => (module, &masked_constants),
                _ => (&unmasked_module, &unmasked_constants),
            };
            Some(Fragment { module, entry: "transparent_shade", constants, targets })
        };
        let raster = |write_depth| Raster {
            label: "transparent_shade",
            layout: &layout,
            vertex_module: &module,
            vertex_entry: "forward_vertex",
            // In front of the opaque surface. Not written by blended surfaces, so every layer in
            // front of it blends; written by transmissive ones, whose α of 1 covers what lies behind.
            depth: depth_test(write_depth, wgpu::CompareFunction::Greater),
        };
        let blended = raster(false).per_state(device, states(&scene.transparent_draw_commands), |s| fragment(s, &blended_targets));
        let nearest = raster(true).per_state(device, states(&scene.transmissive_draw_commands), |s| fragment(s, &covering_targets));
        let background = methods.transmission.then(|| TransmissionBackground::new(ctx, hdr)).transpose()?;
        let group = match &background {
            Some(background) => {
                // Trilinear: rough surfaces blend between the chain's levels.
                let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
                    label: Some("transmission background"),
                    mag_filter: wgpu::FilterMode::Linear,
                    min_filter: wgpu::FilterMode::Linear,
                    mipmap_filter: wgpu::MipmapFilterMode::Linear,
                    ..Default::default()
                });
                bindings::bind_group(
                    device,
                    "transparent_shade background",
                    &group_layout,
                    vec![wgpu::BindingResource::TextureView(&background.view), wgpu::BindingResource::Sampler(&sampler)],
                )
            }
            None => bindings::bind_group(device, "transparent_shade background", &group_layout, Vec::new()),
        };
        Ok(Some(Self { blended, nearest, background, group }))
    }

    /// Draws the transmissive, then the blended draws over `hdr`, tested against `depth`, after
    /// copying the opaque image that transmissive ones see through.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, inputs: &FrameInputs, image: ShadedImage) {
        if let Some(background) = &self.background {
            background.record(encoder, timer.as_deref_mut());
        }
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("transparent_shade"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: image.hdr,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: image.depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.map(|t| t.render_pass("transparent_shade")),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(1, &self.group, &[]);
        pass.set_bind_group(2, &inputs.lights.bind_group, &[]);
        pass.set_bind_group(3, &inputs.decals.bind_group, &[]);
        let scene = inputs.scene;
        let draws = &scene.frame_draws;
        super::draw_ordered(&mut pass, scene, &draws.transmissive, &scene.transmissive_draw_commands, &self.nearest);
        super::draw_ordered(&mut pass, scene, &draws.transparent, &scene.transparent_draw_commands, &self.blended);
    }
}
