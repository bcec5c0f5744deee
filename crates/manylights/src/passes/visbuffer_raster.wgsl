// Visibility-buffer raster: depth plus one u32 visibility id per pixel (the draw's
// `first_visibility_id` + the triangle's number within the draw). Alpha-masked materials discard here;
// nothing else is shaded. Raster is bound by fragment output on GPUs with few graphics units, so this
// pass writes 4 bytes a pixel, not 8, and over the opaque draws never clears the ids: shading tells
// the background by its depth (benchmarks/LOG.md, topic 5). Over the transmissive draws
// (`transmissive_shade`), whose depth starts at the opaque surfaces', ids are cleared to a value no
// triangle has. Over the blended draws (`blended_shade`) a fragment writes no target: it links its
// id into its pixel's list of layers (`blended_layers.wgsl`).
//
// Shared by two entry files that differ in how a fragment learns its triangle:
// `visbuffer_raster_indexed.wgsl` draws indexed (the vertex cache reuses shared vertices) and reads
// the `primitive_index` builtin; `visbuffer_raster_pulled.wgsl`, for devices without that feature,
// pulls each corner through the index buffer by vertex_index, so the triangle is vertex_index / 3.
#include "shading/scene_bindings.wgsl"
#include "shading/material.wgsl"
#include "passes/blended_layers.wgsl"

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    // The visibility id of the draw's first triangle (indexed) or of this triangle (pulled).
    @location(0) @interpolate(flat) visibility_id: u32,
    @location(1) @interpolate(flat) draw_index: u32,
    @location(2) uv: vec4<f32>,
    // The vertex colour's alpha, for alpha masks.
    @location(3) alpha: f32,
}

fn raster_vertex(draw_index: u32, vertex: Vertex, visibility_id: u32) -> VertexOutput {
    var out: VertexOutput;
    out.clip_position = frame.clip_from_world * (draws[draw_index].world_from_local * vec4<f32>(vertex.position, 1.0));
    out.visibility_id = visibility_id;
    out.draw_index = draw_index;
    out.uv = vertex_uvs(vertex);
    out.alpha = vertex_color(vertex).a;
    return out;
}

// Whether an alpha-masked fragment covers its pixel.
fn raster_alpha_covers(in: VertexOutput) -> bool {
    let material = materials[draws[in.draw_index].material];
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    return material_base_color(material, g, vec4<f32>(1.0, 1.0, 1.0, in.alpha)).a >= material.alpha_cutoff;
}

// Bindings of the blended draws' raster (`blended_shade.rs`).
@group(1) @binding(0) var shaded_depth: texture_depth_2d;
@group(1) @binding(1) var<storage, read_write> layer_heads: array<atomic<u32>>;
@group(1) @binding(2) var<storage, read_write> layers: array<BlendedLayer>;
@group(1) @binding(3) var<storage, read_write> layer_status: BlendedLayerStatus;

// Links a blended fragment into its pixel's layers if it lies in front of the shaded surfaces and
// is not wholly transparent (it would blend to nothing, and take one of the 16 layers a pixel
// keeps). The depth test is the shader's own: a fragment's stores happen even where a late depth
// test rejects it. A fragment past the layers' capacity is dropped, and the count it needed
// recorded: the renderer grows the layers and renders the frame again.
fn append_blended_layer(in: VertexOutput, visibility_id: u32) {
    // Before any branch: the texture's derivatives need the whole quad.
    let material = materials[draws[in.draw_index].material];
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    let alpha = material_base_color(material, g, vec4<f32>(1.0, 1.0, 1.0, in.alpha)).a;
    let pixel = vec2<u32>(in.clip_position.xy);
    if alpha <= 0.0 || in.clip_position.z <= textureLoad(shaded_depth, pixel, 0) {
        return;
    }
    let layer = atomicAdd(&layer_status.count, 1u);
    if layer >= arrayLength(&layers) {
        atomicMax(&layer_status.needed, layer + 1u);
        return;
    }
    let next = atomicExchange(&layer_heads[layer_head_index(pixel)], layer + 1u);
    layers[layer] = BlendedLayer(visibility_id, in.clip_position.z, next);
}
