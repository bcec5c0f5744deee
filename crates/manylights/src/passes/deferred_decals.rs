//! Deferred decals (Kim 2012, `deferred_decals.wgsl`): every decal's box rasterised over the
//! G-buffer, blending into albedo, normal and roughness-metallic before lighting. The deferred
//! pipeline's `--decal-method deferred-decals`; the other pipelines have no G-buffer to blend into.

use wgpu::util::DeviceExt;

use super::{gbuffer_raster::GBUFFER_FORMATS, visbuffer_raster::DEPTH_FORMAT};
use crate::accel::VolumeStructure;
use crate::gpu::{bindings, shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

/// Vertices of a box: 12 triangles.
const BOX_VERTICES: u32 = 36;

pub struct DeferredDecals {
    /// For boxes away from the eye, and for boxes around it.
    pipelines: [wgpu::RenderPipeline; 2],
    bind_group: wgpu::BindGroup,
    /// An empty group 2: the pass reads no lights.
    no_lights: wgpu::BindGroup,
    /// The draws of each layer, bottom first: instance ranges of the draw order.
    layers: Vec<std::ops::Range<u32>>,
}

impl DeferredDecals {
    /// `surface_normals` is the copy of the G-buffer's normals the fragments read (the normal target
    /// itself is being blended).
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        decals: &VolumeStructure,
        depth: &wgpu::TextureView,
        surface_normals: &wgpu::TextureView,
    ) -> Result<Self> {
        let device = &ctx.device;
        let desc = ShaderDesc::new("passes/deferred_decals.wgsl");
        let module = shaders::create_module(device, &desc)?;
        let fragment_module = shaders::create_stage_module(device, &desc, naga::ShaderStage::Fragment, "deferred_decal_fragment", &[])?;
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let vertex = wgpu::ShaderStages::VERTEX;
        // Keep in sync with group 1 of `deferred_decals.wgsl`.
        let layout = bindings::layout(
            device,
            "deferred_decals",
            &[
                bindings::texture(0, fragment, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2),
                bindings::texture(1, fragment, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2),
                bindings::storage_read(2, vertex),
            ],
        );
        let empty = bindings::layout(device, "no lights", &[]);
        let pipeline_layout =
            bindings::pipeline_layout(device, "deferred_decals", &[&scene.bind_group_layout, &layout, &empty, &decals.bind_group_layout]);
        // Over blending on the three attributes decals change; each output's alpha is its coverage,
        // never written (the albedo target's alpha holds the surface's occlusion).
        let over = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::SrcAlpha,
            dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
            operation: wgpu::BlendOperation::Add,
        };
        let target = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: Some(wgpu::BlendState { color: over, alpha: over }),
                write_mask: wgpu::ColorWrites::COLOR,
            })
        };
        let targets = [target(GBUFFER_FORMATS[0]), target(GBUFFER_FORMATS[1]), target(GBUFFER_FORMATS[2])];
        let pipeline = |around_the_eye: bool| {
            // Away from the eye: front faces in front of the surface (reverse Z), each covered pixel
            // once; the fragment stage discards but writes no depth, so occluded fragments are still
            // rejected early. Around the eye: back faces, untested (`deferred_decals.wgsl`).
            let (cull, compare) = if around_the_eye {
                (wgpu::Face::Front, wgpu::CompareFunction::Always)
            } else {
                (wgpu::Face::Back, wgpu::CompareFunction::GreaterEqual)
            };
            let constants = [("AROUND_THE_EYE", if around_the_eye { 1.0 } else { 0.0 })];
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("deferred_decals"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("deferred_decal_vertex"),
                    compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() },
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState { cull_mode: Some(cull), ..Default::default() },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &fragment_module,
                    entry_point: Some("deferred_decal_fragment"),
                    compilation_options: Default::default(),
                    targets: &targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let pipelines = [pipeline(false), pipeline(true)];
        let (order, layers) = decals.pairs_in_layer_order()?;
        let order_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("deferred decal order"),
            contents: if order.is_empty() { &[0; 8] } else { bytemuck::cast_slice(&order) },
            usage: wgpu::BufferUsages::STORAGE,
        });
        let bind_group = bindings::bind_group(
            device,
            "deferred_decals",
            &layout,
            vec![
                wgpu::BindingResource::TextureView(depth),
                wgpu::BindingResource::TextureView(surface_normals),
                order_buffer.as_entire_binding(),
            ],
        );
        let no_lights = bindings::bind_group(device, "no lights", &empty, Vec::new());
        Ok(Self { pipelines, bind_group, no_lights, layers })
    }

    /// Blends the decals into the first three G-buffer targets (albedo, normal, roughness-metallic).
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        scene: &GpuScene,
        decals: &VolumeStructure,
        gbuffer: &[wgpu::TextureView; super::gbuffer_raster::GBUFFER_TARGETS],
        depth: &wgpu::TextureView,
    ) {
        let attachments = gbuffer[..3]
            .iter()
            .map(|view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
                })
            })
            .collect::<Vec<_>>();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("deferred_decals"),
            color_attachments: &attachments,
            // Read-only: the fragments also read it as a texture.
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment { view: depth, depth_ops: None, stencil_ops: None }),
            timestamp_writes: timer.map(|t| t.render_pass("deferred_decals")),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(0, &scene.bind_group, &[]);
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.set_bind_group(2, &self.no_lights, &[]);
        pass.set_bind_group(3, &decals.bind_group, &[]);
        // Layer after layer, bottom first; each vertex stage skips the other pipeline's boxes.
        for layer in &self.layers {
            for pipeline in &self.pipelines {
                pass.set_pipeline(pipeline);
                pass.draw(0..BOX_VERTICES, layer.clone());
            }
        }
    }
}
