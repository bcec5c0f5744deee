#include "shading/scene_bindings.wgsl"
#include "shading/shading_input.wgsl"

// Material evaluation: glTF metallic-roughness textures sampled with explicit gradients, so the same
// code runs in compute (visibility-buffer resolve, ray hits) and fragment stages.

// One set of texture coordinates and their screen-space derivatives.
struct TextureCoordinates {
    uv: vec2<f32>,
    ddx: vec2<f32>,
    ddy: vec2<f32>,
}

// A surface's two sets of texture coordinates (glTF's TEXCOORD_0 in xy, TEXCOORD_1 in zw) and their
// screen-space derivatives.
struct UvGradients {
    uv: vec4<f32>,
    ddx: vec4<f32>,
    ddy: vec4<f32>,
}

// Whether any texture reads the second set: a pipeline constant of the shading passes (`plan.rs`,
// `ShadingMethods::second_uv_set`); without, they never choose it (and the resolve's interpolation of
// it is dead code). Alpha-tested raster passes keep the default.
override SECOND_UV_SET: bool = true;

// Samples a layer with the sampler of a slot's wrap modes (`Material.wrap_modes`), at the slot's
// transform of its set of coordinates (`Material.uv_transforms`), their gradients through its linear
// part.
fn sample_wrapped(textures: texture_2d_array<f32>, layer: i32, material: Material, slot: u32, surface: UvGradients) -> vec4<f32> {
    let columns = material.uv_transforms[2u * slot];
    let linear = mat2x2<f32>(columns.xy, columns.zw);
    let translation_set = material.uv_transforms[2u * slot + 1u];
    var coordinates = TextureCoordinates(surface.uv.xy, surface.ddx.xy, surface.ddy.xy);
    if SECOND_UV_SET && translation_set.z != 0.0 {
        coordinates = TextureCoordinates(surface.uv.zw, surface.ddx.zw, surface.ddy.zw);
    }
    let g = TextureCoordinates(linear * coordinates.uv + translation_set.xy, linear * coordinates.ddx, linear * coordinates.ddy);
    switch (material.wrap_modes[slot / 8u] >> ((slot % 8u) * 4u)) & 0xFu {
        case 1u: { return textureSampleGrad(textures, wrap_u1_v0, g.uv, layer, g.ddx, g.ddy); }
        case 2u: { return textureSampleGrad(textures, wrap_u2_v0, g.uv, layer, g.ddx, g.ddy); }
        case 4u: { return textureSampleGrad(textures, wrap_u0_v1, g.uv, layer, g.ddx, g.ddy); }
        case 5u: { return textureSampleGrad(textures, wrap_u1_v1, g.uv, layer, g.ddx, g.ddy); }
        case 6u: { return textureSampleGrad(textures, wrap_u2_v1, g.uv, layer, g.ddx, g.ddy); }
        case 8u: { return textureSampleGrad(textures, wrap_u0_v2, g.uv, layer, g.ddx, g.ddy); }
        case 9u: { return textureSampleGrad(textures, wrap_u1_v2, g.uv, layer, g.ddx, g.ddy); }
        case 10u: { return textureSampleGrad(textures, wrap_u2_v2, g.uv, layer, g.ddx, g.ddy); }
        default: { return textureSampleGrad(textures, wrap_u0_v0, g.uv, layer, g.ddx, g.ddy); }
    }
}

// The functions below read a surface material's textures from `color_textures` (sRGB: base colour,
// emissive, specular colour, sheen colour) and `data_textures` (linear: the others); decals sample their own
// arrays, clamped, in `decals.wgsl`.

// Whether any mesh has vertex colours: a pipeline constant of the shading passes' compute and
// fragment stages (`plan.rs`, `ShadingMethods::vertex_colors`); scenes without them skip them there.
override VERTEX_COLORS: bool = true;

// Base colour with alpha, times the interpolated vertex colour (glTF's COLOR_0, white without);
// used for alpha masking too.
fn material_base_color(material: Material, g: UvGradients, vertex_color: vec4<f32>) -> vec4<f32> {
    var color = material.base_color_factor;
    if VERTEX_COLORS {
        color *= vertex_color;
    }
    if material.base_color_layer != NO_TEXTURE {
        color *= sample_wrapped(color_textures, material.base_color_layer, material, 0u, g);
    }
    return color;
}

