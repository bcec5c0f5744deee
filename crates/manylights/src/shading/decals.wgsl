// Decal application: each decal covering a shading point projects its material (albedo and alpha,
// roughness and metallic, normal) onto the surface. Layers are blended bottom to top; decals of one
// layer are blended order-independently (weighted blended OIT, McGuire & Bavoil 2013), per attribute c:
//
//     c = (Σ cᵢ αᵢ wᵢ / Σ αᵢ wᵢ) (1 − Π (1 − αᵢ)) + c₀ Π (1 − αᵢ)
//
// where c₀ is the value below the layer. The enumeration modules (`shading/enumerate/decals_*.wgsl`)
// call `decal_blend_begin`, `decal_accumulate` per candidate decal, and `decal_blend_end`. Layers
// above a point's that leave no transmittance in albedo and in normals hide it exactly (its result
// is multiplied by 0): modules that meet decals top layer first skip such decals
// (`decal_accumulate_top_down`).
#include "shading/scene_bindings.wgsl"
#include "shading/shading_input.wgsl"
#include "shading/material.wgsl"
#include "accel/bvh_types.wgsl"
#include "shading/decal_bindings.wgsl"
#include "shading/debug_view.wgsl"

const DECAL_LAYERS: u32 = 4u;
// Decals fade out as the surface turns edge-on to the projector: fully applied from this cosine up.
const DECAL_FULL_FACING: f32 = 0.25;

// One layer's sums: Σ c α w for each attribute, Σ α w and Π (1 − α). Normals have their own α sums,
// because decals without a normal texture leave normals alone.
struct DecalLayerSums {
    albedo: vec3<f32>,
    alpha_weight: f32,
    normal: vec3<f32>,
    normal_alpha_weight: f32,
    roughness: f32,
    metallic: f32,
    transmittance: f32,
    normal_transmittance: f32,
}

// Not zero-filled on Vulkan (`gpu/spirv.rs`, UNZEROED_VARIABLES): a layer is written when its bit
// in `decal_layers_touched` is set, and read only after.
var<private> decal_layers: array<DecalLayerSums, DECAL_LAYERS>;
// Bit L set: layer L has sums. Most points are under no decal, and skip the layers entirely. Bits
// 8 + L and 16 + L (DECAL_LAYERS ≤ 8): layer L's decals leave no transmittance in albedo, in normals
// (`decal_lowest_shown`).
var<private> decal_layers_touched: u32;

fn decal_blend_begin() {
    decal_layers_touched = 0u;
    debug_decals_covering = 0u;
}

// The shading point as the decals of one group see it: its normal and position gradients in the
// group's space, where the decals' boxes are (`decal_world_surface`: the same in the world). Instances are rigid with a uniform scale, so the normal
// keeps unit length once the scale is multiplied back.
struct DecalSurface {
    normal: vec3<f32>,
    ddx: vec3<f32>,
    ddy: vec3<f32>,
}

fn decal_world_surface(s: ShadingInput, dp: PositionGradients) -> DecalSurface {
    return DecalSurface(s.normal, dp.ddx, dp.ddy);
}

fn decal_surface_in_group(world: DecalSurface, instance: VolumeInstance) -> DecalSurface {
    return DecalSurface(
        instance_vector_to_group(instance, world.normal) * instance.scale,
        instance_vector_to_group(instance, world.ddx),
        instance_vector_to_group(instance, world.ddy),
    );
}

// Adds decal `index` if the point (`local`, in the decal's group space) is inside its box. `surface`
// is the surface before any decal, in the same group's space (`decal_surface_in_group`). The record's
// box is read first and the rest only for decals whose box holds the point, as with lights: decals
// that fail the box test never load their whole record (benchmarks/LOG.md, topic 3).
fn decal_accumulate(index: u32, instance: VolumeInstance, local: vec3<f32>, surface: DecalSurface) {
    let decal_from_group = decals[index].decal_from_group;
    let p = vec4<f32>(local, 1.0) * decal_from_group;
    if any(abs(p) > vec3<f32>(0.5)) {
        return;
    }
    // The rows of decal_from_group are the gradients of the decal coordinates: along the box's axes.
    let axis_z = decal_from_group[2].xyz;
    let facing_length = dot(surface.normal, axis_z);
    if facing_length <= 0.0 {
        return;
    }
    let facing = facing_length * inverseSqrt(dot(axis_z, axis_z));
    let to_decal = mat3x3<f32>(decal_from_group[0].xyz, decal_from_group[1].xyz, decal_from_group[2].xyz);
    let ddx = surface.ddx * to_decal;
    let ddy = surface.ddy * to_decal;
    // u along +x, v down along -y: the image as seen from the projector.
    let g = TextureCoordinates(vec2<f32>(p.x + 0.5, 0.5 - p.y), vec2<f32>(ddx.x, -ddx.y), vec2<f32>(ddy.x, -ddy.y));

    let material = decals[index].material;
    let color = decal_base_color(material, g);
    let alpha = saturate(color.a) * smoothstep(0.0, DECAL_FULL_FACING, facing);
    if alpha <= 0.0 {
        return;
    }
    if DEBUG_VIEWS {
        debug_decals_covering += 1u;
    }
    let aw = alpha * decals[index].weight;
    let roughness_metallic = decal_roughness_metallic(material, g);
    let layer = min(decals[index].layer, DECAL_LAYERS - 1u);
    if (decal_layers_touched & (1u << layer)) == 0u {
        decal_layers_touched |= 1u << layer;
        decal_layers[layer] = DecalLayerSums(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, 0.0, 0.0, 1.0, 1.0);
    }
    decal_layers[layer].albedo += color.rgb * aw;
    decal_layers[layer].roughness += roughness_metallic.x * aw;
    decal_layers[layer].metallic += roughness_metallic.y * aw;
    decal_layers[layer].alpha_weight += aw;
    decal_layers[layer].transmittance *= 1.0 - alpha;
    // Opaque as `decal_blend_end` applies layers: with weight as well.
    if decal_layers[layer].transmittance == 0.0 && decal_layers[layer].alpha_weight > 0.0 {
        decal_layers_touched |= 0x100u << layer;
    }

    if materials[material].normal_layer != NO_TEXTURE {
        // The decal's tangent frame on the surface: its x axis made orthogonal to the surface normal,
        // and the normal's cross product with that on the side of its y axis, so the normal map bends
        // the surface's own normal; the result turned into the world. (The axis is not parallel to
        // the normal: then the decal would face the surface edge-on, and have no alpha.)
        let n = surface.normal;
        let axis_x = decal_from_group[0].xyz;
        let t = normalize(axis_x - n * dot(n, axis_x));
        let n_cross_t = cross(n, t);
        let b = select(n_cross_t, -n_cross_t, dot(n_cross_t, decal_from_group[1].xyz) < 0.0);
        let texel = textureSampleGrad(decal_data_textures, wrap_u2_v2, g.uv, materials[material].normal_layer, g.ddx, g.ddy).xyz;
        let decal_normal = instance_direction_to_world(instance, normal_map_applied(texel, materials[material].normal_scale, n, t, b));
        decal_layers[layer].normal += decal_normal * aw;
        decal_layers[layer].normal_alpha_weight += aw;
        decal_layers[layer].normal_transmittance *= 1.0 - alpha;
        if decal_layers[layer].normal_transmittance == 0.0 && decal_layers[layer].normal_alpha_weight > 0.0 {
            decal_layers_touched |= 0x10000u << layer;
        }
    }
}

