// What the denoiser's passes share (`passes/denoise/`): their per-pixel records and the tests that
// tell whether two pixels see the same surface. Input: the shading core's `DenoiseSample`s.
#include "shading/scene_bindings.wgsl"
#include "shading/camera.wgsl"
#include "shading/octahedral.wgsl"

// What a pixel keeps for the next frame: its lobes' luminance moments (mean, mean square of the
// diffuse, then of the specular), its surface, and its lobes' light accumulated over the frames
// (before any spatial filter).
struct DenoiseHistory {
    moments: vec4<f32>,
    position: vec3<f32>,
    // Octahedral normal in 12 + 12 bits; the frames accumulated in the top 8 (0: nothing kept).
    normal_length: u32,
    diffuse: vec4<f32>,
    specular: vec4<f32>,
}

// A pixel's light between the filters: each lobe's demodulated light and, in w, its variance.
struct DenoiseLight {
    diffuse: vec4<f32>,
    specular: vec4<f32>,
}

const DENOISE_LUMINANCE: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);

fn denoise_index(pixel: vec2<u32>) -> u32 {
    return pixel.y * u32(frame.viewport.x) + pixel.x;
}

fn denoise_normal(sample: DenoiseSample) -> vec3<f32> {
    return octahedral_unpack(sample.normal, 16u);
}

fn denoise_pack_normal_length(n: vec3<f32>, frames: u32) -> u32 {
    return octahedral_pack(n, 12u) | (min(frames, 255u) << 24u);
}

fn denoise_unpack_normal(packed: u32) -> vec3<f32> {
    return octahedral_unpack(packed, 12u);
}

// The world-space width of a pixel at `position`.
fn denoise_footprint(position: vec3<f32>) -> f32 {
    return max(pixel_footprint(position - frame.world_from_view[3].xyz), 1e-6);
}

// A pixel's surface as the spatial passes read it, 16 bytes rather than the sample's 48: its world
// position, and its normal in 16 + 16 bits (`octahedral_pack`) as the fourth word. Written by the
// temporal pass.
fn denoise_guide(sample: DenoiseSample) -> vec4<u32> {
    return vec4<u32>(bitcast<vec3<u32>>(sample.position), sample.normal);
}

// How much the surface of another pixel, `pixels_apart` pixels away, counts in a filter at a pixel
// whose surface is at `position` facing `normal`, a pixel `footprint` wide: normals alike (cos¹²⁸, as
// in SVGF), and the other surface near the pixel's tangent plane, relative to the ground between
// them, so no light crosses edges in depth.
fn denoise_surface_weight(normal: vec3<f32>, position: vec3<f32>, footprint: f32, other: vec4<u32>, pixels_apart: f32) -> f32 {
    let normals = pow(max(0.0, dot(normal, octahedral_unpack(other.w, 16u))), 128.0);
    let plane_distance = abs(dot(normal, bitcast<vec3<f32>>(other.xyz) - position));
    return normals * exp(-plane_distance / (footprint * max(pixels_apart, 1.0)));
}
