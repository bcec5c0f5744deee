#include "shading/shading_input.wgsl"

// Cook-Torrance specular (GGX distribution, height-correlated Smith visibility, Schlick Fresnel) plus
// Lambert diffuse: the glTF metallic-roughness BRDF, with its extensions' dielectric reflectance
// (KHR_materials_ior, KHR_materials_specular) and clear coat (KHR_materials_clearcoat), as their
// specifications compose them: mix(dielectric, metal, metallic) under the coat, where the
// dielectric is `diffuse · (1 − weight · max(F)) + specular · weight · F`, and the coat mixes in
// by `clearcoat · F_coat(n_coat · v)`. A transmissive dielectric (KHR_materials_transmission) lets
// its `transmission` share of the diffuse lobe through instead: light from behind reaches the viewer
// through a specular transmission lobe (`transmission_lobe_times_cosine`).

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

// Whether light from below the surface's horizon reaches its viewer: through a transmissive
// surface's transmission lobe, in the pass that shades them (TRANSMISSION).
fn lit_from_behind(s: ShadingInput) -> bool {
    return TRANSMISSION && s.transmission > 0.0;
}

// The path light takes through the surface's medium (KHR_materials_volume), from the shading point to
// where it leaves: refracted into it by the index of refraction, as long as the medium is thick (0
// for thin walls).
fn transmission_path(s: ShadingInput) -> vec3<f32> {
    let refracted = refract(-s.view_dir, s.normal, 1.0 / max(s.ior, 1.0));
    let direction = select(-s.view_dir, normalize(refracted), dot(refracted, refracted) > 0.0);
    return direction * s.thickness;
}

// The medium's transmittance over `distance` (Beer's law): the attenuation colour after its distance;
// none through a thin wall (where a black attenuation colour would make pow(0, 0)).
fn medium_transmittance(s: ShadingInput, distance: f32) -> vec3<f32> {
    if s.attenuation.w <= 0.0 || distance <= 0.0 {
        return vec3<f32>(1.0);
    }
    return pow(s.attenuation.rgb, vec3<f32>(distance / s.attenuation.w));
}

// The transmission lobe towards `light_dir` below the surface, times |n·l|, for a transmissive
// dielectric of reflectance `dielectric` (`surface_dielectric`): GGX about the light mirrored above
// the surface, as the glTF specification and the Khronos sample viewer evaluate it for thin and thick
// surfaces alike, at the roughness refraction blurs with (none at an index of 1, fully from 1.5, as
// `shading/transmitted_screen.wgsl` blurs the light behind); through the transmission share, the base
// colour, what the dielectric does not reflect and the medium along the refracted view ray. The
// light's direction is taken from the shading point, not from where that ray leaves the medium.
fn transmission_lobe_times_cosine(s: ShadingInput, light_dir: vec3<f32>, dielectric: vec4<f32>) -> vec3<f32> {
    let mirrored = light_dir - 2.0 * dot(s.normal, light_dir) * s.normal;
    let n_dot_l = max(dot(s.normal, mirrored), 0.0);
    let n_dot_v = max(dot(s.normal, s.view_dir), 1e-4);
    let h = normalize(mirrored + s.view_dir);
    let roughness = max(s.roughness * saturate(s.ior * 2.0 - 2.0), MIN_ROUGHNESS);
    let alpha = roughness * roughness;
    let fresnel = dielectric.xyz + (1.0 - dielectric.xyz) * pow(1.0 - saturate(dot(s.view_dir, h)), 5.0);
    let unreflected = 1.0 - dielectric.w * max(fresnel.x, max(fresnel.y, fresnel.z));
    let lobe = d_ggx(saturate(dot(s.normal, h)), alpha) * v_smith_ggx_correlated(n_dot_v, n_dot_l, alpha) * n_dot_l;
    let share = s.transmission * (1.0 - s.metallic) * unreflected * lobe;
    return s.base_color * medium_transmittance(s, length(transmission_path(s))) * share;
}

// The BRDF's two lobes, each times n·l.
struct BrdfLobes {
    diffuse: vec3<f32>,
    specular: vec3<f32>,
}

