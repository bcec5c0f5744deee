//! Visibility-buffer raster: depth and a visibility id (draw and triangle) per pixel. See
//! `visbuffer_raster.wgsl`: indexed draws where the device has `primitive_index`, pulled vertices
//! otherwise.

use std::collections::HashMap;

use super::builder::{nearest_depth, Fragment, Raster};
use crate::gpu::scene::{DrawCommand, OrderedDraws, RasterState, NO_VISIBILITY_ID};
use crate::gpu::{bindings, shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

pub const VISIBILITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

pub struct VisbufferRaster {
    pipelines: HashMap<RasterState, wgpu::RenderPipeline>,
    indexed: bool,
}

/// The images the raster writes: the visibility ids and the depth.
pub struct VisbufferImages<'a> {
    pub visibility: &'a wgpu::TextureView,
    pub depth: &'a wgpu::TextureView,
}

impl VisbufferRaster {
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Result<Self> {
        let (module, indexed) = raster_module(ctx)?;
        let layout = bindings::pipeline_layout(&ctx.device, "visbuffer_raster", &[&scene.bind_group_layout]);
        let raster = Raster {
            label: "visbuffer_raster",
            layout: &layout,
            vertex_module: &module,
            vertex_entry: "visbuffer_vertex",
            depth: nearest_depth(),
        };
        let targets = [Some(VISIBILITY_FORMAT.into())];
        let pipelines = raster.per_state(&ctx.device, RasterState::all(), |state| {
            let entry = if state.alpha_mask { "visbuffer_masked" } else { "visbuffer_opaque" };
            Some(Fragment { module: &module, entry, constants: &[], targets: &targets })
        });
        Ok(Self { pipelines, indexed })
    }

    /// The opaque draws: depth cleared, ids left as they were where nothing is drawn.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, scene: &GpuScene, images: VisbufferImages) {
        // Ids are not cleared: shading reads them only where depth says a triangle was drawn, and a
        // clear costs a sizeable share of this output-bound pass.
        let loads = (wgpu::LoadOp::Load, wgpu::LoadOp::Clear(0.0));
        let mut pass = begin(encoder, timer, "visbuffer_raster", images, loads);
        self.draw(&mut pass, scene, &scene.frame_draws.opaque, &scene.draw_commands);
    }

    /// The transmissive draws that do not blend (`transmissive_shade`), nearest first, over the
    /// opaque surfaces' depth: ids cleared to `NO_VISIBILITY_ID` where none is in front.
    pub fn record_transmissive(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        scene: &GpuScene,
        images: VisbufferImages,
    ) {
        let none = wgpu::Color { r: f64::from(NO_VISIBILITY_ID), g: 0.0, b: 0.0, a: 0.0 };
        let loads = (wgpu::LoadOp::Clear(none), wgpu::LoadOp::Load);
        let mut pass = begin(encoder, timer, "transmissive_raster", images, loads);
        self.draw(&mut pass, scene, &scene.frame_draws.transmissive, &scene.transmissive_draw_commands);
    }

    fn draw(&self, pass: &mut wgpu::RenderPass, scene: &GpuScene, draws: &OrderedDraws, commands: &[DrawCommand]) {
        draw_visibility(pass, scene, draws, commands, &self.pipelines, self.indexed);
    }
}

/// The raster's shader module, and whether it draws indexed: indexed draws transform shared
/// vertices once, a faster raster (benchmarks/LOG.md, topic 5), where the device has
/// `primitive_index`; pulled vertices otherwise.
pub fn raster_module(ctx: &GpuContext) -> Result<(wgpu::ShaderModule, bool)> {
    let indexed = ctx.features.contains(wgpu::Features::PRIMITIVE_INDEX);
    let entry = if indexed { "passes/visbuffer_raster_indexed.wgsl" } else { "passes/visbuffer_raster_pulled.wgsl" };
    Ok((shaders::create_module(&ctx.device, &ShaderDesc::new(entry))?, indexed))
}

/// Draws `draws` with `pipelines` built from [`raster_module`], `indexed` as it says.
pub fn draw_visibility(
    pass: &mut wgpu::RenderPass,
    scene: &GpuScene,
    draws: &OrderedDraws,
    commands: &[DrawCommand],
    pipelines: &HashMap<RasterState, wgpu::RenderPipeline>,
    indexed: bool,
) {
    if indexed {
        super::draw_ordered(pass, scene, draws, commands, pipelines);
        return;
    }
    // Pulled vertices: a call per draw, each vertex_index a corner of its range of the indices.
    pass.set_bind_group(0, &scene.bind_group, &[]);
    for &(state, first, count) in &draws.runs {
        pass.set_pipeline(&pipelines[&state]);
        for &c in &draws.commands[first as usize..(first + count) as usize] {
            let command = &commands[c as usize];
            pass.draw(0..command.index_count, command.draw_index..command.draw_index + 1);
        }
    }
}

/// The raster's render pass over `images`, loading the ids and the depth as `loads` says.
fn begin<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    timer: Option<&mut GpuTimer>,
    label: &'static str,
    VisbufferImages { visibility, depth }: VisbufferImages,
    (ids, depth_load): (wgpu::LoadOp<wgpu::Color>, wgpu::LoadOp<f32>),
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: visibility,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: ids, store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations { load: depth_load, store: wgpu::StoreOp::Store }),
            stencil_ops: None,
        }),
        timestamp_writes: timer.map(|t| t.render_pass(label)),
        occlusion_query_set: None,
        multiview_mask: None,
    })
}
