// Image-based lighting from the scene's environment (`gpu/environment.rs`, `scene/ibl.rs`): the
// split-sum approximation. Diffuse light from the irradiance's spherical harmonics; specular light
// from the environment prefiltered for the surface's roughness times the BRDF table's scale and bias
// on F0. A uniform environment (the scene's `ambient`) gives its radiance times the albedos.
#include "shading/scene_bindings.wgsl"
#include "shading/shading_input.wgsl"
#include "shading/brdf.wgsl"

// Equirectangular coordinates of unit `dir`: centre column −Z, top row +Y. Keep in sync with
// `scene::environment::uv_of`.
fn environment_uv(dir: vec3<f32>) -> vec2<f32> {
    return vec2<f32>(atan2(dir.x, -dir.z) / (2.0 * PI) + 0.5, acos(clamp(dir.y, -1.0, 1.0)) / PI);
}

// Irradiance / π at unit normal `n`. Keep in sync with `scene::ibl::evaluate_irradiance`.
fn environment_irradiance(n: vec3<f32>) -> vec3<f32> {
    let c = frame.environment_irradiance;
    let irradiance = c[0].rgb + c[1].rgb * n.y + c[2].rgb * n.z + c[3].rgb * n.x + c[4].rgb * (n.x * n.y) + c[5].rgb * (n.y * n.z)
        + c[6].rgb * (3.0 * n.z * n.z - 1.0) + c[7].rgb * (n.x * n.z) + c[8].rgb * (n.x * n.x - n.y * n.y);
    // Nine harmonics ring slightly negative opposite a bright sky.
    return max(irradiance, vec3<f32>(0.0));
}

// The environment along `dir` prefiltered with the GGX lobe of perceptual `roughness`.
fn environment_specular_radiance(dir: vec3<f32>, roughness: f32) -> vec3<f32> {
    let level = saturate(roughness) * frame.environment.x;
    return textureSampleLevel(environment_prefiltered, environment_sampler, environment_uv(dir), level).rgb;
}

// The direction whose prefiltered radiance a surface reflects towards its viewer.
fn environment_reflection_direction(s: ShadingInput) -> vec3<f32> {
    return reflect(-s.view_dir, s.normal);
}

// The BRDF table's scale and bias on F0 (F90 for the bias) for unit normal `n` and `roughness`.
fn environment_scale_bias(n: vec3<f32>, view_dir: vec3<f32>, roughness: f32) -> vec2<f32> {
    let size = vec2<f32>(textureDimensions(environment_brdf_table));
    let n_dot_v = max(dot(n, view_dir), 1e-4);
    // Clamped to the texel centres: the sampler wraps horizontally.
    let uv = clamp(vec2<f32>(n_dot_v, roughness), 0.5 / size, 1.0 - 0.5 / size);
    return textureSampleLevel(environment_brdf_table, environment_sampler, uv, 0.0).rg;
}

// The fraction of the (prefiltered) environment the material below any sheen and clear coat
// reflects towards its viewer: F0 × scale + F90 × bias from the BRDF table, by n·v and roughness;
// the sheen's and the coat's shares removed.
fn environment_specular_albedo(s: ShadingInput) -> vec3<f32> {
    let scale_bias = environment_scale_bias(s.normal, s.view_dir, s.roughness);
    let dielectric = surface_dielectric(s);
    let f0 = mix(dielectric.w * dielectric.xyz, s.base_color, s.metallic);
    let f90 = mix(dielectric.w, 1.0, s.metallic);
    return (f0 * scale_bias.x + f90 * scale_bias.y) * sheen_leaves_view(s) * (1.0 - clearcoat_fresnel(s));
}

// The fraction of a uniform environment a sheen reflects towards its viewer, below any clear coat
// (0 without one): its colour times its albedo.
fn environment_sheen_albedo(s: ShadingInput) -> vec3<f32> {
    if !has_sheen(s) {
        return vec3<f32>(0.0);
    }
    return s.sheen_color * sheen_view_albedo(s) * (1.0 - clearcoat_fresnel(s));
}

// Diffuse and specular light from the environment, and the sheen's and the clear coat's reflections
// of it, as much as the surface's occlusion lets through.
fn environment_light(s: ShadingInput) -> vec3<f32> {
    let irradiance = environment_irradiance(s.normal);
    var diffuse = irradiance * s.base_color * (1.0 - s.metallic) * sheen_leaves_view(s) * (1.0 - clearcoat_fresnel(s));
    if TRANSMISSION {
        diffuse *= 1.0 - s.transmission;
    }
    let specular = environment_specular_albedo(s) * environment_specular_radiance(environment_reflection_direction(s), s.roughness);
    // The sheen reflects the irradiance times its albedo, as it reflects a uniform environment
    // exactly (no environment is prefiltered for its lobe).
    let sheen = environment_sheen_albedo(s) * irradiance;
    var coat = vec3<f32>(0.0);
    if MATERIAL_EXTENSIONS && s.clearcoat > 0.0 {
        let scale_bias = environment_scale_bias(s.clearcoat_normal, s.view_dir, s.clearcoat_roughness);
        let direction = reflect(-s.view_dir, s.clearcoat_normal);
        coat = clearcoat_fresnel(s) * (scale_bias.x + scale_bias.y) * environment_specular_radiance(direction, s.clearcoat_roughness);
    }
    return (diffuse + specular + sheen + coat) * s.occlusion;
}

// Whether the sun's disc is seen in the sky (`sky_radiance`): with the daylight sky, where the scene
// has a sun of some angular size.
fn sun_disc_seen() -> bool {
    return frame.environment.y > 0.0 && frame.sun_direction.w > 0.0 && frame.ray_settings.x > 0.0;
}

// Radiance seen where no geometry was drawn and where reflected rays leave the scene: the
// environment, and with the daylight sky the sun's disc (its angular size the soft shadows').
fn sky_radiance(dir: vec3<f32>) -> vec3<f32> {
    var radiance = textureSampleLevel(environment_radiance, environment_sampler, environment_uv(dir), 0.0).rgb;
    let radius = frame.ray_settings.x;
    if sun_disc_seen() && dot(dir, -frame.sun_direction.xyz) > cos(radius) {
        radiance += frame.sun_radiance.rgb / (PI * radius * radius);
    }
    return radiance;
}