// GGX's D · V for unit normal `n`, times n·l, towards `light_dir` (0 below n's horizon).
fn ggx_times_cosine(n: vec3<f32>, view_dir: vec3<f32>, light_dir: vec3<f32>, roughness: f32) -> f32 {
    let n_dot_l = dot(n, light_dir);
    if n_dot_l <= 0.0 {
        return 0.0;
    }
    let n_dot_v = max(dot(n, view_dir), 1e-4);
    let n_dot_h = saturate(dot(n, normalize(light_dir + view_dir)));
    let alpha = max(roughness, MIN_ROUGHNESS) * max(roughness, MIN_ROUGHNESS);
    return d_ggx(n_dot_h, alpha) * v_smith_ggx_correlated(n_dot_v, n_dot_l, alpha) * n_dot_l;
}

// The dielectric's reflectance at normal incidence (xyz) and its weight (w): the surface's with the
// extensions, glTF's core 4 % and 1 without (a pipeline constant, so the core path carries none).
fn surface_dielectric(s: ShadingInput) -> vec4<f32> {
    if MATERIAL_EXTENSIONS {
        return vec4<f32>(s.dielectric_f0, s.specular_weight);
    }
    return vec4<f32>(vec3<f32>(0.04), 1.0);
}

// The share of light a clear coat reflects towards the viewer (Schlick, index of refraction 1.5):
// what reaches the material below is scaled by one minus it.
fn clearcoat_fresnel(s: ShadingInput) -> f32 {
    if !MATERIAL_EXTENSIONS {
        return 0.0;
    }
    return s.clearcoat * (0.04 + 0.96 * pow(1.0 - saturate(abs(dot(s.clearcoat_normal, s.view_dir))), 5.0));
}

// Reflected radiance for unit irradiance from direction `light_dir` (towards the light), already
// multiplied by n·l, lobe by lobe (the coat in the specular lobe, the transmission lobe there too).
// Zero below the horizon, but for light through a transmissive surface.
fn brdf_lobes_times_cosine(s: ShadingInput, light_dir: vec3<f32>) -> BrdfLobes {
    var lobes = BrdfLobes(vec3<f32>(0.0), vec3<f32>(0.0));
    let n_dot_l = dot(s.normal, light_dir);
    if n_dot_l > 0.0 {
        let n_dot_v = max(dot(s.normal, s.view_dir), 1e-4);
        let h = normalize(light_dir + s.view_dir);
        let n_dot_h = saturate(dot(s.normal, h));
        let grazing = pow(1.0 - saturate(dot(s.view_dir, h)), 5.0);
        let roughness = max(s.roughness, MIN_ROUGHNESS);
        let alpha = roughness * roughness;
        let dielectric = surface_dielectric(s);
        let dielectric_fresnel = dielectric.xyz + (1.0 - dielectric.xyz) * grazing;
        let metal_fresnel = s.base_color + (1.0 - s.base_color) * grazing;
        let fresnel = mix(dielectric.w * dielectric_fresnel, metal_fresnel, s.metallic);
        lobes.specular = d_ggx(n_dot_h, alpha) * v_smith_ggx_correlated(n_dot_v, n_dot_l, alpha) * n_dot_l * fresnel;
        let reflected = dielectric.w * max(dielectric_fresnel.x, max(dielectric_fresnel.y, dielectric_fresnel.z));
        lobes.diffuse = s.base_color * ((1.0 - s.metallic) * (1.0 - reflected) * n_dot_l / PI);
        if TRANSMISSION {
            // What a transmissive surface lets through it does not scatter (`shading/transmission.wgsl`).
            lobes.diffuse *= 1.0 - s.transmission;
        }
    } else if lit_from_behind(s) {
        lobes.specular = transmission_lobe_times_cosine(s, light_dir, surface_dielectric(s));
    }
    if MATERIAL_EXTENSIONS && s.clearcoat > 0.0 {
        let coat = clearcoat_fresnel(s);
        lobes.diffuse *= 1.0 - coat;
        lobes.specular = lobes.specular * (1.0 - coat)
            + vec3<f32>(coat * ggx_times_cosine(s.clearcoat_normal, s.view_dir, light_dir, s.clearcoat_roughness));
    }
    return lobes;
}

// Both lobes together.
fn brdf_times_cosine(s: ShadingInput, light_dir: vec3<f32>) -> vec3<f32> {
    let lobes = brdf_lobes_times_cosine(s, light_dir);
    return lobes.diffuse + lobes.specular;
}
