// The clustered method's froxel grid (Olsson, Billeter & Assarsson 2012): the view frustum cut into
// screen tiles of `frame.cluster_grid.w` pixels and depth slices exponential in view depth, from the
// near plane to the far side of the scene (`gpu/frame.rs` sets both). The list builder
// (`cluster_build.wgsl`) and the lookup at shading points map through these same functions, with
// every index clamped into the grid: a volume's froxel range, computed from bounds that contain it,
// then always contains the froxel of each of its points.
#include "shading/scene_bindings.wgsl"

fn cluster_froxel_count() -> u32 {
    return frame.cluster_grid.x * frame.cluster_grid.y * frame.cluster_grid.z;
}

// Distance in front of the camera along its view axis.
fn cluster_view_depth(world: vec3<f32>) -> f32 {
    return dot(world - frame.world_from_view[3].xyz, -frame.world_from_view[2].xyz);
}

// Clip-space position: x / w and y / w are the point's normalised device coordinates.
fn cluster_clip(world: vec3<f32>) -> vec4<f32> {
    return frame.clip_from_world * vec4<f32>(world, 1.0);
}

// Tile column and row of normalised device coordinates (rows top to bottom, as pixels).
fn cluster_tile(ndc: vec2<f32>) -> vec2<u32> {
    let pixel = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * frame.viewport.xy / f32(frame.cluster_grid.w);
    let last = vec2<f32>(frame.cluster_grid.xy - 1u);
    return vec2<u32>(clamp(floor(pixel), vec2<f32>(0.0), last));
}

fn cluster_slice(view_depth: f32) -> u32 {
    let near = frame.cluster_depth.x;
    let slice = floor(log2(max(view_depth, near) / near) * frame.cluster_depth.y);
    return u32(clamp(slice, 0.0, f32(frame.cluster_grid.z - 1u)));
}

fn cluster_index(tile: vec2<u32>, slice: u32) -> u32 {
    return (slice * frame.cluster_grid.y + tile.y) * frame.cluster_grid.x + tile.x;
}

// The froxel of a world-space point in front of the camera.
fn cluster_of(world: vec3<f32>) -> u32 {
    let clip = cluster_clip(world);
    return cluster_index(cluster_tile(clip.xy / clip.w), cluster_slice(cluster_view_depth(world)));
}
