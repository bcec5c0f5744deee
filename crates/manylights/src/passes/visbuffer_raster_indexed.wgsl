// The visibility-buffer raster for devices with `primitive_index` (see `visbuffer_raster.wgsl`):
// indexed draws, so vertices shared by several triangles are transformed once.
enable primitive_index;
#include "passes/visbuffer_raster.wgsl"

@vertex
fn visbuffer_vertex(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) draw_index: u32) -> VertexOutput {
    // An indexed draw's vertex_index already includes the draw's base vertex.
    return raster_vertex(draw_index, vertices[vertex_index], draws[draw_index].first_visibility_id);
}

@fragment
fn visbuffer_opaque(in: VertexOutput, @builtin(primitive_index) triangle: u32) -> @location(0) u32 {
    return in.visibility_id + triangle;
}

@fragment
fn visbuffer_masked(in: VertexOutput, @builtin(primitive_index) triangle: u32) -> @location(0) u32 {
    if !raster_alpha_covers(in) {
        discard;
    }
    return in.visibility_id + triangle;
}

@fragment
fn visbuffer_blended(in: VertexOutput, @builtin(primitive_index) triangle: u32) {
    append_blended_layer(in, in.visibility_id + triangle);
}
