// Group 0: the GPU scene and the frame, shared by every pass (raster and compute).
// Keep in sync with `gpu/scene.rs` (`GpuScene::bind_group_layout`), binding for binding.
#include "shading/types.wgsl"

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<storage, read> vertices: array<Vertex>;
@group(0) @binding(2) var<storage, read> indices: array<u32>;
@group(0) @binding(3) var<storage, read> draws: array<Draw>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var<storage, read> lights: array<Light>;
@group(0) @binding(6) var color_textures: texture_2d_array<f32>;
@group(0) @binding(7) var data_textures: texture_2d_array<f32>;
@group(0) @binding(8) var material_sampler: sampler;
