#include "shading/shading_input.wgsl"

// Cook-Torrance specular (GGX distribution, height-correlated Smith visibility, Schlick Fresnel) plus
// Lambert diffuse: the glTF metallic-roughness BRDF.

const PI: f32 = 3.141592653589793;
// Below this perceptual roughness GGX highlights of point lights become sub-pixel and alias.
const MIN_ROUGHNESS: f32 = 0.045;

fn d_ggx(n_dot_h: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

fn v_smith_ggx_correlated(n_dot_v: f32, n_dot_l: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
    let gl = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    return 0.5 / max(gv + gl, 1e-7);
}

fn f_schlick(f0: vec3<f32>, v_dot_h: f32) -> vec3<f32> {
    let f = pow(1.0 - v_dot_h, 5.0);
    return f0 + (vec3<f32>(1.0) - f0) * f;
}

// The BRDF's two lobes, each times n·l.
struct BrdfLobes {
    diffuse: vec3<f32>,
    specular: vec3<f32>,
}

// Reflected radiance for unit irradiance from direction `light_dir` (towards the light), already
// multiplied by n·l, lobe by lobe. Zero below the horizon.
fn brdf_lobes_times_cosine(s: ShadingInput, light_dir: vec3<f32>) -> BrdfLobes {
    let n_dot_l = dot(s.normal, light_dir);
    if n_dot_l <= 0.0 {
        return BrdfLobes(vec3<f32>(0.0), vec3<f32>(0.0));
    }
    let n_dot_v = max(dot(s.normal, s.view_dir), 1e-4);
    let h = normalize(light_dir + s.view_dir);
    let n_dot_h = saturate(dot(s.normal, h));
    let v_dot_h = saturate(dot(s.view_dir, h));
    let roughness = max(s.roughness, MIN_ROUGHNESS);
    let alpha = roughness * roughness;

    let f0 = mix(vec3<f32>(0.04), s.base_color, s.metallic);
    let fresnel = f_schlick(f0, v_dot_h);
    let specular = d_ggx(n_dot_h, alpha) * v_smith_ggx_correlated(n_dot_v, n_dot_l, alpha) * fresnel;
    let diffuse = (vec3<f32>(1.0) - fresnel) * s.base_color * (1.0 - s.metallic) / PI;
    return BrdfLobes(diffuse * n_dot_l, specular * n_dot_l);
}

// Both lobes together.
fn brdf_times_cosine(s: ShadingInput, light_dir: vec3<f32>) -> vec3<f32> {
    let lobes = brdf_lobes_times_cosine(s, light_dir);
    return lobes.diffuse + lobes.specular;
}
