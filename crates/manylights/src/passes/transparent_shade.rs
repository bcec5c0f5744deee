//! Transparent surfaces over the shaded HDR image, after the opaque ones, in every pipeline.
//! Transmissive surfaces (`KHR_materials_transmission`) see through the opaque image, which
//! `transmission_background` first copies into a mip chain; those that do not blend are shaded in
//! compute by `transmissive_shade` (each pixel its nearest, writing depth, so blended surfaces behind
//! it are hidden as they are behind opaque ones). Then the alpha-blended draws (glTF BLEND,
//! `transparent_shade.wgsl`) are drawn back to front, depth tested and not written; each fragment is
//! lit and decaled by the shading core through the frame's methods, so decals and lights reach them
//! too. The fragment stage is the only place for them: no G-buffer or visibility buffer holds more
//! than one surface per pixel.

use std::collections::HashMap;

use super::builder::{depth_test, Fragment, Raster};
use super::transmission_background::TransmissionBackground;
use super::transmissive_shade::TransmissiveShade;
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
    /// Transmissive draws that do not blend, if any.
    transmissive: Option<TransmissiveShade>,
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
        let fragment_stage = wgpu::ShaderStages::FRAGMENT;
        let background_entries = [
            bindings::texture(0, fragment_stage, wgpu::TextureSampleType::Float { filterable: true }, wgpu::TextureViewDimension::D2),
            bindings::sampler(1, fragment_stage),
        ];
        let sees_through = methods.transmission || !scene.transmissive_draw_commands.is_empty();
        let entries: &[wgpu::BindGroupLayoutEntry] = if sees_through { &background_entries } else { &[] };
        let group_layout = bindings::layout(device, "transparent_shade background", entries);
        let layout = bindings::pipeline_layout(
            device,
            "transparent_shade",
            &[&scene.bind_group_layout, &group_layout, &structures.lights.bind_group_layout, &structures.decals.bind_group_layout],
        );
        let blended =
            if scene.transparent_draw_commands.is_empty() { HashMap::new() } else { blended_pipelines(device, scene, methods, &layout)? };
        let background = sees_through.then(|| TransmissionBackground::new(ctx, hdr)).transpose()?;
        let group = match &background {
            Some(background) => bindings::bind_group(
                device,
                "transparent_shade background",
                &group_layout,
                vec![wgpu::BindingResource::TextureView(&background.view), wgpu::BindingResource::Sampler(&background.sampler)],
            ),
            None => bindings::bind_group(device, "transparent_shade background", &group_layout, Vec::new()),
        };
        let transmissive = match &background {
            Some(background) if !scene.transmissive_draw_commands.is_empty() => {
                Some(TransmissiveShade::new(ctx, scene, methods, structures, hdr, background)?)
            }
            _ => None,
        };
        Ok(Some(Self { blended, transmissive, background, group }))
    }

    /// Shades the transmissive, then draws the blended draws over `hdr`, tested against `depth`,
    /// after copying the opaque image that transmissive ones see through.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, inputs: &FrameInputs, image: ShadedImage) {
        if let Some(background) = &self.background {
            background.record(encoder, timer.as_deref_mut());
        }
        if let Some(transmissive) = &self.transmissive {
            transmissive.record(encoder, timer.as_deref_mut(), inputs, image.depth);
        }
        if self.blended.is_empty() {
            return;
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
        super::draw_ordered(&mut pass, scene, &scene.frame_draws.transparent, &scene.transparent_draw_commands, &self.blended);
    }
}

/// A pipeline for each raster state of the blended draws (and its mirror: an animated instance may
/// turn mirrored), blending "over" into the HDR image.
fn blended_pipelines(
    device: &wgpu::Device,
    scene: &GpuScene,
    methods: ShadingMethods,
    layout: &wgpu::PipelineLayout,
) -> Result<HashMap<RasterState, wgpu::RenderPipeline>> {
    let desc = shader(methods);
    let vertex_module = shaders::create_module(device, &desc)?;
    let flag = |on: bool| f64::from(u8::from(on));
    let constants =
        [&[methods.debug_views_constant(), ("TRANSMISSION", flag(methods.transmission))][..], &methods.material_constants()].concat();
    let module = shaders::create_stage_module(device, &desc, naga::ShaderStage::Fragment, "transparent_shade", &constants)?;
    let states: std::collections::BTreeSet<RasterState> =
        scene.transparent_draw_commands.iter().flat_map(|c| [c.state, RasterState { mirrored: !c.state.mirrored, ..c.state }]).collect();
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
    let targets = [Some(wgpu::ColorTargetState {
        format: HDR_FORMAT,
        blend: Some(wgpu::BlendState { color: over, alpha: keep }),
        write_mask: wgpu::ColorWrites::ALL,
    })];
    let raster = Raster {
        label: "transparent_shade",
        layout,
        vertex_module: &vertex_module,
        vertex_entry: "forward_vertex",
        // In front of the surfaces shaded so far, which are not written, so every layer blends.
        depth: depth_test(false, wgpu::CompareFunction::Greater),
    };
    Ok(raster.per_state(device, states, |_| {
        Some(Fragment { module: &module, entry: "transparent_shade", constants: &constants, targets: &targets })
    }))
}
