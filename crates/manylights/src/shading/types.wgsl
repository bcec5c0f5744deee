// GPU scene types. Keep in sync with `gpu/scene.rs` (GpuVertex = scene::Vertex, GpuDraw, GpuMaterial,
// GpuLight, GpuDecal) and `gpu/frame.rs` (FrameUniforms): field order, sizes and padding match the repr(C) structs.
//
// Spaces: `world_from_local` maps a mesh into the world, `clip_from_world` the world into reverse-Z clip
// space (near → 1, far → 0). Directions named `*_dir` are unit vectors.

struct Vertex {
    position: vec3<f32>,
    u: f32,
    normal: vec3<f32>,
    v: f32,
    // xyz tangent, w bitangent sign
    tangent: vec4<f32>,
    // Linear RGBA as 16-bit unorms (`vertex_color`), white where the mesh has no colours.
    color: vec2<u32>,
    // TEXCOORD_1, zero where the mesh has none.
    uv1: vec2<f32>,
}

// Both sets of texture coordinates: TEXCOORD_0 in xy, TEXCOORD_1 in zw (`UvGradients`).
fn vertex_uvs(v: Vertex) -> vec4<f32> {
    return vec4<f32>(v.u, v.v, v.uv1);
}

fn vertex_color(v: Vertex) -> vec4<f32> {
    return vec4<f32>(unpack2x16unorm(v.color.x), unpack2x16unorm(v.color.y));
}

// One instance of one mesh primitive.
struct Draw {
    world_from_local: mat4x4<f32>,
    // Inverse transpose of the upper 3×3 (columns in xyz); w of column 0 holds the sign of the
    // determinant, which flips the bitangent of mirrored instances.
    normal_from_local: mat3x4<f32>,
    first_index: u32,
    // Visibility id of the draw's first triangle: ids number every drawn triangle from 0, draw after
    // draw, so one u32 per pixel names draw and triangle.
    first_visibility_id: u32,
    base_vertex: u32,
    material: u32,
}

const NO_TEXTURE: i32 = -1;

// Texture wrap modes: per texture slot (wrap_v << 2) | wrap_u, each 0 repeat, 1 mirrored repeat,
// 2 clamp to edge; they select a sampler in `material.wgsl`.

// Alpha masking and double-sidedness are raster state (`gpu::scene::RasterState`), not fields here.
struct Material {
    base_color_factor: vec4<f32>,
    emissive_factor: vec3<f32>,
    // Alpha-masked materials discard below it in `visbuffer_raster`.
    alpha_cutoff: f32,
    metallic_factor: f32,
    roughness_factor: f32,
    normal_scale: f32,
    // MATERIAL_UNLIT, MATERIAL_CLEARCOAT, MATERIAL_TRANSMISSION, MATERIAL_SHEEN.
    flags: u32,
    // Layers in `color_textures` (base colour, emissive, specular and sheen colour) and `data_textures` (the
    // others); NO_TEXTURE when absent. Texture slots, in order: base colour 0, emissive 1,
    // metallic-roughness 2, normal 3, specular 4, specular colour 5, clearcoat 6, clearcoat
    // roughness 7, clearcoat normal 8, occlusion 9, transmission 10, thickness 11, sheen colour 12,
    // sheen roughness 13.
    base_color_layer: i32,
    emissive_layer: i32,
    metallic_roughness_layer: i32,
    normal_layer: i32,
    // The dielectric's reflectance at normal incidence before the colour texture, the clamp to 1 and
    // the specular factor, ((ior − 1) / (ior + 1))² × colour factor; and the specular factor
    // (KHR_materials_ior, KHR_materials_specular).
    specular_color: vec3<f32>,
    specular_factor: f32,
    clearcoat_factor: f32,
    clearcoat_roughness_factor: f32,
    clearcoat_normal_scale: f32,
    // How far the occlusion texture darkens the environment's light.
    occlusion_strength: f32,
    specular_layer: i32,
    specular_color_layer: i32,
    clearcoat_layer: i32,
    clearcoat_roughness_layer: i32,
    clearcoat_normal_layer: i32,
    occlusion_layer: i32,
    // Four bits a texture slot, `(wrap_v << 2) | wrap_u`, eight slots a word.
    wrap_modes: vec2<u32>,
    // The medium behind a transmissive surface (KHR_materials_volume): the colour left after
    // `attenuation_distance` (0: clear), its thickness in the mesh's units (0: thin-walled), and the
    // index of refraction that bends light into it (KHR_materials_ior, at least 1).
    attenuation_color: vec3<f32>,
    attenuation_distance: f32,
    // The share of the diffuse lobe let through instead (KHR_materials_transmission).
    transmission_factor: f32,
    thickness_factor: f32,
    ior: f32,
    transmission_layer: i32,
    thickness_layer: i32,
    sheen_color_layer: i32,
    sheen_roughness_layer: i32,
    // How far the medium's index of refraction spreads over the colours (KHR_materials_dispersion).
    dispersion: f32,
    // The sheen's colour (black: none) and roughness (KHR_materials_sheen).
    sheen_color: vec3<f32>,
    sheen_roughness: f32,
    // Each slot's texture coordinates from the mesh's (glTF's texCoord and KHR_texture_transform):
    // two vec4s a slot, the 2×2 matrix's columns (xy, zw), then the translation (xy) and the set of
    // coordinates it transforms (z: 0 or 1).
    uv_transforms: array<vec4<f32>, 28>,
}

