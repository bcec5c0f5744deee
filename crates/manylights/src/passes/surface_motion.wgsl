// Where animated instances' surfaces were a frame before (`SurfaceMotion`), for the passes that reuse
// what pixels kept (`restir`'s reservoirs, the denoiser's history): each moving draw again, each vertex
// through its draw's current and previous transform (`GpuScene::previous_transforms`), a deformed one
// from its previous pose, the displacement interpolated across the triangle — exact, as both ends are affine in the triangle's
// points. The fragment whose surface the frame's depth holds writes it at its pixel, stamped with the
// frame's number; alpha-masked materials' holes are discarded as the raster did.
#include "shading/scene_bindings.wgsl"
#include "shading/material.wgsl"
#include "shading/previous_vertex.wgsl"

@group(1) @binding(0) var<storage, read> previous_world_from_local: array<mat4x4<f32>>;
@group(1) @binding(1) var depth: texture_depth_2d;

struct MotionVertex {
    @builtin(position) @invariant clip_position: vec4<f32>,
    // Where the point was a frame before, less where it is (world space).
    @location(0) moved: vec3<f32>,
    @location(1) @interpolate(flat) draw_index: u32,
    @location(2) uv: vec4<f32>,
    // The vertex colour's alpha, for alpha masks.
    @location(3) alpha: f32,
}

@vertex
fn surface_motion_vertex(@builtin(vertex_index) vertex_index: u32, @builtin(instance_index) draw_index: u32) -> MotionVertex {
    // An indexed draw's vertex_index already includes the draw's base vertex.
    let vertex = vertices[vertex_index];
    let position = vec4<f32>(vertex.position, 1.0);
    let world = draws[draw_index].world_from_local * position;
    var out: MotionVertex;
    out.clip_position = frame.clip_from_world * world;
    out.moved = (previous_world_from_local[draw_index] * previous_vertex_position(vertex_index, vertex.position)).xyz - world.xyz;
    out.draw_index = draw_index;
    out.uv = vertex_uvs(vertex);
    out.alpha = vertex_color(vertex).a;
    return out;
}

// Writes the fragment's motion where its surface is the pixel's. The pipeline's depth test rejects
// hidden fragments only once they have run (a shader that writes memory is tested late), so the
// fragment compares its depth with the frame's itself, within `reach`: its depth's change to the
// next pixel and the rounding of another raster's depth.
fn keep_motion(in: MotionVertex, reach: f32) {
    let pixel = vec2<u32>(in.clip_position.xy);
    if in.clip_position.z + reach < textureLoad(depth, pixel, 0) {
        return;
    }
    surface_motions[pixel.y * u32(frame.viewport.x) + pixel.x] = SurfaceMotion(in.moved, frame.direct_lighting.x);
}

fn depth_reach(in: MotionVertex) -> f32 {
    return fwidth(in.clip_position.z) + 1e-5 * in.clip_position.z;
}

@fragment
fn surface_motion(in: MotionVertex) {
    keep_motion(in, depth_reach(in));
}

@fragment
fn surface_motion_masked(in: MotionVertex) {
    let reach = depth_reach(in);
    let material = materials[draws[in.draw_index].material];
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    if material_base_color(material, g, vec4<f32>(1.0, 1.0, 1.0, in.alpha)).a < material.alpha_cutoff {
        discard;
    }
    keep_motion(in, reach);
}
