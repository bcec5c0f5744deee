//! Render and compute passes, one file each with its WGSL beside it. A pass is built once (pipelines,
//! layouts, bind groups over its targets) and recorded each frame by `record`, under a timestamp scope
//! named like its file and its WGSL entry point.

use std::collections::HashMap;

use crate::accel::VolumeStructure;
use crate::gpu::{
    scene::{DrawCommand, OrderedDraws, RasterState, DRAW_ARGUMENT_BYTES},
    shaders::ShaderDesc,
    GpuScene,
};
use crate::plan::{query_walks, volume_query_module, ShadingMethods, ShadingStage};

pub mod blended_shade;
pub mod builder;
#[cfg(test)]
pub mod catalogue;
pub mod deferred_decals;
pub mod deferred_shade;
pub mod deform;
pub mod denoise;
pub mod depth_prepass;
pub mod forward_shade;
pub mod gbuffer_raster;
pub mod ray_shadows;
pub mod shadow_filter;
pub mod surface_motion;
pub mod transmission_background;
pub mod transmissive_shade;
pub mod transparent_shade;
pub mod visbuffer_raster;
pub mod visbuffer_shade;

/// A pass's shader that calls the shading core, composed with the WGSL modules of its methods
/// (`shading/shade.wgsl` includes `$LIGHT_ENUMERATION`, `$DECAL_ENUMERATION` and `$PARTICLE_LIGHTING`,
/// the light modules `$DIRECT_LIGHTING`, rays `$RAY_TRACE`, and `shading/transmission.wgsl`
/// `$TRANSMITTED_LIGHT`, which only the transmissive and transparent passes give a source; the opaque surfaces' shading
/// passes include `$REFLECTIONS`)
/// and of its point queries' walks ([`query_walks`]: `$LIGHT_QUERY`, `$DECAL_QUERY`, `$DECAL_LEAVES`).
pub fn shading_core_shader(entry: &'static str, methods: ShadingMethods, stage: ShadingStage) -> ShaderDesc {
    let walks = query_walks(methods, stage);
    ShaderDesc::new(entry)
        .with("LIGHT_ENUMERATION", methods.light_enumeration_module())
        .with("DECAL_ENUMERATION", methods.decal_enumeration_module())
        .with("PARTICLE_LIGHTING", methods.particle_lighting_module())
        .with("REFLECTIONS", if methods.reflections { "shading/reflections.wgsl" } else { "shading/reflections_off.wgsl" })
        .with("TRANSMITTED_LIGHT", "shading/transmitted_none.wgsl")
        .with("DIRECT_LIGHTING", methods.direct.module())
        .with("RAY_TRACE", methods.ray_trace_module())
        .with("LIGHT_QUERY", volume_query_module(walks.lights))
        .with("DECAL_QUERY", volume_query_module(walks.decals))
        .with(
            "DECAL_LEAVES",
            if walks.decal_leaves_shared_out {
                "shading/enumerate/decal_leaves_shared_out.wgsl"
            } else {
                "shading/enumerate/decal_leaves_each.wgsl"
            },
        )
}

/// What a frame reads besides its pipeline's own images: the scene, the light and decal structures
/// (bound as groups 2 and 3 by the shading passes), and the frame's parity, which picks the halves of
/// what passes keep from frame to frame.
#[derive(Clone, Copy)]
pub struct FrameInputs<'a> {
    pub scene: &'a GpuScene,
    pub lights: &'a VolumeStructure,
    pub decals: &'a VolumeStructure,
    pub parity: usize,
}

/// The light and decal structures, bound as groups 2 and 3 by the shading passes.
#[derive(Clone, Copy)]
pub struct Structures<'a> {
    pub lights: &'a VolumeStructure,
    pub decals: &'a VolumeStructure,
}

/// The HDR image a raster shading pass writes, and the depth image it tests against.
#[derive(Clone, Copy)]
pub struct ShadedImage<'a> {
    pub hdr: &'a wgpu::TextureView,
    pub depth: &'a wgpu::TextureView,
}

/// Workgroup edge of the 2D compute passes (`@workgroup_size(8, 8)` in their WGSL).
pub const TILE: u32 = 8;

pub fn dispatch_size(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(TILE), height.div_ceil(TILE))
}

/// Draws the scene's opaque draws indexed, in the frame's order (`GpuScene::order_draws`), with the
/// pipeline of each draw's raster state; binds the scene as group 0.
pub fn draw_scene(pass: &mut wgpu::RenderPass, scene: &GpuScene, pipelines: &HashMap<RasterState, wgpu::RenderPipeline>) {
    draw_ordered(pass, scene, &scene.frame_draws.opaque, &scene.draw_commands, pipelines);
}

/// Draws `draws` of `commands` indexed, in order, with the pipeline of each run's raster state: a run
/// in one indirect call where the scene has indirect arguments, a call per draw otherwise. Binds the
/// scene as group 0.
pub fn draw_ordered(
    pass: &mut wgpu::RenderPass,
    scene: &GpuScene,
    draws: &OrderedDraws,
    commands: &[DrawCommand],
    pipelines: &HashMap<RasterState, wgpu::RenderPipeline>,
) {
    pass.set_bind_group(0, &scene.bind_group, &[]);
    pass.set_index_buffer(scene.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
    for &(state, first, count) in &draws.runs {
        pass.set_pipeline(&pipelines[&state]);
        match &scene.draw_arguments {
            Some(arguments) => {
                let offset = u64::from(draws.first_argument + first) * DRAW_ARGUMENT_BYTES;
                pass.multi_draw_indexed_indirect(arguments, offset, count);
            }
            None => {
                for &c in &draws.commands[first as usize..(first + count) as usize] {
                    let command = &commands[c as usize];
                    let draw = command.draw_index..command.draw_index + 1;
                    pass.draw_indexed(command.first_index..command.first_index + command.index_count, command.base_vertex as i32, draw);
                }
            }
        }
    }
}
