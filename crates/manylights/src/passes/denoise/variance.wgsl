// The denoiser's variance estimate where a surface has little history (SVGF, Schied et al. 2017):
// after a disocclusion the temporal moments say little, so a pixel with fewer than
// DENOISE_SHORT_HISTORY frames takes its lobes' moments and light from the surface around it instead
// (7×7 pixels, weighed by `denoise_surface_weight`), its variance raised by the frames it lacks.
// Pixels with enough history pass through.
#include "passes/denoise/denoise_types.wgsl"

@group(1) @binding(0) var<storage, read> history: array<DenoiseHistory>;
@group(1) @binding(1) var<storage, read> integrated: array<vec4<u32>>;
@group(1) @binding(2) var<storage, read_write> estimated: array<vec4<u32>>;
@group(1) @binding(3) var<storage, read> guides: array<vec4<u32>>;

const DENOISE_SHORT_HISTORY: u32 = 4u;
const DENOISE_VARIANCE_RADIUS: i32 = 3;

@compute @workgroup_size(8, 8)
fn denoise_variance(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame.viewport.xy);
    if any(id.xy >= size) {
        return;
    }
    let index = denoise_index(id.xy);
    let frames = history[index].normal_length >> 24u;
    let guide = guides[index];
    if frames >= DENOISE_SHORT_HISTORY || !denoise_guide_has_surface(guide) {
        estimated[index] = integrated[index];
        return;
    }
    let position = bitcast<vec3<f32>>(guide.xyz);
    let normal = denoise_guide_normal(guide);
    let footprint = denoise_footprint(position);
    var moments = vec4<f32>(0.0);
    var diffuse = vec3<f32>(0.0);
    var specular = vec3<f32>(0.0);
    var weights = 0.0;
    for (var dy = -DENOISE_VARIANCE_RADIUS; dy <= DENOISE_VARIANCE_RADIUS; dy += 1) {
        for (var dx = -DENOISE_VARIANCE_RADIUS; dx <= DENOISE_VARIANCE_RADIUS; dx += 1) {
            let q = vec2<i32>(id.xy) + vec2<i32>(dx, dy);
            if any(q < vec2<i32>(0)) || any(q >= vec2<i32>(size)) {
                continue;
            }
            let other = denoise_index(vec2<u32>(q));
            let other_guide = guides[other];
            if !denoise_guide_has_surface(other_guide) {
                continue;
            }
            let light = denoise_unpack_light(integrated[other]);
            let w = denoise_surface_weight(normal, position, footprint, other_guide, length(vec2<f32>(f32(dx), f32(dy))));
            moments += w * history[other].moments;
            diffuse += w * light.diffuse.rgb;
            specular += w * light.specular.rgb;
            weights += w;
        }
    }
    // The pixel itself weighs 1: `weights` is at least that.
    moments /= weights;
    let variance = max(vec2<f32>(0.0), moments.yw - moments.xz * moments.xz) * f32(DENOISE_SHORT_HISTORY) / f32(max(frames, 1u));
    estimated[index] = denoise_pack_light(DenoiseLight(vec4<f32>(diffuse / weights, variance.x), vec4<f32>(specular / weights, variance.y)));
}
