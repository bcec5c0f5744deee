//! Short constructors for bind group layout entries, bind groups and compute pipelines, so each pass
//! states its bindings as a list in WGSL `@binding` order instead of nested descriptors.

use super::shaders::{self, ShaderDesc};
use crate::Result;

pub fn uniform(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    buffer(binding, visibility, wgpu::BufferBindingType::Uniform)
}

/// A uniform bound at a dynamic offset, `size` bytes from it: one buffer of many records, a record per
/// dispatch.
pub fn uniform_dynamic(binding: u32, visibility: wgpu::ShaderStages, size: u64) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: true,
            min_binding_size: wgpu::BufferSize::new(size),
        },
        count: None,
    }
}

pub fn storage_read(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    buffer(binding, visibility, wgpu::BufferBindingType::Storage { read_only: true })
}

pub fn storage_read_write(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    buffer(binding, visibility, wgpu::BufferBindingType::Storage { read_only: false })
}

fn buffer(binding: u32, visibility: wgpu::ShaderStages, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

pub fn texture(
    binding: u32,
    visibility: wgpu::ShaderStages,
    sample_type: wgpu::TextureSampleType,
    view_dimension: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Texture { sample_type, view_dimension, multisampled: false },
        count: None,
    }
}

pub fn storage_texture_write(binding: u32, visibility: wgpu::ShaderStages, format: wgpu::TextureFormat) -> wgpu::BindGroupLayoutEntry {
    storage_texture_write_dimension(binding, visibility, format, wgpu::TextureViewDimension::D2)
}

pub fn storage_texture_3d_write(binding: u32, visibility: wgpu::ShaderStages, format: wgpu::TextureFormat) -> wgpu::BindGroupLayoutEntry {
    storage_texture_write_dimension(binding, visibility, format, wgpu::TextureViewDimension::D3)
}

fn storage_texture_write_dimension(
    binding: u32,
    visibility: wgpu::ShaderStages,
    format: wgpu::TextureFormat,
    view_dimension: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::StorageTexture { access: wgpu::StorageTextureAccess::WriteOnly, format, view_dimension },
        count: None,
    }
}

/// A top-level acceleration structure that ray queries read.
pub fn acceleration_structure(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry { binding, visibility, ty: wgpu::BindingType::AccelerationStructure { vertex_return: false }, count: None }
}

pub fn sampler(binding: u32, visibility: wgpu::ShaderStages) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry { binding, visibility, ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering), count: None }
}

pub fn layout(device: &wgpu::Device, label: &str, entries: &[wgpu::BindGroupLayoutEntry]) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries })
}

/// A bind group whose resources are bound at 0, 1, 2, … in the order given.
pub fn bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: Vec<wgpu::BindingResource<'_>>,
) -> wgpu::BindGroup {
    bind_group_at(device, label, layout, resources.into_iter().enumerate().map(|(binding, resource)| (binding as u32, resource)).collect())
}

/// A bind group whose resources are bound at the slots given (for layouts with gaps).
pub fn bind_group_at(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: Vec<(u32, wgpu::BindingResource<'_>)>,
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> =
        resources.into_iter().map(|(binding, resource)| wgpu::BindGroupEntry { binding, resource }).collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
}

pub fn pipeline_layout(device: &wgpu::Device, label: &str, bind_group_layouts: &[&wgpu::BindGroupLayout]) -> wgpu::PipelineLayout {
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = bind_group_layouts.iter().copied().map(Some).collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor { label: Some(label), bind_group_layouts: &layouts, immediate_size: 0 })
}

/// A compute pipeline whose label and entry point are both `entry`, the pass's name.
pub fn compute_pipeline(
    device: &wgpu::Device,
    entry: &'static str,
    shader: &ShaderDesc,
    bind_group_layouts: &[&wgpu::BindGroupLayout],
) -> Result<wgpu::ComputePipeline> {
    compute_pipeline_with_constants(device, entry, shader, bind_group_layouts, &[])
}

/// As [`compute_pipeline`], with values for the shader's `override` constants.
pub fn compute_pipeline_with_constants(
    device: &wgpu::Device,
    entry: &'static str,
    shader: &ShaderDesc,
    bind_group_layouts: &[&wgpu::BindGroupLayout],
    constants: &[(&str, f64)],
) -> Result<wgpu::ComputePipeline> {
    let module = shaders::create_stage_module(device, shader, naga::ShaderStage::Compute, entry, constants)?;
    Ok(device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(&pipeline_layout(device, entry, bind_group_layouts)),
        module: &module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions { constants, ..Default::default() },
        cache: None,
    }))
}