// The visibility id no triangle has (`gpu::scene::NO_VISIBILITY_ID`): where the transmissive raster
// drew nothing.
const NO_VISIBILITY_ID: u32 = 0xffffff00u;

const MATERIAL_UNLIT: u32 = 1u;
const MATERIAL_CLEARCOAT: u32 = 2u;
const MATERIAL_TRANSMISSION: u32 = 4u;
const MATERIAL_SHEEN: u32 = 16u;

const LIGHT_POINT: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;

struct Light {
    position: vec3<f32>,
    range: f32,
    // Colour × intensity (candela).
    radiant: vec3<f32>,
    kind: u32,
    // Spot axis: the direction the light points.
    direction: vec3<f32>,
    // Spot cone as glTF's scale/offset: attenuation = saturate(cos θ · scale + offset)².
    spot_scale: f32,
    spot_offset: f32,
    // LIGHT_CASTS_SHADOWS when shading traces shadow rays towards it.
    flags: u32,
    _pad0: u32,
    _pad1: u32,
}

// Keep in sync with `gpu::scene::LIGHT_CASTS_SHADOWS`.
const LIGHT_CASTS_SHADOWS: u32 = 1u;

// A decal (`scene::Decal`): projects its material onto surfaces inside the unit box [-0.5, 0.5]³ of
// decal space, along -Z.
struct Decal {
    // Rows of the affine map from the decal's group space into decal space, applied as
    // `vec4(p, 1.0) * decal_from_group`.
    decal_from_group: mat3x4<f32>,
    material: u32,
    layer: u32,
    weight: f32,
    _pad0: u32,
}

const TONEMAP_ACES: u32 = 0u;
const TONEMAP_AGX: u32 = 1u;
const TONEMAP_NONE: u32 = 2u;

