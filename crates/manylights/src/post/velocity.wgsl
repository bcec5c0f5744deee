// Per-pixel velocity for motion blur: how far, in pixels, the surface a pixel shows moved on screen
// since the previous frame (now − then). `velocity` covers every pixel as if only the camera moved:
// the point rebuilt from depth (the sky: its direction) taken through the previous camera. Then
// `velocity_raster` draws the moving instances again over it, each vertex through its current and
// its previous transform, where their surface is the one depth holds.
#include "shading/scene_bindings.wgsl"
#include "shading/camera.wgsl"
#include "post/post_types.wgsl"

@group(1) @binding(0) var<uniform> post: PostUniforms;
@group(1) @binding(1) var depth: texture_depth_2d;
@group(1) @binding(2) var velocity_output: texture_storage_2d<rg32float, write>;

@compute @workgroup_size(8, 8)
fn velocity(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= vec2<u32>(frame.viewport.xy)) {
        return;
    }
    let pixel = vec2<f32>(id.xy) + 0.5;
    let z = textureLoad(depth, id.xy, 0);
    // The sky is a direction: only the camera's turn moves it.
    var point = vec4<f32>(camera_ray(pixel).dir, 0.0);
    if z != 0.0 {
        point = vec4<f32>(depth_relative_position(pixel, z), 1.0);
    }
    let previous = post.previous_clip_from_relative * point;
    // Behind the previous camera (or a direction an orthographic camera cannot place): no trail.
    var moved = vec2<f32>(0.0);
    if previous.w > 1e-20 {
        moved = pixel - clip_to_pixel(previous);
    }
    textureStore(velocity_output, id.xy, vec4<f32>(moved, 0.0, 0.0));
}
