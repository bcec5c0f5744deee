//! Render and compute passes, one file each with its WGSL beside it. A pass is built once (pipelines,
//! layouts, bind groups over its targets) and recorded each frame by `record`, under a timestamp scope
//! named like its file and its WGSL entry point.

use std::collections::HashMap;

use crate::gpu::{
    scene::{DrawCommand, RasterState},
    shaders::ShaderDesc,
    GpuScene,
};
use crate::pipelines::ShadingMethods;

pub mod deferred_decals;
pub mod deferred_shade;
pub mod deform;
pub mod depth_prepass;
pub mod forward_shade;
pub mod gbuffer_raster;
pub mod ray_shadows;
pub mod shadow_filter;
pub mod transparent_shade;
pub mod visbuffer_raster;
pub mod visbuffer_shade;

/// A pass's shader that calls the shading core, composed with the WGSL modules of its methods
/// (`shading/shade.wgsl` includes `$LIGHT_ENUMERATION`, `$DECAL_ENUMERATION` and `$PARTICLE_LIGHTING`,
/// the light modules `$LIGHT_SHADOWS`; the opaque surfaces' shading passes include `$REFLECTIONS`)
/// and of its point queries' walks ([`query_walks`]: `$LIGHT_QUERY`, `$DECAL_QUERY`, `$DECAL_LEAVES`).
pub fn shading_core_shader(entry: &'static str, methods: ShadingMethods, stage: ShadingStage) -> ShaderDesc {
    let walks = query_walks(methods, stage);
    ShaderDesc::new(entry)
        .with("LIGHT_ENUMERATION", methods.lights.enumeration_module())
        .with("DECAL_ENUMERATION", decal_enumeration_module(methods))
        .with("PARTICLE_LIGHTING", methods.particles.lighting_module())
        .with("REFLECTIONS", if methods.reflections { "shading/reflections.wgsl" } else { "shading/reflections_off.wgsl" })
        .with("LIGHT_SHADOWS", if methods.light_shadows { "shading/light_shadows.wgsl" } else { "shading/light_shadows_off.wgsl" })
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

/// The module that defines `apply_decals`: the decal method's, or, for `bvh` decals with cell lists
/// where subgroups share them out, the one that reads the lists.
fn decal_enumeration_module(methods: ShadingMethods) -> &'static str {
    if methods.decals == crate::pipelines::DecalMethod::Bvh && methods.decal_cell_lists && methods.subgroups {
        "shading/enumerate/decals_bvh_cells.wgsl"
    } else {
        methods.decals.enumeration_module()
    }
}

/// The shader stage a pass shades in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadingStage {
    Compute,
    Fragment,
}

/// Which structures a pass's point queries walk a subgroup at a time (where the device has subgroup
/// operations), as measured on the H100 (BENCHMARKS.md, "Subgroup walks", "Dense decals' leaves shared
/// out"): a walk shared by the subgroup loads each node once for all its lanes, but lanes that need
/// nothing wait for it, and each item any lane finds is processed in a round of its own. It pays for
/// dense lights (particles as exact lights: hundreds reach every point) in every stage, for decals in
/// fragments, whose lanes walking alone diverge most, and for dense decals in compute, whose leaves the
/// lanes then share out, each testing one decal against the box around all their points; not for
/// sparse lights, nor for sparse decals in compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QueryWalks {
    pub lights: bool,
    pub decals: bool,
    /// The decals' leaves are shared out among the lanes (`shading/enumerate/decal_leaves_shared_out.wgsl`);
    /// otherwise each lane tests every decal of the leaves it gets (`decal_leaves_each.wgsl`).
    pub decal_leaves_shared_out: bool,
}

/// From how many boxes hold a decal's centre, on average ([`crate::accel::VolumeStructure::centre_overlap`]),
/// decals count as dense ([`ShadingMethods::dense_decals`]). Over Sponza, ≈ 1 m decals give 20.5 at
/// 50,000 decals, where sharing their leaves out shaded as fast as walking alone (0.689 against 0.692
/// ms in the visibility buffer on the H100), and 28.1 at 70,000, where it was 5 % faster; 100 decals
/// give 1.0, which shared out were 12 % slower in fragments (BENCHMARKS.md, "Dense decals' leaves
/// shared out").
pub const DENSE_DECAL_OVERLAP: f32 = 24.0;

pub fn query_walks(methods: ShadingMethods, stage: ShadingStage) -> QueryWalks {
    let dense_lights = methods.particles == crate::pipelines::ParticleMethod::Bvh;
    let dense_decals = methods.subgroups && methods.dense_decals;
    QueryWalks {
        lights: methods.subgroups && dense_lights,
        decals: dense_decals || (methods.subgroups && stage == ShadingStage::Fragment),
        decal_leaves_shared_out: dense_decals,
    }
}

/// A point query module: walked by a whole subgroup, or by each invocation alone.
pub fn volume_query_module(subgroups: bool) -> &'static str {
    if subgroups {
        "accel/volume_query_subgroup.wgsl"
    } else {
        "accel/volume_query_invocation.wgsl"
    }
}

/// Workgroup edge of the 2D compute passes (`@workgroup_size(8, 8)` in their WGSL).
pub const TILE: u32 = 8;

pub fn dispatch_size(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(TILE), height.div_ceil(TILE))
}

/// Draws the scene's opaque draws indexed, in `GpuScene::draw_order`, with the pipeline of each
/// draw's raster state; binds the scene as group 0.
pub fn draw_scene(pass: &mut wgpu::RenderPass, scene: &GpuScene, eye: glam::Vec3, pipelines: &HashMap<RasterState, wgpu::RenderPipeline>) {
    draw_commands(pass, scene, &scene.draw_order(eye), pipelines);
}

/// Draws `commands` indexed, in order, with the pipeline of each draw's raster state; binds the scene
/// as group 0.
pub fn draw_commands(
    pass: &mut wgpu::RenderPass,
    scene: &GpuScene,
    commands: &[&DrawCommand],
    pipelines: &HashMap<RasterState, wgpu::RenderPipeline>,
) {
    pass.set_bind_group(0, &scene.bind_group, &[]);
    pass.set_index_buffer(scene.index_buffer.slice(..), wgpu::IndexFormat::Uint32);
    let mut current = None;
    for &command in commands {
        if current != Some(command.state) {
            pass.set_pipeline(&pipelines[&command.state]);
            current = Some(command.state);
        }
        let draw = command.draw_index..command.draw_index + 1;
        pass.draw_indexed(command.first_index..command.first_index + command.index_count, command.base_vertex as i32, draw);
    }
}
