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

// A pixel's light between the filters: each lobe's demodulated light and, in w, its variance. Kept
// as eight halves (`denoise_pack_light`), 16 bytes a pixel: the filters' taps read it most.
struct DenoiseLight {
    diffuse: vec4<f32>,
    specular: vec4<f32>,
}

// The largest half-precision float.
const DENOISE_HALF_MAX: f32 = 65504.0;

fn denoise_pack_light(light: DenoiseLight) -> vec4<u32> {
    let d = clamp(light.diffuse, vec4<f32>(-DENOISE_HALF_MAX), vec4<f32>(DENOISE_HALF_MAX));
    let s = clamp(light.specular, vec4<f32>(-DENOISE_HALF_MAX), vec4<f32>(DENOISE_HALF_MAX));
    return vec4<u32>(pack2x16float(d.xy), pack2x16float(d.zw), pack2x16float(s.xy), pack2x16float(s.zw));
}

fn denoise_unpack_light(packed: vec4<u32>) -> DenoiseLight {
    return DenoiseLight(
        vec4<f32>(unpack2x16float(packed.x), unpack2x16float(packed.y)),
        vec4<f32>(unpack2x16float(packed.z), unpack2x16float(packed.w)),
    );
}

const DENOISE_LUMINANCE: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);

fn denoise_index(pixel: vec2<u32>) -> u32 {
    return pixel.y * u32(frame.viewport.x) + pixel.x;
}

fn denoise_normal(sample: DenoiseSample) -> vec3<f32> {
    return octahedral_unpack(sample.normal, 16u);
}


// The world-space width of a pixel at `position`.
fn denoise_footprint(position: vec3<f32>) -> f32 {
    return max(pixel_footprint(position - frame.world_from_view[3].xyz), 1e-6);
}

// A pixel's surface as the spatial passes read it, 16 bytes rather than the sample's 48: its world
// position, and as the fourth word its normal in 15 + 15 bits (`octahedral_pack`) under a top bit
// set (a pixel without a surface has 0). Written by the temporal pass.
const DENOISE_GUIDE_SURFACE: u32 = 0x80000000u;

fn denoise_guide(position: vec3<f32>, normal: vec3<f32>) -> vec4<u32> {
    return vec4<u32>(bitcast<vec3<u32>>(position), octahedral_pack(normal, 15u) | DENOISE_GUIDE_SURFACE);
}

fn denoise_guide_has_surface(guide: vec4<u32>) -> bool {
    return (guide.w & DENOISE_GUIDE_SURFACE) != 0u;
}

fn denoise_guide_normal(guide: vec4<u32>) -> vec3<f32> {
    return octahedral_unpack(guide.w, 15u);
}

// How much the surface of another pixel, `pixels_apart` pixels away, counts in a filter at a pixel
// whose surface is at `position` facing `normal`, a pixel `footprint` wide: normals alike (cos¹²⁸, as
// in SVGF), and the other surface near the pixel's tangent plane, relative to the ground between
// them, so no light crosses edges in depth.
fn denoise_surface_weight(normal: vec3<f32>, position: vec3<f32>, footprint: f32, other: vec4<u32>, pixels_apart: f32) -> f32 {
    let terms = denoise_surface_terms(normal, position, footprint, other, pixels_apart);
    return terms.x * exp(-terms.y);
}

// `denoise_surface_weight`'s two factors: the normals' (cos¹²⁸, by squaring) and the plane's
// exponent, which the filters add to their own so that one exponential serves them all.
fn denoise_surface_terms(normal: vec3<f32>, position: vec3<f32>, footprint: f32, other: vec4<u32>, pixels_apart: f32) -> vec2<f32> {
    var normals = max(0.0, dot(normal, denoise_guide_normal(other)));
    for (var i = 0; i < 7; i += 1) {
        normals *= normals;
    }
    let plane_distance = abs(dot(normal, bitcast<vec3<f32>>(other.xyz) - position));
    return vec2<f32>(normals, plane_distance / (footprint * max(pixels_apart, 1.0)));
}
