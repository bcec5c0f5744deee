// The visibility-buffer raster for devices without `primitive_index` (see `visbuffer_raster.wgsl`):
// non-indexed draws of 3 × triangles vertices, each corner pulled through the index buffer.
#include "passes/visbuffer_raster.wgsl"

@vertex
fn visbuffer_vertex(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) draw_index: u32) -> VertexOutput {
    let draw = draws[draw_index];
    let vertex = vertices[draw.base_vertex + indices[draw.first_index + vertex_index]];
    return raster_vertex(draw_index, vertex, draw.first_visibility_id + vertex_index / 3u);
}

@fragment
fn visbuffer_opaque(in: VertexOutput) -> @location(0) u32 {
    return in.visibility_id;
}

@fragment
fn visbuffer_masked(in: VertexOutput) -> @location(0) u32 {
    if !raster_alpha_covers(in) {
        discard;
    }
    return in.visibility_id;
}

@fragment
fn visbuffer_blended(in: VertexOutput) {
    append_blended_layer(in, in.visibility_id);
}
