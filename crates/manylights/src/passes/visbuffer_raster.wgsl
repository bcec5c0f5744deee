// Visibility-buffer raster: depth plus one u32 visibility id per pixel (`Draw.first_visibility_id` +
// triangle; 0 marks the background). Vertices are pulled from the scene buffers, so the triangle index
// is simply vertex_index / 3 and no primitive-index feature is needed. Alpha-masked materials discard
// here; nothing else is shaded. On our benchmark GPUs this pass is bound by fragment output, so it
// writes 4 bytes a pixel, not 8.
#include "shading/scene_bindings.wgsl"
#include "shading/material.wgsl"

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) @interpolate(flat) visibility_id: u32,
    @location(1) @interpolate(flat) draw_index: u32,
    @location(2) uv: vec2<f32>,
}

@vertex
fn visbuffer_vertex(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) draw_index: u32) -> VertexOutput {
    let draw = draws[draw_index];
    let index = indices[draw.first_index + vertex_index];
    let vertex = vertices[draw.base_vertex + index];
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * (draw.world_from_local * vec4<f32>(vertex.position, 1.0));
    out.visibility_id = draw.first_visibility_id + vertex_index / 3u;
    out.draw_index = draw_index;
    out.uv = vec2<f32>(vertex.u, vertex.v);
    return out;
}

@fragment
fn visbuffer_opaque(in: VertexOutput) -> @location(0) u32 {
    return in.visibility_id;
}

@fragment
fn visbuffer_masked(in: VertexOutput) -> @location(0) u32 {
    let material = materials[draws[in.draw_index].material];
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    if material_base_color(material, g).a < material.alpha_cutoff {
        discard;
    }
    return in.visibility_id;
}
