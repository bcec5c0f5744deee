// No reflections: surfaces reflect only the prefiltered environment `shade` gives them.
#include "shading/shading_input.wgsl"

fn reflected_radiance(s: ShadingInput, geometric_normal: vec3<f32>, footprint: f32) -> vec3<f32> {
    return vec3<f32>(0.0);
}