// Perceptual roughness and metallic (x, y): factors times the metallic-roughness texture (glTF: G, B).
fn material_roughness_metallic(material: Material, g: UvGradients) -> vec2<f32> {
    var roughness_metallic = vec2<f32>(material.roughness_factor, material.metallic_factor);
    if material.metallic_roughness_layer != NO_TEXTURE {
        roughness_metallic *= sample_wrapped(data_textures, material.metallic_roughness_layer, material, 2u, g).gb;
    }
    return saturate(roughness_metallic);
}

// Whether any material has an occlusion texture: a pipeline constant of the shading passes, as
// VERTEX_COLORS is.
override OCCLUSION_TEXTURES: bool = true;

// The environment's light reaching the surface: 1 + strength × (R − 1) of the occlusion texture.
fn material_occlusion(material: Material, g: UvGradients) -> f32 {
    if !OCCLUSION_TEXTURES || material.occlusion_layer == NO_TEXTURE {
        return 1.0;
    }
    let r = sample_wrapped(data_textures, material.occlusion_layer, material, 9u, g).r;
    return 1.0 + material.occlusion_strength * (r - 1.0);
}

// The material's normal map (it must have one) applied in the frame (t, b, n); a zero-length result
// (blank normal map texel) keeps n.
fn material_mapped_normal(material: Material, g: UvGradients, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return normal_map_applied(sample_wrapped(data_textures, material.normal_layer, material, 3u, g).xyz, material.normal_scale, n, t, b);
}

// A normal map's texel (tangent space, [0, 1]), its x and y scaled by `scale`, in the frame (t, b, n).
fn normal_map_applied(texel: vec3<f32>, scale: f32, n: vec3<f32>, t: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    var n_ts = texel * 2.0 - 1.0;
    n_ts = vec3<f32>(n_ts.xy * scale, n_ts.z);
    let mapped = t * n_ts.x + b * n_ts.y + n * n_ts.z;
    return select(n, normalize(mapped), dot(mapped, mapped) > 1e-12);
}

// A draw's local directions and normals in world space.
fn world_direction(draw: Draw, v: vec3<f32>) -> vec3<f32> {
    return (draw.world_from_local * vec4<f32>(v, 0.0)).xyz;
}

fn world_normal(draw: Draw, n: vec3<f32>) -> vec3<f32> {
    return draw.normal_from_local[0].xyz * n.x + draw.normal_from_local[1].xyz * n.y + draw.normal_from_local[2].xyz * n.z;
}

// The surface frame at a point: interpolated, in world space.
struct SurfaceFrame {
    normal: vec3<f32>,
    tangent: vec3<f32>,
    bitangent_sign: f32,
}

// Fills a ShadingInput from a material and the interpolated surface.
fn evaluate_material(material: Material, surface: SurfaceFrame, g: UvGradients, vertex_color: vec4<f32>, position: vec3<f32>, view_dir: vec3<f32>) -> ShadingInput {
    var s: ShadingInput;
    s.position = position;
    s.view_dir = view_dir;

    let base = material_base_color(material, g, vertex_color);
    s.base_color = base.rgb;
    s.alpha = base.a;

    let roughness_metallic = material_roughness_metallic(material, g);
    s.roughness = roughness_metallic.x;
    s.metallic = roughness_metallic.y;

    var emissive = material.emissive_factor;
    if material.emissive_layer != NO_TEXTURE {
        emissive *= sample_wrapped(color_textures, material.emissive_layer, material, 1u, g).rgb;
    }
    s.emissive = emissive;
    s.occlusion = material_occlusion(material, g);

    let t = normalize(surface.tangent - surface.normal * dot(surface.normal, surface.tangent));
    let b = cross(surface.normal, t) * surface.bitangent_sign;
    var normal = surface.normal;
    if material.normal_layer != NO_TEXTURE {
        normal = material_mapped_normal(material, g, surface.normal, t, b);
    }
    s.normal = normal;

    // Callers that know the triangle's own normal or an uncertain position set these.
    s.ray_normal = surface.normal;
    s.ray_clearance = 0.0;

    // glTF's core material, unless the scene's materials use the extensions.
    s.unlit = false;
    s.dielectric_f0 = vec3<f32>(0.04);
    s.specular_weight = 1.0;
    s.clearcoat = 0.0;
    s.clearcoat_roughness = 0.0;
    s.clearcoat_normal = surface.normal;
    s.transmission = 0.0;
    s.ior = 1.5;
    s.thickness = 0.0;
    s.attenuation = vec4<f32>(1.0, 1.0, 1.0, 0.0);
    s.dispersion = 0.0;
    s.sheen_color = vec3<f32>(0.0);
    s.sheen_roughness = 0.0;
    if MATERIAL_EXTENSIONS {
        material_extensions(material, g, surface, t, b, &s);
    }
    if SHEEN && (material.flags & MATERIAL_SHEEN) != 0u {
        material_sheen(material, g, &s);
    }
    return s;
}

