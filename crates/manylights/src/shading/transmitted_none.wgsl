// `$TRANSMITTED_LIGHT` for passes that shade no transmissive surface: those are drawn over the opaque
// image by the transparent pass (`Material::drawn_over_opaque`), and rays do not see them.
#include "shading/shading_input.wgsl"

fn transmitted_light(s: ShadingInput, path: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}

fn transmitted_light_shows_sun(s: ShadingInput, path: vec3<f32>) -> bool {
    return false;
}
