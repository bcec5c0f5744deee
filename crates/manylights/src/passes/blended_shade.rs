//! Alpha-blended surfaces (glTF BLEND) in compute (`blended_shade.wgsl`), after the opaque and
//! transmissive ones in every pipeline. The visibility-buffer raster over the blended draws
//! (`visbuffer_blended`, which writes no target) links each fragment in front of the shaded surfaces
//! into its pixel's list of layers (`blended_layers.wgsl`); the HDR image is copied as what lies
//! behind; then a compute pass sorts each pixel's nearest layers far to near, shades each through the
//! shading core and blends it over. A shading loop in fragments costs many times what it costs in
//! compute, and sorting per pixel blends intersecting surfaces as draw order cannot.

use std::collections::{BTreeSet, HashMap};

use super::builder::{depth_test, ComputeStep, Fragment, Raster};
use super::transmission_background::{TransmissionBackground, BACKGROUND_FORMAT};
use super::visbuffer_raster::{draw_visibility, raster_module};
use super::{visbuffer_shade::HDR_FORMAT, FrameInputs, Structures};
use crate::gpu::scene::RasterState;
use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::plan::ShadingMethods;
use crate::{Error, Result};

/// Bytes of a layer (`BlendedLayer`: id, depth, link).
const LAYER_BYTES: u64 = 12;
/// Layers the list first holds per pixel of the image; a frame that needs more grows it.
const FIRST_LAYERS_PER_PIXEL: u64 = 1;

/// The shader for a set of shading methods. Light behind transmissive surfaces comes from the
/// background's mip chain; its bindings are declared even where the `TRANSMISSION` constant leaves
/// them unread, so group 1's bindings run 0, 1, 2, … as the layout's entries do (`gpu/spirv.rs`).
pub fn shader(methods: ShadingMethods) -> ShaderDesc {
    super::shading_core_shader("passes/blended_shade.wgsl", methods, crate::plan::ShadingStage::Compute)
        .with("TRANSMITTED_LIGHT", "shading/transmitted_screen.wgsl")
}

pub struct BlendedShade {
    /// Per raster state of the blended draws (and its mirror: an animated instance may turn mirrored).
    raster: HashMap<RasterState, wgpu::RenderPipeline>,
    indexed: bool,
    step: ComputeStep,
    /// The raster's group 1: the shaded depth and the lists (`visbuffer_raster.wgsl`).
    raster_layout: wgpu::BindGroupLayout,
    raster_group: wgpu::BindGroup,
    /// The compute pass's group 1: the background and its sampler, the lists, `behind`, the output.
    shade_layout: wgpu::BindGroupLayout,
    shade_group: wgpu::BindGroup,
    /// Each pixel's first layer + 1 (0: none).
    heads: wgpu::Buffer,
    layers: wgpu::Buffer,
    /// Layers `layers` holds, and the most one storage binding can.
    capacity: u64,
    max_capacity: u64,
    /// `BlendedLayerStatus`, and where the renderer reads it.
    status: wgpu::Buffer,
    status_readback: wgpu::Buffer,
    hdr: wgpu::Texture,
    /// The HDR image before the blended surfaces: what lies behind them.
    behind: wgpu::Texture,
    views: Views,
}

/// The images the bind groups hold, kept to bind them again when the layers grow.
struct Views {
    /// The shaded surfaces' depth: tested against, and the raster's read-only attachment.
    depth: wgpu::TextureView,
    behind: wgpu::TextureView,
    hdr: wgpu::TextureView,
    /// Bound at group 1's bindings 0 and 1: the transmission background, or a texel standing in
    /// where nothing is transmissive.
    background: wgpu::TextureView,
    sampler: wgpu::Sampler,
}

