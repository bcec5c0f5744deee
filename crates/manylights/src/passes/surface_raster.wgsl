// Raster passes that rebuild surfaces in the fragment stage — the forward pipeline's depth prepass
// and shading pass, the deferred pipeline's G-buffer — share this vertex function and the fragment's
// surface. The forward passes must compute bit-identical positions for the EQUAL depth test, hence one
// function and `@invariant`. Indexed draws, one draw per instance of a primitive (`instance_index` is
// the draw).
#include "shading/scene_bindings.wgsl"
#include "shading/material.wgsl"
#include "shading/camera.wgsl"

struct ForwardVertex {
    @builtin(position) @invariant clip_position: vec4<f32>,
    @location(0) @interpolate(flat) draw_index: u32,
    @location(1) uv: vec4<f32>,
    // World position relative to the camera, like the visibility-buffer resolve's (precision far from
    // the origin).
    @location(2) relative_position: vec3<f32>,
    // Local-space normal and tangent: the fragment takes them to world space as the resolve does.
    @location(3) normal: vec3<f32>,
    @location(4) tangent: vec4<f32>,
    @location(5) color: vec4<f32>,
}

@vertex
fn forward_vertex(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) draw_index: u32) -> ForwardVertex {
    // An indexed draw's vertex_index already includes the draw's base vertex.
    let vertex = vertices[vertex_index];
    let draw = draws[draw_index];
    let world = draw.world_from_local * vec4<f32>(vertex.position, 1.0);
    var out: ForwardVertex;
    out.clip_position = frame.clip_from_world * world;
    out.draw_index = draw_index;
    out.uv = vertex_uvs(vertex);
    out.relative_position = world.xyz - frame.world_from_view[3].xyz;
    out.normal = vertex.normal;
    out.tangent = vertex.tangent;
    out.color = vertex_color(vertex);
    return out;
}

// The fragment's surface and material, before decals: the fragment stage's counterpart of the
// visibility-buffer resolve. `front_facing` follows the pipeline's winding, which mirrored instances
// reverse; back faces only reach here on double-sided materials and turn their whole tangent frame
// over, as the resolve does.
fn fragment_surface(in: ForwardVertex, front_facing: bool, g: UvGradients) -> ShadingInput {
    let draw = draws[in.draw_index];
    let position = in.relative_position + frame.world_from_view[3].xyz;
    let view_dir = -camera_ray(in.clip_position.xy).dir;
    var surface: SurfaceFrame;
    surface.normal = normalize(world_normal(draw, in.normal));
    surface.tangent = world_direction(draw, in.tangent.xyz);
    surface.bitangent_sign = in.tangent.w * sign(draw.normal_from_local[0].w);
    if !front_facing {
        surface.normal = -surface.normal;
        surface.tangent = -surface.tangent;
        surface.bitangent_sign = -surface.bitangent_sign;
    }
    return evaluate_material(materials[draw.material], surface, g, in.color, position, view_dir);
}

// The fragment's surface for shading passes, which trace rays from it: with its triangle's normal and
// the raster's interpolation error as where rays leave.
fn fragment_shading_surface(in: ForwardVertex, front_facing: bool, g: UvGradients, dp: PositionGradients) -> ShadingInput {
    var s = fragment_surface(in, front_facing, g);
    s.ray_normal = fragment_geometric_normal(dp, s.view_dir);
    s.ray_clearance = surface_clearance(in.relative_position);
    return s;
}

// Whether an alpha-masked fragment covers its pixel (derivatives taken before any discard).
fn forward_alpha_covers(in: ForwardVertex, g: UvGradients) -> bool {
    let material = materials[draws[in.draw_index].material];
    return material_base_color(material, g, in.color).a >= material.alpha_cutoff;
}

// The unit geometric normal of the fragment's triangle, from its position derivatives, on the
// viewer's side.
fn fragment_geometric_normal(dp: PositionGradients, view_dir: vec3<f32>) -> vec3<f32> {
    let n = normalize(cross(dp.ddx, dp.ddy));
    return select(n, -n, dot(n, view_dir) < 0.0);
}
