// The post chain's per-frame constants (`post::PostUniforms`, keep in sync) and what its passes share.
// Every pass binds the scene as group 0 (frame uniforms, camera rays) and these at group 1, binding 0.
#include "shading/camera.wgsl"
#include "shading/pixel_hash.wgsl"

struct PostUniforms {
    // The previous frame's clip space from the current frame's camera-relative world: where a point
    // seen now was on screen a frame ago, as far as the camera is concerned.
    previous_clip_from_relative: mat4x4<f32>,
    // x: auto exposure's key (middle grey times 2^compensation); z: how far this frame's exposure
    // moves towards the measured one (1: all the way); w: the vignette's strength (0: none, 1: the
    // cos⁴ law).
    exposure: vec4<f32>,
    // x: bloom's share of the image (0: none); y: 1 / its levels, which the upsampled sum adds up.
    bloom: vec4<f32>,
    // x: focus distance in metres (0: focus on what the image's centre shows); y: f²/N in pixels of
    // the sensor, the circle of confusion's diameter per dioptre of defocus (|1/S − 1/d|) for a
    // distant focus; z: its largest radius in pixels; w: the focal length f in metres.
    depth_of_field: vec4<f32>,
    // x: shutter time as a fraction of the frame interval; y: samples per pixel; z: the longest blur
    // in pixels.
    motion_blur: vec4<f32>,
}

// Edge of the tiles the depth of field and motion blur gather their neighbourhood's extent over.
const POST_TILE: u32 = 16u;

// The pixel coordinates (y down) of a clip-space point.
fn clip_to_pixel(clip: vec4<f32>) -> vec2<f32> {
    let ndc = clip.xy / clip.w;
    return vec2<f32>((ndc.x * 0.5 + 0.5) * frame.viewport.x, (0.5 - ndc.y * 0.5) * frame.viewport.y);
}

// `texture` at a point in its texel coordinates (texel centres at +0.5), bilinearly, clamped to its
// edges. Taps are loaded by hand: the chain's full-resolution images are 32-bit float, which not every
// GPU filters.
fn post_bilinear(texture: texture_2d<f32>, p: vec2<f32>) -> vec3<f32> {
    let size = vec2<i32>(textureDimensions(texture));
    let q = p - 0.5;
    let base_texel = vec2<i32>(floor(q));
    let f = q - floor(q);
    let t00 = textureLoad(texture, clamp(base_texel, vec2<i32>(0), size - 1), 0).rgb;
    let t10 = textureLoad(texture, clamp(base_texel + vec2<i32>(1, 0), vec2<i32>(0), size - 1), 0).rgb;
    let t01 = textureLoad(texture, clamp(base_texel + vec2<i32>(0, 1), vec2<i32>(0), size - 1), 0).rgb;
    let t11 = textureLoad(texture, clamp(base_texel + vec2<i32>(1, 1), vec2<i32>(0), size - 1), 0).rgb;
    return mix(mix(t00, t10, f.x), mix(t01, t11, f.x), f.y);
}

// Distance along the view axis from the camera to the surface a pixel of the depth buffer shows
// (reverse Z; 0 is the sky, infinitely far): a lens focuses on a plane at such a distance.
fn post_distance(depth: texture_depth_2d, pixel: vec2<u32>) -> f32 {
    let z = textureLoad(depth, pixel, 0);
    if z == 0.0 {
        return 3.0e38;
    }
    let forward = -normalize(frame.world_from_view[2].xyz);
    return dot(depth_relative_position(vec2<f32>(pixel) + 0.5, z), forward);
}
