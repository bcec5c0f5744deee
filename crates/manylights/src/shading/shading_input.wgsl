// The surface every pipeline hands to the shading core: built by the visibility-buffer resolve, the
// G-buffer decode and forward fragments. Decals modify it before `shade`.

// Some material of the scene uses the extensions' parameters below (`ShadingMethods::
// material_extensions`); where none does, the passes compile glTF's core material alone, the same
// formulas at the parameters' default values.
override MATERIAL_EXTENSIONS: bool = true;

// The pass shades transmissive surfaces (KHR_materials_transmission): only the transmissive and
// transparent passes, and only where some material is (`ShadingMethods::transmission`). Elsewhere the transmission terms are
// compiled out.
override TRANSMISSION: bool = false;

// Some material has a sheen (KHR_materials_sheen; `ShadingMethods::sheen`): where none does, its
// layer is compiled out. Apart from MATERIAL_EXTENSIONS, so that a scene whose only extension is
// sheen leaves the others' path out.
override SHEEN: bool = true;

struct ShadingInput {
    position: vec3<f32>,
    // Shading normal (after normal mapping), unit, facing the viewer's side.
    normal: vec3<f32>,
    // Unit vector from the surface towards the eye.
    view_dir: vec3<f32>,
    base_color: vec3<f32>,
    alpha: f32,
    metallic: f32,
    // Perceptual roughness (alpha = roughness²).
    roughness: f32,
    emissive: vec3<f32>,
    // The dielectric's specular reflectance at normal incidence and its weight, which is also its
    // reflectance at grazing incidence (KHR_materials_ior, KHR_materials_specular; 0.04 and 1 for
    // glTF's core material); a metal reflects its base colour.
    dielectric_f0: vec3<f32>,
    specular_weight: f32,
    // A clear coat over it (KHR_materials_clearcoat): its strength (0: none), perceptual roughness
    // and unit normal, on the viewer's side as `normal` is.
    clearcoat: f32,
    clearcoat_roughness: f32,
    clearcoat_normal: vec3<f32>,
    // KHR_materials_unlit: `base_color` is the radiance sent, and nothing lights it.
    unlit: bool,
    // Light let through (KHR_materials_transmission): the share of the dielectric's diffuse lobe
    // passed on instead, the index of refraction bending it, and the medium behind
    // (KHR_materials_volume): its thickness in world units (0: thin-walled) and the colour left
    // after distance w (w = 0: clear) in `attenuation`, and how far its index of refraction spreads
    // over the colours (KHR_materials_dispersion).
    transmission: f32,
    ior: f32,
    thickness: f32,
    attenuation: vec4<f32>,
    dispersion: f32,
    // A sheen over it all but the clear coat (KHR_materials_sheen): its colour (black: none) and
    // perceptual roughness.
    sheen_color: vec3<f32>,
    sheen_roughness: f32,
    // The share of the environment's light reaching the surface (glTF's occlusion texture, 1
    // without): it darkens the environment standing in for indirect light, not the lights.
    occlusion: f32,
    // Where rays leave the surface (shadow rays towards local lights): its geometric normal on the
    // viewer's side, and how far off the surface `position` may lie — `surface_clearance` for a
    // position rebuilt from depth or interpolated by the raster, 0 at a ray's hit, which is exact.
    ray_normal: vec3<f32>,
    ray_clearance: f32,
}

// Whether the surface has a sheen, in a pass compiled with them.
fn has_sheen(s: ShadingInput) -> bool {
    return SHEEN && any(s.sheen_color > vec3<f32>(0.0));
}

// World-space change of the shading position from one pixel to the next in x and y (or, at a ray's
// hit, across its cone): decal textures are sampled with gradients from it (compute has no implicit
// derivatives).
struct PositionGradients {
    ddx: vec3<f32>,
    ddy: vec3<f32>,
}