impl BlendedShade {
    /// The pass over `hdr`, the frame's shaded image, in front of the surfaces in `depth`; with
    /// transmission, blended surfaces see through `background`.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        methods: ShadingMethods,
        structures: Structures,
        (hdr, depth): (&wgpu::Texture, &wgpu::Texture),
        background: Option<&TransmissionBackground>,
    ) -> Result<Self> {
        let device = &ctx.device;
        let (width, height) = (hdr.width(), hdr.height());
        let max_capacity = ctx.limits.max_storage_buffer_binding_size.min(ctx.limits.max_buffer_size) / LAYER_BYTES;
        let capacity = (u64::from(width) * u64::from(height) * FIRST_LAYERS_PER_PIXEL).min(max_capacity);
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        use wgpu::BufferUsages as U;
        let heads = buffer("blended layer heads", u64::from(width) * u64::from(height) * 4, U::STORAGE | U::COPY_DST);
        let layers = buffer("blended layers", capacity * LAYER_BYTES, U::STORAGE);
        let status = buffer("blended layer status", 8, U::STORAGE | U::COPY_SRC | U::COPY_DST);
        let status_readback = buffer("blended layer status readback", 8, U::MAP_READ | U::COPY_DST);
        let behind = crate::gpu::textures::target(
            device,
            "blended behind",
            width,
            height,
            HDR_FORMAT,
            wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let (background, sampler) = match background {
            Some(background) => (background.view.clone(), background.sampler.clone()),
            None => {
                let texel = crate::gpu::textures::target(
                    device,
                    "no transmission background",
                    1,
                    1,
                    BACKGROUND_FORMAT,
                    wgpu::TextureUsages::TEXTURE_BINDING,
                );
                (texel.create_view(&Default::default()), device.create_sampler(&Default::default()))
            }
        };
        let view = |texture: &wgpu::Texture| texture.create_view(&Default::default());
        let views = Views { depth: view(depth), behind: view(&behind), hdr: view(hdr), background, sampler };

        let fragment = wgpu::ShaderStages::FRAGMENT;
        let raster_layout = bindings::layout(
            device,
            "blended_raster",
            &[
                bindings::texture(0, fragment, wgpu::TextureSampleType::Depth, wgpu::TextureViewDimension::D2),
                bindings::storage_read_write(1, fragment),
                bindings::storage_read_write(2, fragment),
                bindings::storage_read_write(3, fragment),
            ],
        );
        let (module, indexed) = raster_module(ctx)?;
        let layout = bindings::pipeline_layout(device, "blended_raster", &[&scene.bind_group_layout, &raster_layout]);
        // The fragment tests depth itself (`append_blended_layer`); the attachment is read only.
        let raster = Raster {
            label: "blended_raster",
            layout: &layout,
            vertex_module: &module,
            vertex_entry: "visbuffer_vertex",
            depth: depth_test(false, wgpu::CompareFunction::Always),
        };
        let states: BTreeSet<RasterState> = scene
            .transparent_draw_commands
            .iter()
            .flat_map(|c| [c.state, RasterState { mirrored: !c.state.mirrored, ..c.state }])
            .collect();
        let raster = raster
            .per_state(device, states, |_| Some(Fragment { module: &module, entry: "visbuffer_blended", constants: &[], targets: &[] }));

        let compute = wgpu::ShaderStages::COMPUTE;
        let shade_layout = bindings::layout(
            device,
            "blended_shade",
            &[
                bindings::texture(0, compute, wgpu::TextureSampleType::Float { filterable: true }, wgpu::TextureViewDimension::D2),
                bindings::sampler(1, compute),
                bindings::storage_read(2, compute),
                bindings::storage_read(3, compute),
                bindings::texture(4, compute, wgpu::TextureSampleType::Float { filterable: false }, wgpu::TextureViewDimension::D2),
                bindings::storage_texture_write(5, compute, HDR_FORMAT),
            ],
        );
        let layouts = [&scene.bind_group_layout, &shade_layout, &structures.lights.bind_group_layout, &structures.decals.bind_group_layout];
        let flag = |on: bool| f64::from(u8::from(on));
        let constants =
            [&[methods.debug_views_constant(), ("TRANSMISSION", flag(methods.transmission))][..], &methods.material_constants()].concat();
        let step = ComputeStep::new(device, &shader(methods), "blended_shade", &layouts, &constants)?;
        let (raster_group, shade_group) = bind_groups(device, (&raster_layout, &shade_layout), &views, [&heads, &layers, &status]);
        Ok(Self {
            raster,
            indexed,
            step,
            raster_layout,
            raster_group,
            shade_layout,
            shade_group,
            heads,
            layers,
            capacity,
            max_capacity,
            status,
            status_readback,
            hdr: hdr.clone(),
            behind,
            views,
        })
    }

    /// Links the blended draws' layers in front of the shaded surfaces, then shades them over the
    /// HDR image.
    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, mut timer: Option<&mut GpuTimer>, inputs: &FrameInputs) {
        let scene = inputs.scene;
        if scene.frame_draws.transparent.commands.is_empty() {
            return;
        }
        encoder.clear_buffer(&self.heads, 0, None);
        // The count of this frame's layers; the most needed stays until the renderer reads it.
        encoder.clear_buffer(&self.status, 0, Some(4));
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("blended_raster"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.views.depth,
                    depth_ops: None,
                    stencil_ops: None,
                }),
                timestamp_writes: timer.as_deref_mut().map(|t| t.render_pass("blended_raster")),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_bind_group(1, &self.raster_group, &[]);
            draw_visibility(&mut pass, scene, &scene.frame_draws.transparent, &scene.transparent_draw_commands, &self.raster, self.indexed);
        }
        encoder.copy_texture_to_texture(self.hdr.as_image_copy(), self.behind.as_image_copy(), self.hdr.size());
        let groups = [&scene.bind_group, &self.shade_group, &inputs.lights.bind_group, &inputs.decals.bind_group];
        self.step.record(encoder, timer, &groups, super::dispatch_size(self.hdr.width(), self.hdr.height()));
    }

    /// Whether the layers held every blended fragment the frames since the last call linked; if
    /// not, grows them (the caller renders those frames again).
    pub fn fitted(&mut self, ctx: &GpuContext) -> Result<bool> {
        let needed = u64::from(crate::gpu::readback::take_most_needed(ctx, &self.status, &self.status_readback)?);
        if needed <= self.capacity {
            return Ok(true);
        }
        if needed > self.max_capacity {
            return Err(Error::InvalidScene(format!(
                "the blended (glTF BLEND) surfaces in this view need {needed} layers ({} MiB), over the {} MiB this GPU's \
                 storage bindings hold; render a smaller image, or make some of those materials OPAQUE or MASK",
                (needed * LAYER_BYTES) >> 20,
                (self.max_capacity * LAYER_BYTES) >> 20,
            )));
        }
        self.capacity = (needed * 5 / 4).min(self.max_capacity);
        let device = &ctx.device;
        self.layers = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("blended layers"),
            size: self.capacity * LAYER_BYTES,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        (self.raster_group, self.shade_group) =
            bind_groups(device, (&self.raster_layout, &self.shade_layout), &self.views, [&self.heads, &self.layers, &self.status]);
        Ok(false)
    }
}