// The extensions' parameters: KHR_materials_unlit, _ior and _specular (textures 4, 5), _clearcoat
// (textures 6 to 8), _transmission and _volume (textures 10, 11; the thickness in the mesh's units,
// which the caller scales to the world's).
fn material_extensions(material: Material, g: UvGradients, surface: SurfaceFrame, t: vec3<f32>, b: vec3<f32>, s: ptr<function, ShadingInput>) {
    (*s).unlit = (material.flags & MATERIAL_UNLIT) != 0u;
    var f0 = material.specular_color;
    if material.specular_color_layer != NO_TEXTURE {
        f0 *= sample_wrapped(color_textures, material.specular_color_layer, material, 5u, g).rgb;
    }
    (*s).dielectric_f0 = min(f0, vec3<f32>(1.0));
    (*s).specular_weight = material.specular_factor;
    if material.specular_layer != NO_TEXTURE {
        (*s).specular_weight *= sample_wrapped(data_textures, material.specular_layer, material, 4u, g).a;
    }
    if (material.flags & MATERIAL_CLEARCOAT) != 0u {
        (*s).clearcoat = material.clearcoat_factor;
        if material.clearcoat_layer != NO_TEXTURE {
            (*s).clearcoat *= sample_wrapped(data_textures, material.clearcoat_layer, material, 6u, g).r;
        }
        (*s).clearcoat_roughness = material.clearcoat_roughness_factor;
        if material.clearcoat_roughness_layer != NO_TEXTURE {
            (*s).clearcoat_roughness *= sample_wrapped(data_textures, material.clearcoat_roughness_layer, material, 7u, g).g;
        }
        if material.clearcoat_normal_layer != NO_TEXTURE {
            let texel = sample_wrapped(data_textures, material.clearcoat_normal_layer, material, 8u, g).xyz;
            (*s).clearcoat_normal = normal_map_applied(texel, material.clearcoat_normal_scale, surface.normal, t, b);
        }
    }
    if (material.flags & MATERIAL_TRANSMISSION) != 0u {
        (*s).transmission = material.transmission_factor;
        if material.transmission_layer != NO_TEXTURE {
            (*s).transmission *= sample_wrapped(data_textures, material.transmission_layer, material, 10u, g).r;
        }
        (*s).thickness = material.thickness_factor;
        if material.thickness_layer != NO_TEXTURE {
            (*s).thickness *= sample_wrapped(data_textures, material.thickness_layer, material, 11u, g).g;
        }
        (*s).ior = material.ior;
        (*s).attenuation = vec4<f32>(material.attenuation_color, material.attenuation_distance);
        (*s).dispersion = material.dispersion;
    }
}

// KHR_materials_sheen's colour and roughness (textures 12, 13).
fn material_sheen(material: Material, g: UvGradients, s: ptr<function, ShadingInput>) {
    (*s).sheen_color = material.sheen_color;
    if material.sheen_color_layer != NO_TEXTURE {
        (*s).sheen_color *= sample_wrapped(color_textures, material.sheen_color_layer, material, 12u, g).rgb;
    }
    (*s).sheen_roughness = material.sheen_roughness;
    if material.sheen_roughness_layer != NO_TEXTURE {
        (*s).sheen_roughness *= sample_wrapped(data_textures, material.sheen_roughness_layer, material, 13u, g).a;
    }
}
