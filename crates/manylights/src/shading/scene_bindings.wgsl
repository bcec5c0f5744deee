// Group 0: the GPU scene and the frame, shared by every pass (raster and compute).
// Keep in sync with `gpu/scene.rs` (`GpuScene::bind_group_layout`), binding for binding.
#include "shading/types.wgsl"
#include "rays/ray_types.wgsl"

@group(0) @binding(0) var<uniform> frame: FrameUniforms;
@group(0) @binding(1) var<storage, read> vertices: array<Vertex>;
@group(0) @binding(2) var<storage, read> indices: array<u32>;
@group(0) @binding(3) var<storage, read> draws: array<Draw>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var color_textures: texture_2d_array<f32>;
@group(0) @binding(6) var data_textures: texture_2d_array<f32>;
// Lights and decals are bound with their acceleration structures: `light_bindings.wgsl`,
// `decal_bindings.wgsl`.
// One sampler per pair of glTF wrap modes, `wrap_u<U>_v<V>` with 0 repeat, 1 mirrored repeat, 2 clamp
// to edge: wrapping in the sampler stays exact at every mip level, which emulating it cannot.
@group(0) @binding(7) var wrap_u0_v0: sampler;
@group(0) @binding(8) var wrap_u1_v0: sampler;
@group(0) @binding(9) var wrap_u2_v0: sampler;
@group(0) @binding(10) var wrap_u0_v1: sampler;
@group(0) @binding(11) var wrap_u1_v1: sampler;
@group(0) @binding(12) var wrap_u2_v1: sampler;
@group(0) @binding(13) var wrap_u0_v2: sampler;
@group(0) @binding(14) var wrap_u1_v2: sampler;
@group(0) @binding(15) var wrap_u2_v2: sampler;
// The particle lights' grids (`particles/`): colour and direction sums per voxel, filtered
// trilinearly and clamped; 1×1×1 placeholders without particles.
@group(0) @binding(16) var particle_color_grid: texture_3d<f32>;
@group(0) @binding(17) var particle_direction_grid: texture_3d<f32>;
@group(0) @binding(18) var particle_sampler: sampler;
// The scene's ray-tracing hierarchy (`rays/`): nodes (TLAS then BLASes), triangles in leaf order and
// mesh instances. Without ray-traced effects, one empty node that no ray enters.
@group(0) @binding(19) var<storage, read> ray_nodes: array<BvhNode>;
@group(0) @binding(20) var<storage, read> ray_triangles: array<RayTriangle>;
@group(0) @binding(21) var<storage, read> ray_instances: array<RayInstance>;
// Decal materials' textures (`shading/decals.wgsl`), in arrays of their own size: decal materials'
// records (`GpuScene::decal_material_base`) name layers here.
@group(0) @binding(22) var decal_color_textures: texture_2d_array<f32>;
@group(0) @binding(23) var decal_data_textures: texture_2d_array<f32>;
// The environment (`gpu/environment.rs`, `shading/environment.wgsl`): its radiance, the same
// GGX-prefiltered by roughness along the mips, and the BRDF table (the split sum's scale and bias,
// the sheen's albedo: `scene::ibl`); one sampler wrapping around the horizon.
@group(0) @binding(24) var environment_radiance: texture_2d<f32>;
@group(0) @binding(25) var environment_prefiltered: texture_2d<f32>;
@group(0) @binding(26) var environment_brdf_table: texture_2d<f32>;
@group(0) @binding(27) var environment_sampler: sampler;
// `restir`'s reservoirs (`shading/direct/restir.wgsl`): two halves of one per pixel, the frames
// alternating which half they write and which they reuse. One placeholder where nothing is kept.
@group(0) @binding(28) var<storage, read_write> restir_reservoirs: array<Reservoir>;
// The denoiser's samples (`shading/shading_pixel.wgsl`, `passes/denoise/`): one per pixel, written by
// the shading of its opaque surface. One placeholder where nothing is denoised.
@group(0) @binding(29) var<storage, read_write> denoise_samples: array<DenoiseSample>;
// Where animated instances' surfaces were a frame before (`passes/surface_motion.wgsl`), for the
// reuse of what pixels kept: one per pixel, or one placeholder where nothing is reused or nothing moves.
@group(0) @binding(30) var<storage, read_write> surface_motions: array<SurfaceMotion>;

// Where the surface at `position`, seen at `pixel`, was a frame before: moved with its instance where
// an animated instance shows there this frame, else where it is (the camera's own motion is the
// previous camera's, `frame.previous_clip_from_world`).
fn previous_surface_position(pixel: vec2<u32>, position: vec3<f32>) -> vec3<f32> {
    let index = min(pixel.y * u32(frame.viewport.x) + pixel.x, arrayLength(&surface_motions) - 1u);
    let motion = surface_motions[index];
    return select(position, position + motion.moved, motion.frame == frame.direct_lighting.x);
}
