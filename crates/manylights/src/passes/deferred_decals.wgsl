// Deferred decals (Kim, "Using Deferred Decals", 2012), the classic method the acceleration
// structures are compared against: each decal's box is rasterised over the G-buffer, layer after
// layer, and its fragments blend the decal's albedo, normal and roughness-metallic into the G-buffer
// with the hardware's "over" blending, before lighting. A fragment finds its surface from the depth (and,
// for normal decals, the surface normal from a copy of the G-buffer's normals), and evaluates the
// decal with the shading core's `decal_accumulate`: same box test, fading, texture gradients and
// tangent frame as every other method.
//
// What differs from the shading core's blend (`shading/decals.wgsl`), by construction:
// - decals blend in draw order (by layer; within a layer boxes away from the eye, then boxes around
//   it, each by index), not by weighted blended OIT within a layer, and decal weights are ignored:
//   identical where decals of one layer do not overlap;
// - the blend happens in the G-buffer's precision (8-bit sRGB albedo, 8-bit roughness-metallic) and
//   normals blend as octahedral coordinates, not as vectors;
// - only opaque surfaces in the G-buffer receive them: transparent surfaces drawn later cannot.
#include "shading/decal_bindings.wgsl"
#include "passes/gbuffer.wgsl"
#include "passes/gbuffer_surface.wgsl"

@group(1) @binding(0) var depth: texture_depth_2d;
// The G-buffer's normals before any decal: the render target itself cannot be read while blended.
@group(1) @binding(1) var surface_normals: texture_2d<f32>;
// (decal instance, decal) pairs in draw order.
@group(1) @binding(2) var<storage, read> draw_order: array<vec2<u32>>;

struct DecalVertex {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) @interpolate(flat) pair: vec2<u32>,
}

// The box's 12 triangles, two per face, wound counter-clockwise seen from outside; corner i has
// coordinates (i & 1, (i >> 1) & 1, (i >> 2) & 1).
const BOX_CORNERS: array<u32, 36> = array<u32, 36>(
    0u, 2u, 1u, 1u, 2u, 3u, // -z
    4u, 5u, 6u, 5u, 7u, 6u, // +z
    0u, 1u, 4u, 1u, 5u, 4u, // -y
    2u, 6u, 3u, 3u, 6u, 7u, // +y
    0u, 4u, 2u, 2u, 4u, 6u, // -x
    1u, 3u, 5u, 3u, 7u, 5u, // +x
);

// Distance from the eye to the near plane's corners: a box nearer the eye than this may be cut open
// by the near plane.
fn near_plane_reach() -> f32 {
    let corner = frame.view_from_clip * vec4<f32>(1.0, 1.0, 1.0, 1.0);
    return length(corner.xyz / corner.w);
}

// Which boxes this pipeline draws. Boxes away from the eye: front faces, depth-tested against the
// G-buffer (reverse Z: passing where the face is in front of the surface), so boxes hidden behind
// nearer surfaces cost no fragment work. Boxes around the eye (within the near plane's reach) have no
// front face in view: back faces, untested — the classic method's "camera inside" case.
override AROUND_THE_EYE: bool = false;

@vertex
fn deferred_decal_vertex(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) draw: u32) -> DecalVertex {
    let pair = draw_order[draw];
    let decal = decals[pair.y];
    let instance = decal_instances[pair.x];
    let corner = BOX_CORNERS[vertex_index];
    var local = vec3<f32>(vec3<u32>(corner, corner >> 1u, corner >> 2u) & vec3<u32>(1u)) - 0.5;
    // Decals store decal_from_group (rows); the box's corners need its inverse.
    let to_decal = mat3x3<f32>(decal.decal_from_group[0].xyz, decal.decal_from_group[1].xyz, decal.decal_from_group[2].xyz);
    // The eye in decal space; a world distance d moves decal coordinate i by at most d |row i| / scale.
    let eye = vec4<f32>(instance_point_to_group(instance, frame.world_from_view[3].xyz), 1.0) * decal.decal_from_group;
    let reach = near_plane_reach() / instance.scale * vec3<f32>(length(to_decal[0]), length(to_decal[1]), length(to_decal[2]));
    var out: DecalVertex;
    out.pair = pair;
    if all(abs(eye) <= vec3<f32>(0.5) + reach) != AROUND_THE_EYE {
        // The other pipeline's box: a point outside the clip volume, so no triangle is drawn.
        out.clip_position = vec4<f32>(0.0, 0.0, -1.0, 1.0);
        return out;
    }
    // A mirroring decal would turn the box inside out: mirror the box too (it is symmetric).
    if determinant(to_decal) < 0.0 {
        local.x = -local.x;
    }
    let offset = vec3<f32>(decal.decal_from_group[0].w, decal.decal_from_group[1].w, decal.decal_from_group[2].w);
    // p_decal = p_group * to_decal + offset (row vector), so p_group = (p_decal - offset) * inverse(to_decal).
    let group = (local - offset) * inverse_3x3(to_decal);
    out.clip_position = frame.clip_from_world * vec4<f32>(instance_point_to_world(instance, group), 1.0);
    return out;
}

fn inverse_3x3(m: mat3x3<f32>) -> mat3x3<f32> {
    let adjugate_transposed = mat3x3<f32>(cross(m[1], m[2]), cross(m[2], m[0]), cross(m[0], m[1]));
    return transpose(adjugate_transposed) * (1.0 / dot(m[0], cross(m[1], m[2])));
}

struct DecalTexel {
    @location(0) albedo: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) roughness_metallic: vec4<f32>,
}

@fragment
fn deferred_decal_fragment(in: DecalVertex) -> DecalTexel {
    let texel = vec2<u32>(in.clip_position.xy);
    let z = textureLoad(depth, texel, 0);
    if z == 0.0 {
        discard;
    }
    let pixel = in.clip_position.xy;
    let relative_position = depth_relative_position(pixel, z);
    var s: ShadingInput;
    s.position = relative_position + frame.world_from_view[3].xyz;
    s.normal = gbuffer_decode_normal(textureLoad(surface_normals, texel, 0));
    let instance = decal_instances[in.pair.x];
    let dp = gbuffer_position_gradients(pixel, relative_position, s.normal);

    decal_blend_begin();
    decal_accumulate(in.pair.y, instance, instance_point_to_group(instance, s.position), decal_surface_in_group(decal_world_surface(s, dp), instance));
    let layer = min(decals[in.pair.y].layer, DECAL_LAYERS - 1u);
    if decal_layers_touched == 0u {
        discard;
    }
    // One decal: its sums are its own values times α w, and 1 − transmittance is its α.
    let sums = decal_layers[layer];
    let alpha = 1.0 - sums.transmittance;
    var out: DecalTexel;
    out.albedo = vec4<f32>(sums.albedo / sums.alpha_weight, alpha);
    out.roughness_metallic = vec4<f32>(sums.roughness / sums.alpha_weight, sums.metallic / sums.alpha_weight, 0.0, alpha);
    // Decals without a normal texture leave normals alone: α 0.
    let normal_alpha = 1.0 - sums.normal_transmittance;
    let normal = select(s.normal, sums.normal / max(sums.normal_alpha_weight, 1e-30), normal_alpha > 0.0);
    out.normal = vec4<f32>(octahedral_encode(normalize(normal)), 0.0, normal_alpha);
    return out;
}
