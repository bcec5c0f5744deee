// Light through transmissive surfaces (KHR_materials_transmission, KHR_materials_volume), as the
// specification composes it: the dielectric's diffuse lobe gives its `transmission` share to a
// specular transmission lobe, which carries the light behind the surface through the base colour,
// the medium's attenuation and what the specular lobe does not reflect. Where that light comes from
// is the pass's: `$TRANSMITTED_LIGHT` defines `transmitted_light(s)`, the radiance arriving along the
// refracted ray (the transparent pass reads it from the image of the opaque surfaces).
#include "shading/environment.wgsl"
#include "$TRANSMITTED_LIGHT"

// The path light takes through the surface's medium, from the shading point to where it leaves:
// refracted into it by the index of refraction, as long as the medium is thick (0 for thin walls).
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

// Radiance a transmissive surface passes on towards its viewer: the light behind it times the
// transmission lobe's weight — its share, the base colour, the medium's transmittance, one minus the
// dielectric's specular albedo (the BRDF table's, as the environment's reflection uses), below any
// clear coat and for the non-metallic part only.
fn transmitted_radiance(s: ShadingInput) -> vec3<f32> {
    let path = transmission_path(s);
    let scale_bias = environment_scale_bias(s.normal, s.view_dir, s.roughness);
    let dielectric = surface_dielectric(s);
    let reflected = dielectric.w * (dielectric.xyz * scale_bias.x + scale_bias.y);
    let weight = s.transmission * (1.0 - s.metallic) * (1.0 - clearcoat_fresnel(s));
    return weight * s.base_color * (1.0 - reflected) * medium_transmittance(s, length(path)) * transmitted_light(s, path);
}
