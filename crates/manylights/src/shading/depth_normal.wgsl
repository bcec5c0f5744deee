// A surface's geometric normal rebuilt from a depth buffer, for passes that have no triangle at hand
// (the shadow rays, the G-buffer's reflections): the cross product of the position's change towards
// a neighbour in x and one in y, each taken on the side whose depth is closer to the pixel's, so an
// edge to another surface (or the sky) does not bend it (Turánszki's "accurate normal
// reconstruction"). Faces the camera.
#include "shading/camera.wgsl"

// The camera-relative position at an integer pixel of `depth`, and its depth in w: 0 for the sky and
// for pixels outside the image, which hold no surface.
fn depth_sample(depth: texture_depth_2d, pixel: vec2<i32>) -> vec4<f32> {
    let size = vec2<i32>(textureDimensions(depth));
    if any(pixel < vec2<i32>(0)) || any(pixel >= size) {
        return vec4<f32>(0.0);
    }
    let z = textureLoad(depth, pixel, 0);
    return vec4<f32>(depth_relative_position(vec2<f32>(pixel) + 0.5, max(z, 1e-30)), z);
}

// The change from `center` (depth `z`) to whichever of two opposite neighbours holds a surface and
// lies closer in depth, pointing along +axis; zero when neither holds one.
fn depth_closer_step(depth: texture_depth_2d, pixel: vec2<i32>, axis: vec2<i32>, center: vec3<f32>, z: f32) -> vec3<f32> {
    let ahead = depth_sample(depth, pixel + axis);
    let behind = depth_sample(depth, pixel - axis);
    let use_ahead = ahead.w > 0.0 && (behind.w == 0.0 || abs(ahead.w - z) <= abs(behind.w - z));
    if use_ahead {
        return ahead.xyz - center;
    }
    if behind.w > 0.0 {
        return center - behind.xyz;
    }
    return vec3<f32>(0.0);
}

// The unit geometric normal at `pixel`, whose camera-relative position is `center` at depth `z` (> 0).
fn depth_geometric_normal(depth: texture_depth_2d, pixel: vec2<u32>, center: vec3<f32>, z: f32) -> vec3<f32> {
    let p = vec2<i32>(pixel);
    let dx = depth_closer_step(depth, p, vec2<i32>(1, 0), center, z);
    let dy = depth_closer_step(depth, p, vec2<i32>(0, 1), center, z);
    let n = cross(dx, dy);
    let length_sq = dot(n, n);
    // A pixel without a surface beside it on some axis (a one-pixel sliver): face the camera.
    let facing = select(-center, n, length_sq > 1e-30);
    return normalize(select(facing, -facing, dot(facing, center) > 0.0));
}
