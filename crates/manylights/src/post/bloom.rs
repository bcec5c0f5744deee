//! Bloom: `bloom_downsample` down a chain of half-resolution levels, then `bloom_upsample` back up,
//! in one compute pass. See `bloom.wgsl`.

use crate::gpu::{bindings, shaders::ShaderDesc, GpuContext, GpuScene, GpuTimer};
use crate::Result;

/// The chain's levels: 16-bit float, filtered by hand like the full image.
const BLOOM_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Most levels, and the smallest edge a level may have.
const MAX_LEVELS: u32 = 7;
const MIN_LEVEL_EDGE: u32 = 8;

pub struct BloomPass {
    first_downsample: wgpu::ComputePipeline,
    downsample: wgpu::ComputePipeline,
    upsample: wgpu::ComputePipeline,
    /// Each dispatch in order: its stage, bind group and size in texels.
    steps: Vec<BloomStep>,
    /// The top level after the climb: what the tonemap blends in.
    pub result: wgpu::TextureView,
    pub levels: u32,
}

enum BloomStage {
    FirstDownsample,
    Downsample,
    Upsample,
}

struct BloomStep {
    stage: BloomStage,
    bind_group: wgpu::BindGroup,
    size: (u32, u32),
}

/// The levels of a `width`×`height` image's chain: halving until an edge would drop below
/// `MIN_LEVEL_EDGE`, at least one.
pub fn bloom_levels(width: u32, height: u32) -> u32 {
    let mut levels = 1;
    let mut edge = (width.min(height) / 2).max(1);
    while levels < MAX_LEVELS && edge / 2 >= MIN_LEVEL_EDGE {
        edge /= 2;
        levels += 1;
    }
    levels
}

impl BloomPass {
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        uniforms: &wgpu::Buffer,
        input: &wgpu::TextureView,
        (width, height): (u32, u32),
    ) -> Result<Self> {
        let device = &ctx.device;
        let c = wgpu::ShaderStages::COMPUTE;
        let unfilterable = wgpu::TextureSampleType::Float { filterable: false };
        let d2 = wgpu::TextureViewDimension::D2;
        // Keep in sync with `bloom.wgsl`.
        let layout = bindings::layout(
            device,
            "bloom",
            &[
                bindings::uniform(0, c),
                bindings::texture(1, c, unfilterable, d2),
                bindings::texture(2, c, unfilterable, d2),
                bindings::storage_texture_write(3, c, BLOOM_FORMAT),
            ],
        );
        let shader = ShaderDesc::new("post/bloom.wgsl");
        let layouts = [&scene.bind_group_layout, &layout];
        let first_downsample =
            bindings::compute_pipeline_with_constants(device, "bloom_downsample", &shader, &layouts, &[("FIRST_LEVEL", 1.0)])?;
        let downsample = bindings::compute_pipeline(device, "bloom_downsample", &shader, &layouts)?;
        let upsample = bindings::compute_pipeline(device, "bloom_upsample", &shader, &layouts)?;

        let levels = bloom_levels(width, height);
        let chain = |label| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width: (width / 2).max(1), height: (height / 2).max(1), depth_or_array_layers: 1 },
                mip_level_count: levels,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: BLOOM_FORMAT,
                usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        };
        let (down, up) = (chain("bloom downsampled"), chain("bloom upsampled"));
        let level_view = |texture: &wgpu::Texture, level: u32| {
            texture.create_view(&wgpu::TextureViewDescriptor { base_mip_level: level, mip_level_count: Some(1), ..Default::default() })
        };
        let down_views: Vec<_> = (0..levels).map(|l| level_view(&down, l)).collect();
        let up_views: Vec<_> = (0..levels).map(|l| level_view(&up, l)).collect();
        let size_of = |level: u32| (((width / 2) >> level).max(1), ((height / 2) >> level).max(1));
        let group = |source: &wgpu::TextureView, base: &wgpu::TextureView, output: &wgpu::TextureView| {
            bindings::bind_group(
                device,
                "bloom",
                &layout,
                vec![
                    uniforms.as_entire_binding(),
                    wgpu::BindingResource::TextureView(source),
                    wgpu::BindingResource::TextureView(base),
                    wgpu::BindingResource::TextureView(output),
                ],
            )
        };
        let mut steps = Vec::new();
        for level in 0..levels {
            // Downsampling reads no base: the source stands in.
            let source = if level == 0 { input } else { &down_views[level as usize - 1] };
            let stage = if level == 0 { BloomStage::FirstDownsample } else { BloomStage::Downsample };
            steps.push(BloomStep { stage, bind_group: group(source, source, &down_views[level as usize]), size: size_of(level) });
        }
        for level in (0..levels.saturating_sub(1)).rev() {
            let below = level as usize + 1;
            let source = if below == levels as usize - 1 { &down_views[below] } else { &up_views[below] };
            steps.push(BloomStep {
                stage: BloomStage::Upsample,
                bind_group: group(source, &down_views[level as usize], &up_views[level as usize]),
                size: size_of(level),
            });
        }
        let result = if levels == 1 { level_view(&down, 0) } else { level_view(&up, 0) };
        Ok(Self { first_downsample, downsample, upsample, steps, result, levels })
    }

    pub fn record(&self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>, scene: &GpuScene) {
        // One pass: wgpu orders each dispatch's reads after the previous dispatches' writes.
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("bloom"),
            timestamp_writes: timer.map(|t| t.compute_pass("bloom")),
        });
        pass.set_bind_group(0, &scene.bind_group, &[]);
        for step in &self.steps {
            pass.set_pipeline(match step.stage {
                BloomStage::FirstDownsample => &self.first_downsample,
                BloomStage::Downsample => &self.downsample,
                BloomStage::Upsample => &self.upsample,
            });
            pass.set_bind_group(1, &step.bind_group, &[]);
            let (x, y) = crate::passes::dispatch_size(step.size.0, step.size.1);
            pass.dispatch_workgroups(x, y, 1);
        }
    }
}
