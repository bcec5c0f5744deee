// The camera's rays, for any projection: pixels to world-space rays whose origins are relative to the
// camera position (`frame.world_from_view[3]`), so f32 precision holds far from the world origin.
// Shared by the visibility-buffer resolve, the forward pass and the sky.
#include "shading/scene_bindings.wgsl"

struct Ray {
    origin: vec3<f32>,
    dir: vec3<f32>,
}

// The camera ray through a point in pixel coordinates (y down).
fn camera_ray(pixel: vec2<f32>) -> Ray {
    let ndc = vec2<f32>(pixel.x * frame.viewport.z * 2.0 - 1.0, 1.0 - pixel.y * frame.viewport.w * 2.0);
    // Reverse Z: depth 1 is the near plane; 0.5 is a second point on the ray even for infinite far.
    let near = frame.view_from_clip * vec4<f32>(ndc, 1.0, 1.0);
    let mid = frame.view_from_clip * vec4<f32>(ndc, 0.5, 1.0);
    let origin = near.xyz / near.w;
    let world_from_view = mat3x3<f32>(frame.world_from_view[0].xyz, frame.world_from_view[1].xyz, frame.world_from_view[2].xyz);
    return Ray(world_from_view * origin, normalize(world_from_view * (mid.xyz / mid.w - origin)));
}

// The point at `depth` (reverse Z) seen through pixel coordinates `pixel`, relative to the camera
// like the camera rays: how passes that read a depth buffer rebuild positions.
fn depth_relative_position(pixel: vec2<f32>, depth: f32) -> vec3<f32> {
    let ndc = vec2<f32>(pixel.x * frame.viewport.z * 2.0 - 1.0, 1.0 - pixel.y * frame.viewport.w * 2.0);
    let view = frame.view_from_clip * vec4<f32>(ndc, depth, 1.0);
    let world_from_view = mat3x3<f32>(frame.world_from_view[0].xyz, frame.world_from_view[1].xyz, frame.world_from_view[2].xyz);
    return world_from_view * (view.xyz / view.w);
}

// How far a pixel's position, rebuilt from the depth buffer or interpolated by the raster, may lie off
// its surface: the depth buffer's resolution along the view ray — for reverse-Z perspective
// projections d² / near times its relative precision, 2⁻²² covering rasterisers' interpolation, four
// times over; for orthographic ones a few millionths of the distance. Rays leaving the point start
// that far off the surface (`ray_offset_origin`): farther would move contact shadows.
fn surface_clearance(relative_position: vec3<f32>) -> f32 {
    let d = length(relative_position);
    let near = frame.cluster_depth.z;
    return select(4e-6 * d, 4.0 * d * d / near * 2.4e-7, frame.ray_settings.z > 0.0 && near > 0.0);
}

// The width of a pixel's cone at a point (relative to the camera): how far apart neighbouring
// pixels' rays are there. Rays leaving the surface start their cones with it.
fn pixel_footprint(relative_position: vec3<f32>) -> f32 {
    return frame.ray_settings.w + length(relative_position) * frame.ray_settings.z;
}