// The lowest layer whose decals may still show at the point, given those accumulated so far: a layer
// is hidden where a layer above it leaves no transmittance in albedo and one (the same or another)
// none in normals, since `decal_blend_end` multiplies what is below those by 0 (exactly, for finite
// values). It only rises as decals accumulate, so skipping the decals below it is exact in any order;
// modules that meet decals top layer first skip the most. Debug views count every decal.
fn decal_lowest_shown() -> u32 {
    let opaque = (vec2<u32>(decal_layers_touched) >> vec2<u32>(8u, 16u)) & vec2<u32>(0xffu);
    let highest_opaque = firstLeadingBit(opaque);
    return select(0u, min(highest_opaque.x, highest_opaque.y), all(opaque != vec2<u32>(0u)) && !DEBUG_VIEWS);
}

// `decal_accumulate` but for decals of layers hidden at the point, `layer` being decal `index`'s (the
// caller's copy, so that a hidden decal's record is not read).
fn decal_accumulate_top_down(index: u32, layer: u32, instance: VolumeInstance, local: vec3<f32>, surface: DecalSurface) {
    if layer < decal_lowest_shown() {
        return;
    }
    decal_accumulate(index, instance, local, surface);
}

// A decal material's base colour with alpha and its roughness and metallic, as `material.wgsl`'s for
// surfaces, from the material's record for decals (its textures in the decal arrays), read field by
// field. Decals sample their textures clamped to the edges (`wrap_u2_v2`), whatever the material's
// wrap modes (`scene::Decal`): the switch over the nine wrap-mode samplers that surfaces take is
// costly for crowded decals, most of all in fragments (benchmarks/LOG.md, topic 2).
fn decal_base_color(material: u32, g: TextureCoordinates) -> vec4<f32> {
    var color = materials[material].base_color_factor;
    let layer = materials[material].base_color_layer;
    if layer != NO_TEXTURE {
        color *= textureSampleGrad(decal_color_textures, wrap_u2_v2, g.uv, layer, g.ddx, g.ddy);
    }
    return color;
}

fn decal_roughness_metallic(material: u32, g: TextureCoordinates) -> vec2<f32> {
    var roughness_metallic = vec2<f32>(materials[material].roughness_factor, materials[material].metallic_factor);
    let layer = materials[material].metallic_roughness_layer;
    if layer != NO_TEXTURE {
        roughness_metallic *= textureSampleGrad(decal_data_textures, wrap_u2_v2, g.uv, layer, g.ddx, g.ddy).gb;
    }
    return saturate(roughness_metallic);
}

// The surface with every accumulated layer blended over it, bottom to top.
fn decal_blend_end(s: ShadingInput) -> ShadingInput {
    var out = s;
    var touched = decal_layers_touched & ((1u << DECAL_LAYERS) - 1u);
    while touched != 0u {
        // Lowest layer first: bottom to top.
        let layer = firstTrailingBit(touched);
        touched &= touched - 1u;
        let sums = decal_layers[layer];
        if sums.alpha_weight > 0.0 {
            let coverage = 1.0 - sums.transmittance;
            let scale = coverage / sums.alpha_weight;
            out.base_color = sums.albedo * scale + out.base_color * sums.transmittance;
            out.roughness = sums.roughness * scale + out.roughness * sums.transmittance;
            out.metallic = sums.metallic * scale + out.metallic * sums.transmittance;
        }
        if sums.normal_alpha_weight > 0.0 {
            let coverage = 1.0 - sums.normal_transmittance;
            let blended = sums.normal * (coverage / sums.normal_alpha_weight) + out.normal * sums.normal_transmittance;
            // Where the layer's normals cancel out, the normal below stays, or the surface's own
            // where the layer leaves nothing below showing (so that hidden layers stay hidden).
            let kept = select(out.normal, s.normal, sums.normal_transmittance == 0.0);
            out.normal = select(kept, normalize(blended), dot(blended, blended) > 1e-12);
        }
    }
    return out;
}
