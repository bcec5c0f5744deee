#include "shading/scene_bindings.wgsl"
#include "shading/shading_input.wgsl"

// Cook-Torrance specular (GGX distribution, height-correlated Smith visibility, Schlick Fresnel) plus
// Lambert diffuse: the glTF metallic-roughness BRDF, with its extensions' dielectric reflectance
// (KHR_materials_ior, KHR_materials_specular) and clear coat (KHR_materials_clearcoat), as their
// specifications compose them: mix(dielectric, metal, metallic) under the coat, where the
// dielectric is `diffuse · (1 − weight · max(F)) + specular · weight · F`, and the coat mixes in
// by `clearcoat · F_coat(n_coat · v)`. A transmissive dielectric (KHR_materials_transmission) lets
// its `transmission` share of the diffuse lobe through instead: light from behind reaches the viewer
// through a specular transmission lobe (`transmission_lobe_times_cosine`). A sheen
// (KHR_materials_sheen) lies between them and the coat: its Charlie lobe is added, and what lies
// below keeps `1 − max(sheen colour) × E` of the light, E the sheen's albedo (`sheen_albedo`).

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
    return transmission_path_at(s, s.ior);
}

// `transmission_path` at index of refraction `ior`.
fn transmission_path_at(s: ShadingInput, ior: f32) -> vec3<f32> {
    let refracted = refract(-s.view_dir, s.normal, 1.0 / max(ior, 1.0));
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

// The sheen's directional albedo at cosine `cosine` (white sheen; `scene::ibl::sheen_albedo_table`).
fn sheen_albedo(cosine: f32, roughness: f32) -> f32 {
    let size = vec2<f32>(textureDimensions(environment_brdf_table));
    // Clamped to the texel centres: the sampler wraps horizontally.
    let uv = clamp(vec2<f32>(cosine, roughness), 0.5 / size, 1.0 - 0.5 / size);
    return textureSampleLevel(environment_brdf_table, environment_sampler, uv, 0.0).b;
}

// The share of light the sheen leaves the material below it, for view and light albedos `e_view`
// and `e_light` (the specification's min(1 − max(colour) E(v), 1 − max(colour) E(l))).
fn sheen_leaves(s: ShadingInput, e_view: f32, e_light: f32) -> f32 {
    return saturate(1.0 - max(s.sheen_color.x, max(s.sheen_color.y, s.sheen_color.z)) * max(e_view, e_light));
}

// The sheen's albedo towards the viewer.
fn sheen_view_albedo(s: ShadingInput) -> f32 {
    return sheen_albedo(max(dot(s.normal, s.view_dir), 1e-4), max(s.sheen_roughness, MIN_ROUGHNESS));
}

// What a sheen leaves of the light the material below it sends towards the viewer (1 without one).
fn sheen_leaves_view(s: ShadingInput) -> f32 {
    if !has_sheen(s) {
        return 1.0;
    }
    let albedo = sheen_view_albedo(s);
    return sheen_leaves(s, albedo, albedo);
}

// The Charlie distribution (Estevez & Kulla 2017). Keep in sync with `scene::ibl::d_charlie`.
fn d_charlie(n_dot_h: f32, roughness: f32) -> f32 {
    let inverse_alpha = 1.0 / (roughness * roughness);
    let sin_sq = max(1.0 - n_dot_h * n_dot_h, 0.0);
    return (2.0 + inverse_alpha) * pow(sin_sq, 0.5 * inverse_alpha) / (2.0 * PI);
}

// Estevez and Kulla's fit to the sheen's Λ at cosine `x`.
fn sheen_lambda_fit(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let a = mix(21.5473, 25.3245, t);
    let b = mix(3.82987, 3.32435, t);
    let c = mix(0.19823, 0.16801, t);
    let d = mix(-1.97760, -1.27393, t);
    let e = mix(-4.32054, -4.85967, t);
    return a / (1.0 + b * pow(x, c)) + d * x + e;
}

fn sheen_lambda(cosine: f32, alpha: f32) -> f32 {
    if cosine < 0.5 {
        return exp(sheen_lambda_fit(cosine, alpha));
    }
    return exp(2.0 * sheen_lambda_fit(0.5, alpha) - sheen_lambda_fit(1.0 - cosine, alpha));
}

// The sheen's visibility G / (4 n·l n·v). Keep in sync with `scene::ibl::v_sheen`.
fn v_sheen(n_dot_v: f32, n_dot_l: f32, roughness: f32) -> f32 {
    let alpha = roughness * roughness;
    return saturate(1.0 / ((1.0 + sheen_lambda(n_dot_v, alpha) + sheen_lambda(n_dot_l, alpha)) * (4.0 * n_dot_v * n_dot_l)));
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
    if has_sheen(s) && (n_dot_l > 0.0 || lit_from_behind(s)) {
        // The sheen's lobe joins the specular one; both lobes below keep what it leaves.
        let n_dot_v = max(dot(s.normal, s.view_dir), 1e-4);
        let roughness = max(s.sheen_roughness, MIN_ROUGHNESS);
        let n_dot_l = abs(dot(s.normal, light_dir));
        let leaves = sheen_leaves(s, sheen_albedo(n_dot_v, roughness), sheen_albedo(n_dot_l, roughness));
        lobes.diffuse *= leaves;
        lobes.specular *= leaves;
        if dot(s.normal, light_dir) > 0.0 {
            let n_dot_h = saturate(dot(s.normal, normalize(light_dir + s.view_dir)));
            lobes.specular += s.sheen_color * (d_charlie(n_dot_h, roughness) * v_sheen(n_dot_v, n_dot_l, roughness) * n_dot_l);
        }
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
