// The image transmissive surfaces see through (`shading/transmitted_screen.wgsl`): after the opaque
// surfaces are shaded, their HDR image is copied into level 0 of a mip chain, and each further level
// is the mean of the 2×2 texels above it, so a rough surface reads a blurred view from a coarser
// level. Inputs: the HDR image (level 0) or the level above. Output: one level. Dispatch: one thread
// a texel of the level written, in 8×8 tiles, one dispatch a level, all in one pass.

@group(0) @binding(0) var source: texture_2d<f32>;
@group(0) @binding(1) var level: texture_storage_2d<rgba16float, write>;

// The largest half float: brighter radiance is clamped to it rather than stored as infinity.
const HALF_MAX: f32 = 65504.0;

@compute @workgroup_size(8, 8)
fn transmission_background_copy(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= textureDimensions(level)) {
        return;
    }
    textureStore(level, id.xy, vec4<f32>(min(textureLoad(source, id.xy, 0).rgb, vec3<f32>(HALF_MAX)), 1.0));
}

// The last row or column of an odd-sized level above is left out of the next level; a level one
// texel wide or tall reads its edge twice.
@compute @workgroup_size(8, 8)
fn transmission_background_downsample(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= textureDimensions(level)) {
        return;
    }
    let corner = id.xy * 2u;
    let last = textureDimensions(source) - 1u;
    let far = min(corner + 1u, last);
    let sum = textureLoad(source, corner, 0) + textureLoad(source, vec2<u32>(far.x, corner.y), 0)
        + textureLoad(source, vec2<u32>(corner.x, far.y), 0) + textureLoad(source, far, 0);
    textureStore(level, id.xy, sum * 0.25);
}
