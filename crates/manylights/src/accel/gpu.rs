//! Acceleration structures on the GPU: the buffers and bind group (group 2 of passes that shade with
//! `LightMethod::Bvh`) holding the light BVH, built once on the CPU or rebuilt every frame on the GPU.
//! Keep in sync with `accel/bvh_bindings.wgsl`.

use wgpu::util::DeviceExt;

use super::{lbvh::GpuLbvh, volumes, Bvh, BvhNode};
use crate::{
    gpu::{bindings, GpuContext, GpuTimer},
    scene::Light,
    Error, Result,
};

/// Where and when the light BVH is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BvhBuild {
    /// Once, on the CPU (binned SAH): for lights that do not change.
    #[default]
    CpuOnce,
    /// Every frame, on the GPU (LBVH): what changing groups need; timed as `lbvh_build`.
    GpuEveryFrame,
}

pub struct LightBvhBuffers {
    pub bind_group_layout: wgpu::BindGroupLayout,
    pub bind_group: wgpu::BindGroup,
    builder: Option<GpuLbvh>,
}

impl LightBvhBuffers {
    pub fn new(ctx: &GpuContext, lights: &[Light], build: BvhBuild) -> Result<Self> {
        match build {
            BvhBuild::CpuOnce => Self::build_static(ctx, lights),
            BvhBuild::GpuEveryFrame => {
                let aabbs: Vec<volumes::Aabb> = lights.iter().map(volumes::light_aabb).collect();
                let mut builder = GpuLbvh::new(ctx, aabbs.len() as u32)?;
                builder.set_boxes(&ctx.queue, &aabbs)?;
                let (bind_group_layout, bind_group) = Self::bind(&ctx.device, &builder.nodes, &builder.primitives);
                Ok(Self { bind_group_layout, bind_group, builder: Some(builder) })
            }
        }
    }

    /// Records this frame's rebuild, if the BVH is rebuilt every frame.
    pub fn record_rebuild(&mut self, encoder: &mut wgpu::CommandEncoder, timer: Option<&mut GpuTimer>) -> Result<()> {
        match &mut self.builder {
            Some(builder) => builder.record(encoder, timer),
            None => Ok(()),
        }
    }

    /// Builds the light BVH on the CPU and uploads it: the static path, for lights that do not move.
    pub fn build_static(ctx: &GpuContext, lights: &[Light]) -> Result<Self> {
        let aabbs: Vec<volumes::Aabb> = lights.iter().map(volumes::light_aabb).collect();
        let bvh = Bvh::build(&aabbs)?;
        Self::upload(ctx, &bvh)
    }

    fn upload(ctx: &GpuContext, bvh: &Bvh) -> Result<Self> {
        let device = &ctx.device;
        let limit = ctx.limits.max_storage_buffer_binding_size;
        let bytes = std::mem::size_of_val(bvh.nodes.as_slice()) as u64;
        if bytes > limit {
            return Err(Error::InvalidScene(format!(
                "the light BVH takes {} MiB, over this GPU's storage binding limit of {} MiB; use fewer lights",
                bytes >> 20,
                limit >> 20
            )));
        }
        // Bindings cannot be empty: an empty BVH gets one node that contains nothing (shaders skip
        // traversal when there are no lights anyway).
        let empty = [BvhNode { min: [f32::INFINITY; 3], a: 0, max: [f32::NEG_INFINITY; 3], b: 0 }];
        let nodes: &[BvhNode] = if bvh.nodes.is_empty() { &empty } else { &bvh.nodes };
        let primitives: &[u32] = if bvh.primitive_indices.is_empty() { &[0] } else { &bvh.primitive_indices };
        let storage = |label, contents| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let node_buffer = storage("light bvh nodes", bytemuck::cast_slice(nodes));
        let primitive_buffer = storage("light bvh primitives", bytemuck::cast_slice(primitives));

        let (bind_group_layout, bind_group) = Self::bind(device, &node_buffer, &primitive_buffer);
        Ok(Self { bind_group_layout, bind_group, builder: None })
    }

    fn bind(device: &wgpu::Device, nodes: &wgpu::Buffer, primitives: &wgpu::Buffer) -> (wgpu::BindGroupLayout, wgpu::BindGroup) {
        let all = wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let bind_group_layout = bindings::layout(
            device,
            "light bvh",
            &[
                bindings::storage_read(0, all), // nodes
                bindings::storage_read(1, all), // primitive (light) indices
            ],
        );
        let bind_group =
            bindings::bind_group(device, "light bvh", &bind_group_layout, vec![nodes.as_entire_binding(), primitives.as_entire_binding()]);
        (bind_group_layout, bind_group)
    }
}