/// The raster's and the compute pass's group 1.
fn bind_groups(
    device: &wgpu::Device,
    (raster_layout, shade_layout): (&wgpu::BindGroupLayout, &wgpu::BindGroupLayout),
    views: &Views,
    [heads, layers, status]: [&wgpu::Buffer; 3],
) -> (wgpu::BindGroup, wgpu::BindGroup) {
    use wgpu::BindingResource as R;
    let raster = bindings::bind_group(
        device,
        "blended_raster",
        raster_layout,
        vec![R::TextureView(&views.depth), heads.as_entire_binding(), layers.as_entire_binding(), status.as_entire_binding()],
    );
    let shade = bindings::bind_group(
        device,
        "blended_shade",
        shade_layout,
        vec![
            R::TextureView(&views.background),
            R::Sampler(&views.sampler),
            heads.as_entire_binding(),
            layers.as_entire_binding(),
            R::TextureView(&views.behind),
            R::TextureView(&views.hdr),
        ],
    );
    (raster, shade)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The layers' and the status's sizes as both the raster and the compute pass read them.
    #[test]
    fn layer_records_match_their_wgsl_layout() {
        for entry in ["passes/visbuffer_raster_indexed.wgsl", "passes/blended_shade.wgsl"] {
            let source = if entry.contains("blended_shade") { shader(ShadingMethods::default()) } else { ShaderDesc::new(entry) };
            let module = naga::front::wgsl::parse_str(&source.compose().unwrap()).unwrap();
            let mut layouter = naga::proc::Layouter::default();
            layouter.update(module.to_ctx()).unwrap();
            let span = |name: &str| {
                let (handle, _) = module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name)).unwrap();
                u64::from(layouter[handle].size)
            };
            assert_eq!(span("BlendedLayer"), LAYER_BYTES, "{entry}");
            assert_eq!(span("BlendedLayerStatus"), 8, "{entry}: the status buffer's size");
        }
    }
}
