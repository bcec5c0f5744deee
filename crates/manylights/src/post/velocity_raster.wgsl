// The moving instances' velocity (see `velocity.wgsl`): each vertex through its draw's current and
// previous transform (`GpuScene::previous_transforms`), a deformed one from its previous pose, and
// the previous camera; depth-tested against
// the frame's depth so only the surfaces it holds are written, alpha-masked materials' holes
// discarded as the raster did.
#include "shading/scene_bindings.wgsl"
#include "shading/material.wgsl"
#include "post/post_types.wgsl"
#include "shading/previous_vertex.wgsl"

@group(1) @binding(0) var<uniform> post: PostUniforms;
@group(1) @binding(1) var<storage, read> previous_world_from_local: array<mat4x4<f32>>;

struct VelocityVertex {
    @builtin(position) @invariant clip_position: vec4<f32>,
    @location(0) previous_clip: vec4<f32>,
    @location(1) @interpolate(flat) draw_index: u32,
    @location(2) uv: vec4<f32>,
    // The vertex colour's alpha, for alpha masks.
    @location(3) alpha: f32,
}

@vertex
fn velocity_vertex(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) draw_index: u32) -> VelocityVertex {
    // An indexed draw's vertex_index already includes the draw's base vertex.
    let vertex = vertices[vertex_index];
    let position = vec4<f32>(vertex.position, 1.0);
    var out: VelocityVertex;
    out.draw_index = draw_index;
    out.uv = vertex_uvs(vertex);
    out.alpha = vertex_color(vertex).a;
    out.clip_position = frame.clip_from_world * (draws[draw_index].world_from_local * position);
    let previous_world = previous_world_from_local[draw_index] * previous_vertex_position(vertex_index, vertex.position);
    out.previous_clip = post.previous_clip_from_relative * vec4<f32>(previous_world.xyz - frame.world_from_view[3].xyz, 1.0);
    return out;
}

// Pixels moved: both ends of a vertex's path are interpolated linearly in clip space, divided here.
fn moved_since_previous(in: VelocityVertex) -> vec4<f32> {
    var moved = vec2<f32>(0.0);
    if in.previous_clip.w > 1e-20 {
        moved = in.clip_position.xy - clip_to_pixel(in.previous_clip);
    }
    return vec4<f32>(moved, 0.0, 0.0);
}

@fragment
fn velocity_raster(in: VelocityVertex) -> @location(0) vec4<f32> {
    return moved_since_previous(in);
}

@fragment
fn velocity_raster_masked(in: VelocityVertex) -> @location(0) vec4<f32> {
    let material = materials[draws[in.draw_index].material];
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    if material_base_color(material, g, vec4<f32>(1.0, 1.0, 1.0, in.alpha)).a < material.alpha_cutoff {
        discard;
    }
    return moved_since_previous(in);
}