struct FrameUniforms {
    clip_from_world: mat4x4<f32>,
    // Pixel rays are rebuilt in view space and rotated into the world relative to the camera
    // (world_from_view[3] is its position), which keeps f32 precision far from the world origin.
    view_from_clip: mat4x4<f32>,
    world_from_view: mat4x4<f32>,
    // width, height, 1 / width, 1 / height
    viewport: vec4<f32>,
    // xyz: direction the sunlight travels; w: 1 when there is a sun
    sun_direction: vec4<f32>,
    // rgb: colour × illuminance
    sun_radiance: vec4<f32>,
    // The environment's irradiance / π in L2 spherical harmonics (`scene::ibl::irradiance_sh`).
    environment_irradiance: array<vec4<f32>, 9>,
    // x: the prefiltered environment's last mip level (roughness 1); y: 1 when the background draws
    // the sun's disc.
    environment: vec4<f32>,
    // Instances of light and decal groups (`light_instances`, `decal_instances`).
    light_instance_count: u32,
    exposure: f32,
    tonemapper: u32,
    decal_instance_count: u32,
    // The clustered method's froxel grid (`accel/cluster_grid.wgsl`): tile columns, rows, depth
    // slices, tile size in pixels.
    cluster_grid: vec4<u32>,
    // x: near plane of the depth slicing; y: slices per doubling of view depth; z: the camera's near
    // plane, in front of which nothing is visible.
    cluster_depth: vec4<f32>,
    // The particle grid (`particles/`): voxels per axis of each cascade, w the cascades (0 when no
    // grid lights the scene).
    particle_volume: vec4<u32>,
    // How shading filters the grid: x PARTICLE_FILTER_*, y samples per point (1: at the point only).
    particle_filter: vec4<u32>,
    // x: the factor that undoes the splat's texture scale.
    particle_texture_unscale: vec4<f32>,
    // Per cascade, finest first: xyz its corner, w its voxel edge.
    particle_cascades: array<vec4<f32>, 8>,
    // Ray-traced effects (`rays/`): x the sun's shadows (RAY_SHADOWS_*), y rays per pixel towards the
    // sun's disc (soft shadows), z reflection bounces (0: none), w shadow rays towards local lights
    // per shading point (0: none).
    ray_options: vec4<u32>,
    // x: the sun's angular radius (radians); y: surfaces below this perceptual roughness reflect;
    // z: the angle between neighbouring pixels' rays (perspective); w: a pixel's width at the camera
    // (orthographic). A pixel's footprint at distance d is w + d · z.
    ray_settings: vec4<f32>,
    // x: the debug view (`shading/debug_view.wgsl`, DEBUG_VIEW_*; 0: none), y: the count its heat map
    // tops out at.
    debug_view: vec4<u32>,
    // Direct lighting's sampling (`shading/direct/restir.wgsl`): x the frame's number, which seeds each
    // frame's samples; y samples per shading point; z the half of `restir_reservoirs` this frame writes
    // (the frame's number mod 2); w what is reused (RESTIR_REUSE_*, 0: nothing).
    direct_lighting: vec4<u32>,
    // The previous frame's camera, for reprojection.
    previous_clip_from_world: mat4x4<f32>,
}

// A pixel's reservoir for `restir` (`shading/direct/restir.wgsl`), kept for the next frame: the chosen
// light (RESTIR_NO_LIGHT: none) and its instance, a hash of its record, the unbiased contribution
// weight W, and the surface it was made for — position, octahedral normal (12 + 12 bits) and the
// reservoir's confidence M (the top 8 bits).
struct Reservoir {
    light: u32,
    instance: u32,
    light_hash: u32,
    weight: f32,
    position: vec3<f32>,
    normal_count: u32,
}

// How the surface an animated instance shows at a pixel moved since the previous frame
// (`passes/surface_motion.wgsl`): its world-space displacement, then − now, and the frame's number
// (`FrameUniforms::direct_lighting.x`) that wrote it. A record of an earlier frame is stale: the pixel
// shows no moving instance now.
struct SurfaceMotion {
    moved: vec3<f32>,
    frame: u32,
}

// One pixel's sampled lighting for the denoiser (`passes/denoise/`): its diffuse and specular parts,
// each divided by its albedo (rgba8 unorm, the same quantised albedo multiplies them back), and the
// surface that guides the filters: its octahedral normal (16 + 16 bits), world position and
// perceptual roughness (the diffuse albedo's fourth byte).
// Keep in sync with `GpuDenoiseSample` in `gpu/scene.rs`.
struct DenoiseSample {
    diffuse: vec3<f32>,
    normal: u32,
    specular: vec3<f32>,
    albedo: u32,
    position: vec3<f32>,
    specular_albedo: u32,
}

// Keep in sync with `SunShadows` in `rays/mod.rs`.
const RAY_SHADOWS_OFF: u32 = 0u;
const RAY_SHADOWS_HARD: u32 = 1u;
const RAY_SHADOWS_SOFT: u32 = 2u;

// Keep in sync with `ParticleFilter` in `particles/mod.rs`.
const PARTICLE_FILTER_NEAREST: u32 = 0u;
const PARTICLE_FILTER_TRILINEAR: u32 = 1u;
const PARTICLE_FILTER_TRICUBIC: u32 = 2u;
