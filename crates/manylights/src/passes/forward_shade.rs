//! Forward shading in the fragment stage (`forward_shade.wgsl`): the scene drawn again over the depth
//! prepass's depth with an EQUAL test, each fragment lit by the shading core, then the sky where no
//! geometry is. On our benchmark GPUs fragment shading is far slower than the compute resolve; the
//! pipeline exists for comparison (and, later, for transparent surfaces).

use std::collections::HashMap;

use super::builder::{depth_test, Fragment, Raster};
use super::{visbuffer_shade::HDR_FORMAT, FrameInputs, ShadedImage, Structures};
use crate::gpu::scene::RasterState;
use crate::gpu::{bindings, shaders, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::passes::ray_shadows::{self, RayShadows};
use crate::plan::ShadingMethods;
use crate::Result;

/// The shader for a set of shading methods.
pub fn shader(methods: ShadingMethods) -> ShaderDesc {
    super::shading_core_shader("passes/forward_shade.wgsl", methods, crate::plan::ShadingStage::Fragment)
        .testing_depth_first(methods.keeps_pixel_state)
}

pub struct ForwardShade {
    pipelines: HashMap<RasterState, wgpu::RenderPipeline>,
    sky: wgpu::RenderPipeline,
    /// Group 1: the sun's visibility mask (the shading core's light and decal bindings are groups 2
    /// and 3 everywhere).
    bind_group: wgpu::BindGroup,
}

impl ForwardShade {
    /// The light and decal structures are bound as groups 2 and 3, as in the compute resolve;
    /// `shadows` are the sun's ray-traced shadows, if the frame has them.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        methods: ShadingMethods,
        structures: Structures,
        shadows: Option<&RayShadows>,
    ) -> Result<Self> {
        let device = &ctx.device;
        let desc = shader(methods);
        let module = shaders::create_module(device, &desc)?;
        let group = bindings::layout(device, "forward_shade", &[ray_shadows::shading_mask_entry(0, wgpu::ShaderStages::FRAGMENT)]);
        let layout = bindings::pipeline_layout(
            device,
            "forward_shade",
            &[&scene.bind_group_layout, &group, &structures.lights.bind_group_layout, &structures.decals.bind_group_layout],
        );
        let (mask, has_mask) = ray_shadows::shading_mask_binding(device, shadows);
        let constants = [
            &[("SUN_SHADOW_MASK", has_mask), methods.debug_views_constant(), methods.denoised_constant()][..],
            &methods.material_constants(),
        ]
        .concat();
        // One fragment module per entry point, shared by the raster states' pipelines.
        let fragment = |entry: &'static str| -> Result<_> {
            Ok((shaders::create_stage_module(device, &desc, naga::ShaderStage::Fragment, entry, &constants)?, entry))
        };
        let modules = [fragment("forward_opaque")?, fragment("forward_masked")?, fragment("forward_sky")?];
        let targets = [Some(HDR_FORMAT.into())];
        let [opaque, masked, sky] =
            modules.each_ref().map(|(module, entry)| Fragment { module, entry, constants: &constants, targets: &targets });
        let raster = |label, vertex_entry| Raster {
            label,
            layout: &layout,
            vertex_module: &module,
            vertex_entry,
            // EQUAL against the prepass's depth: only the visible fragment of each pixel is shaded.
            depth: depth_test(false, wgpu::CompareFunction::Equal),
        };
        let pipelines = raster("forward_shade", "forward_vertex")
            .per_state(device, RasterState::all(), |state| Some(if state.alpha_mask { masked } else { opaque }));
        let sky = raster("forward_sky", "forward_sky_vertex").pipeline(device, wgpu::PrimitiveState::default(), Some(sky));
        let bind_group = bindings::bind_group(device, "forward_shade", &group, vec![wgpu::BindingResource::TextureView(&mask)]);
        Ok(Self { pipelines, sky, bind_group })
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, inputs: &FrameInputs, image: ShadedImage) {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("forward_shade"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: image.hdr,
                depth_slice: None,
                resolve_target: None,
                // Every pixel is written: by a surface or by the sky.
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: image.depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.map(|t| t.render_pass("forward_shade")),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_bind_group(1, &self.bind_group, &[]);
        pass.set_bind_group(2, &inputs.lights.bind_group, &[]);
        pass.set_bind_group(3, &inputs.decals.bind_group, &[]);
        super::draw_scene(&mut pass, inputs.scene, &self.pipelines);
        pass.set_pipeline(&self.sky);
        pass.draw(0..3, 0..1);
    }
}
