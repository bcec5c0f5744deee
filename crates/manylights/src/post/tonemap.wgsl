// The chain's last pass: exposure (fixed, or measured by `exposure.wgsl`), bloom blended over the
// image, vignetting, tonemapping (ACES fit or AgX) and sRGB encoding into the 8-bit image.
#include "shading/scene_bindings.wgsl"
#include "post/post_types.wgsl"

@group(1) @binding(0) var<uniform> post: PostUniforms;
@group(1) @binding(1) var color_input: texture_2d<f32>;
// The top bloom level (half resolution), or any texture when `BLOOM` is off.
@group(1) @binding(2) var bloom: texture_2d<f32>;
// x: log2 of the measured exposure, used when `AUTO_EXPOSURE` is set.
@group(1) @binding(3) var<storage, read> exposure_state: vec4<f32>;
@group(1) @binding(4) var ldr_output: texture_storage_2d<rgba8unorm, write>;

override BLOOM: bool = false;
override AUTO_EXPOSURE: bool = false;

// Stephen Hill's fit of the ACES RRT + ODT (sRGB primaries in and out).
fn tonemap_aces(color: vec3<f32>) -> vec3<f32> {
    let aces_input = mat3x3<f32>(
        vec3<f32>(0.59719, 0.07600, 0.02840),
        vec3<f32>(0.35458, 0.90834, 0.13383),
        vec3<f32>(0.04823, 0.01566, 0.83777),
    );
    let aces_output = mat3x3<f32>(
        vec3<f32>(1.60475, -0.10208, -0.00327),
        vec3<f32>(-0.53108, 1.10813, -0.07276),
        vec3<f32>(-0.07367, -0.00605, 1.07602),
    );
    let v = aces_input * color;
    let a = v * (v + 0.0245786) - 0.000090537;
    let b = v * (0.983729 * v + 0.4329510) + 0.238081;
    return saturate(aces_output * (a / b));
}

// AgX (Troy Sobotka), base look, with Benjamin Wrensch's polynomial fit of the sigmoid.
fn agx_contrast(x: vec3<f32>) -> vec3<f32> {
    let x2 = x * x;
    let x4 = x2 * x2;
    return 15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x - 0.00232;
}

fn tonemap_agx(color: vec3<f32>) -> vec3<f32> {
    let agx_inset = mat3x3<f32>(
        vec3<f32>(0.842479062253094, 0.0423282422610123, 0.0423756549057051),
        vec3<f32>(0.0784335999999992, 0.878468636469772, 0.0784336),
        vec3<f32>(0.0792237451477643, 0.0791661274605434, 0.879142973793104),
    );
    let agx_outset = mat3x3<f32>(
        vec3<f32>(1.19687900512017, -0.0528968517574562, -0.0529716355144438),
        vec3<f32>(-0.0980208811401368, 1.15190312990417, -0.0980434501171241),
        vec3<f32>(-0.0990297440797205, -0.0989611768448433, 1.15107367264116),
    );
    let min_ev = -12.47393;
    let max_ev = 4.026069;
    var v = agx_inset * max(color, vec3<f32>(1e-10));
    v = saturate((log2(v) - min_ev) / (max_ev - min_ev));
    v = agx_contrast(v);
    v = agx_outset * v;
    // The curve's output is display-encoded with a 2.2 power; return linear for the sRGB encoder.
    return pow(max(v, vec3<f32>(0.0)), vec3<f32>(2.2));
}

fn linear_to_srgb(c: vec3<f32>) -> vec3<f32> {
    let low = c * 12.92;
    let high = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(high, low, c <= vec3<f32>(0.0031308));
}

// `bloom` (half resolution) at a full-resolution pixel.
fn bloom_at(pixel: vec2<f32>) -> vec3<f32> {
    return post_bilinear(bloom, pixel * vec2<f32>(textureDimensions(bloom)) * frame.viewport.zw);
}

// Natural vignetting: a lens passes cos⁴ θ of the light arriving θ off its axis; `strength` blends
// from none (0) to all of it (1). Orthographic cameras (parallel rays) have none.
fn vignette(pixel: vec2<f32>, strength: f32) -> f32 {
    let forward = -normalize(frame.world_from_view[2].xyz);
    let cos_theta = saturate(dot(camera_ray(pixel).dir, forward));
    let cos2 = cos_theta * cos_theta;
    return mix(1.0, cos2 * cos2, strength);
}

@compute @workgroup_size(8, 8)
fn tonemap(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= vec2<u32>(frame.viewport.xy)) {
        return;
    }
    let pixel = vec2<f32>(id.xy) + 0.5;
    var hdr = textureLoad(color_input, id.xy, 0).rgb;
    // A heat-map debug view (`shading/debug_view.wgsl`) is shown as it is: no exposure or curve.
    if frame.debug_view.x != 0u && frame.debug_view.y != 0u {
        textureStore(ldr_output, id.xy, vec4<f32>(linear_to_srgb(saturate(hdr)), 1.0));
        return;
    }
    if BLOOM {
        hdr = mix(hdr, bloom_at(pixel) * post.bloom.y, post.bloom.x);
    }
    var exposure = frame.exposure;
    if AUTO_EXPOSURE {
        exposure = exp2(exposure_state.x);
    }
    hdr *= exposure;
    if post.exposure.w > 0.0 {
        hdr *= vignette(pixel, post.exposure.w);
    }
    // Every curve is white long before this, and the ACES fit squares its input: clamped, any
    // finite radiance and exposure map to a finite colour.
    hdr = min(hdr, vec3<f32>(65504.0));
    var mapped: vec3<f32>;
    switch frame.tonemapper {
        case TONEMAP_AGX: {
            mapped = tonemap_agx(hdr);
        }
        case TONEMAP_NONE: {
            mapped = saturate(hdr);
        }
        default: {
            mapped = tonemap_aces(hdr);
        }
    }
    textureStore(ldr_output, id.xy, vec4<f32>(linear_to_srgb(saturate(mapped)), 1.0));
}
