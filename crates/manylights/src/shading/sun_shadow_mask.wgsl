// The sun's visibility at an opaque surface's pixel, from the mask `passes/ray_shadows.rs` traced
// (and, for soft shadows, `passes/shadow_filter.rs` filtered) before shading; 1 when the sun casts
// no shadows.

// Set by the shading passes when the frame traces sun shadows; they then bind the mask as
// `sun_shadow_mask` (a texture_2d<f32>, visibility in x).
override SUN_SHADOW_MASK: bool = false;

fn sun_visibility(pixel: vec2<u32>) -> f32 {
    if SUN_SHADOW_MASK {
        return textureLoad(sun_shadow_mask, pixel, 0).x;
    }
    return 1.0;
}
