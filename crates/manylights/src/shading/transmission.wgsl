// Light through transmissive surfaces (KHR_materials_transmission, KHR_materials_volume), as the
// specification composes it: the dielectric's diffuse lobe gives its `transmission` share to a
// specular transmission lobe, which carries the light behind the surface through the base colour,
// the medium's attenuation and what the specular lobe does not reflect. Where that light comes from
// is the pass's: `$TRANSMITTED_LIGHT` defines `transmitted_light(s)`, the radiance arriving along the
// refracted ray (the transparent pass reads it from the image of the opaque surfaces). Lights and the
// sun behind the surface shine through its transmission lobe (`shading/brdf.wgsl`).
#include "shading/environment.wgsl"
#include "$TRANSMITTED_LIGHT"

// The light arriving along `path` through the medium, as much as it lets through.
fn transmitted_through_medium(s: ShadingInput, path: vec3<f32>) -> vec3<f32> {
    return medium_transmittance(s, length(path)) * transmitted_light(s, path);
}

// Radiance a transmissive surface passes on towards its viewer: the light behind it times the
// transmission lobe's weight — its share, the base colour, the medium's transmittance, one minus the
// dielectric's specular albedo (the BRDF table's, as the environment's reflection uses), below any
// sheen and clear coat and for the non-metallic part only.
fn transmitted_radiance(s: ShadingInput) -> vec3<f32> {
    let path = transmission_path(s);
    let scale_bias = environment_scale_bias(s.normal, s.view_dir, s.roughness);
    let dielectric = surface_dielectric(s);
    let reflected = dielectric.w * (dielectric.xyz * scale_bias.x + scale_bias.y);
    let weight = s.transmission * (1.0 - s.metallic) * sheen_leaves_view(s) * (1.0 - clearcoat_fresnel(s));
    var light = transmitted_through_medium(s, path);
    if s.dispersion > 0.0 && s.thickness > 0.0 {
        // KHR_materials_dispersion: red and blue are bent by indices half the specification's
        // spread, (ior − 1) × 0.025 × dispersion, below and above the index green keeps.
        let half_spread = (s.ior - 1.0) * 0.025 * s.dispersion;
        light.r = transmitted_through_medium(s, transmission_path_at(s, s.ior - half_spread)).r;
        light.b = transmitted_through_medium(s, transmission_path_at(s, s.ior + half_spread)).b;
    }
    return weight * s.base_color * (1.0 - reflected) * light;
}
