// Bloom: the image blurred over a chain of half-resolution levels (Jimenez, "Next Generation Post
// Processing in Call of Duty: Advanced Warfare", SIGGRAPH 2014). `bloom_downsample` filters each
// level from the one above with 13 bilinear taps (the first level from the full image, with Karis's
// luminance-weighted average against fireflies); `bloom_upsample` climbs back, each level its own
// downsampled image plus a 3×3 tent of the level below. `tonemap` blends the top level over the image
// by `post.bloom.x`, divided by the levels the climb added up. Bilinear taps are done by hand
// (`post_bilinear`).
#include "shading/scene_bindings.wgsl"
#include "post/post_types.wgsl"

@group(1) @binding(0) var<uniform> post: PostUniforms;
// The level filtered: the one above (downsampling) or below (upsampling).
@group(1) @binding(1) var source: texture_2d<f32>;
// Upsampling: this level's downsampled image, which the climb adds to.
@group(1) @binding(2) var base: texture_2d<f32>;
@group(1) @binding(3) var output: texture_storage_2d<rgba16float, write>;

// The levels are 16-bit floats and filled before exposure: radiance above their largest finite value
// (a sharp sun highlight) would store infinity, and infinity times a zero filter weight is NaN.
fn half_float_range(c: vec3<f32>) -> vec3<f32> {
    return clamp(c, vec3<f32>(0.0), vec3<f32>(65504.0));
}

fn karis_weight(c: vec3<f32>) -> f32 {
    return 1.0 / (1.0 + dot(c, vec3<f32>(0.2126, 0.7152, 0.0722)));
}

// Set for the first level, filtered from the full image: Karis's average.
override FIRST_LEVEL: bool = false;

@compute @workgroup_size(8, 8)
fn bloom_downsample(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(output);
    if any(id.xy >= size) {
        return;
    }
    // This texel's centre in the source, which is (about) twice as large.
    let scale = vec2<f32>(textureDimensions(source)) / vec2<f32>(size);
    let c = (vec2<f32>(id.xy) + 0.5) * scale;
    let s = scale * 0.5;
    let a = post_bilinear(source, c + vec2<f32>(-2.0, -2.0) * s);
    let b = post_bilinear(source, c + vec2<f32>(0.0, -2.0) * s);
    let cc = post_bilinear(source, c + vec2<f32>(2.0, -2.0) * s);
    let d = post_bilinear(source, c + vec2<f32>(-1.0, -1.0) * s);
    let e = post_bilinear(source, c + vec2<f32>(1.0, -1.0) * s);
    let f = post_bilinear(source, c + vec2<f32>(-2.0, 0.0) * s);
    let g = post_bilinear(source, c);
    let h = post_bilinear(source, c + vec2<f32>(2.0, 0.0) * s);
    let i = post_bilinear(source, c + vec2<f32>(-1.0, 1.0) * s);
    let j = post_bilinear(source, c + vec2<f32>(1.0, 1.0) * s);
    let k = post_bilinear(source, c + vec2<f32>(-2.0, 2.0) * s);
    let l = post_bilinear(source, c + vec2<f32>(0.0, 2.0) * s);
    let m = post_bilinear(source, c + vec2<f32>(2.0, 2.0) * s);
    // Five overlapping boxes: the centre one weighs half, the four corner ones an eighth each.
    let boxes = array<vec3<f32>, 5>(
        (d + e + i + j) * 0.25,
        (a + b + g + f) * 0.25,
        (b + cc + h + g) * 0.25,
        (f + g + l + k) * 0.25,
        (g + h + m + l) * 0.25,
    );
    let weights = array<f32, 5>(0.5, 0.125, 0.125, 0.125, 0.125);
    var sum = vec3<f32>(0.0);
    var weight_sum = 0.0;
    for (var n = 0u; n < 5u; n += 1u) {
        let w = weights[n] * select(1.0, karis_weight(boxes[n]), FIRST_LEVEL);
        sum += boxes[n] * w;
        weight_sum += w;
    }
    textureStore(output, id.xy, vec4<f32>(half_float_range(sum / weight_sum), 1.0));
}

@compute @workgroup_size(8, 8)
fn bloom_upsample(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(output);
    if any(id.xy >= size) {
        return;
    }
    let scale = vec2<f32>(textureDimensions(source)) / vec2<f32>(size);
    let c = (vec2<f32>(id.xy) + 0.5) * scale;
    var tent = vec3<f32>(0.0);
    for (var dy = -1; dy <= 1; dy += 1) {
        for (var dx = -1; dx <= 1; dx += 1) {
            let w = f32((2 - abs(dx)) * (2 - abs(dy))) / 16.0;
            tent += post_bilinear(source, c + vec2<f32>(f32(dx), f32(dy)) * scale) * w;
        }
    }
    textureStore(output, id.xy, vec4<f32>(half_float_range(textureLoad(base, id.xy, 0).rgb + tent), 1.0));
}
