// A G-buffer pixel's position and its change to the neighbouring pixels, for the passes that read the
// G-buffer in compute (`deferred_shade`) and in fragments (`deferred_decals`): both give decals the
// same texture gradients.
#include "shading/camera.wgsl"
#include "shading/decals.wgsl"

// Where a ray meets the plane through `point` with normal `n` (all camera-relative).
fn ray_plane_point(ray: Ray, point: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let facing = dot(ray.dir, n);
    let t = dot(point - ray.origin, n) / select(facing, 1e-20, abs(facing) < 1e-20);
    return ray.origin + ray.dir * t;
}

// The G-buffer keeps no triangle: the position's change to the next pixel in x and y is where those
// pixels' rays meet the surface's tangent plane.
fn gbuffer_position_gradients(pixel: vec2<f32>, relative_position: vec3<f32>, n: vec3<f32>) -> PositionGradients {
    return PositionGradients(
        ray_plane_point(camera_ray(pixel + vec2<f32>(1.0, 0.0)), relative_position, n) - relative_position,
        ray_plane_point(camera_ray(pixel + vec2<f32>(0.0, 1.0)), relative_position, n) - relative_position,
    );
}
