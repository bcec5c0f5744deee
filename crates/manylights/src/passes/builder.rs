//! What every pass builds the same way, so that a pass file states only its shader, its inputs and
//! outputs and its dispatch: a compute step recorded in a pass of its own, and raster pipelines over
//! the scene's draws, one per raster state.

use std::collections::HashMap;

use super::visbuffer_raster::DEPTH_FORMAT;
use crate::gpu::{bindings, scene::RasterState, shaders::ShaderDesc, GpuTimer};
use crate::Result;

/// One compute dispatch in a pass of its own, labelled and timed by its entry point's name.
pub struct ComputeStep {
    entry: &'static str,
    pipeline: wgpu::ComputePipeline,
}

impl ComputeStep {
    /// The step running `entry` of `shader` over bind groups of `layouts`, with values for the
    /// shader's `override` constants.
    pub fn new(
        device: &wgpu::Device,
        shader: &ShaderDesc,
        entry: &'static str,
        layouts: &[&wgpu::BindGroupLayout],
        constants: &[(&str, f64)],
    ) -> Result<Self> {
        let pipeline = bindings::compute_pipeline_with_constants(device, entry, shader, layouts, constants)?;
        Ok(Self { entry, pipeline })
    }

    /// Records `workgroups` (x, y) with `groups` bound from group 0 on.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: Option<&mut GpuTimer>,
        groups: &[&wgpu::BindGroup],
        workgroups: (u32, u32),
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.entry),
            timestamp_writes: timer.map(|t| t.compute_pass(self.entry)),
        });
        pass.set_pipeline(&self.pipeline);
        for (index, group) in groups.iter().enumerate() {
            pass.set_bind_group(index as u32, *group, &[]);
        }
        pass.dispatch_workgroups(workgroups.0, workgroups.1, 1);
    }
}

/// The depth test of a raster pass against the frame's depth image (reverse Z: nearer is greater).
pub fn depth_test(write: bool, compare: wgpu::CompareFunction) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: Default::default(),
        bias: Default::default(),
    }
}

/// The depth test of passes that draw the nearest surface and write its depth.
pub fn nearest_depth() -> wgpu::DepthStencilState {
    depth_test(true, wgpu::CompareFunction::Greater)
}

/// A fragment stage: its module and entry point, values for its `override` constants, its targets.
#[derive(Clone, Copy)]
pub struct Fragment<'a> {
    pub module: &'a wgpu::ShaderModule,
    pub entry: &'a str,
    pub constants: &'a [(&'a str, f64)],
    pub targets: &'a [Option<wgpu::ColorTargetState>],
}

/// A raster pipeline's fixed parts: its label, layout, vertex stage and depth test.
pub struct Raster<'a> {
    pub label: &'static str,
    pub layout: &'a wgpu::PipelineLayout,
    pub vertex_module: &'a wgpu::ShaderModule,
    pub vertex_entry: &'a str,
    pub depth: wgpu::DepthStencilState,
}

impl Raster<'_> {
    /// The pipeline for `primitive` with `fragment` (none: depth only).
    pub fn pipeline(&self, device: &wgpu::Device, primitive: wgpu::PrimitiveState, fragment: Option<Fragment>) -> wgpu::RenderPipeline {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(self.label),
            layout: Some(self.layout),
            vertex: wgpu::VertexState {
                module: self.vertex_module,
                entry_point: Some(self.vertex_entry),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive,
            depth_stencil: Some(self.depth.clone()),
            multisample: Default::default(),
            fragment: fragment.map(|f| wgpu::FragmentState {
                module: f.module,
                entry_point: Some(f.entry),
                compilation_options: wgpu::PipelineCompilationOptions { constants: f.constants, ..Default::default() },
                targets: f.targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    /// One pipeline per raster state of `states` (culling, winding, alpha mask), with the fragment
    /// stage `fragment` gives for each, for the scene's draws (`super::draw_ordered`).
    pub fn per_state<'f>(
        &self,
        device: &wgpu::Device,
        states: impl IntoIterator<Item = RasterState>,
        fragment: impl Fn(RasterState) -> Option<Fragment<'f>>,
    ) -> HashMap<RasterState, wgpu::RenderPipeline> {
        states.into_iter().map(|state| (state, self.pipeline(device, state.primitive(), fragment(state)))).collect()
    }
}
