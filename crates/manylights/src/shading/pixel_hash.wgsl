// A per-pixel value in [0, 1), to turn each pixel's sample pattern differently (a pixel's rays over
// the sun's disc, a gather's spiral or offsets): filters and eyes average noise better than banding.
fn pixel_hash(pixel: vec2<u32>) -> f32 {
    var h = pixel.x * 0x8da6b343u ^ pixel.y * 0xd8163841u;
    h = (h ^ (h >> 16u)) * 0x7feb352du;
    h = (h ^ (h >> 15u)) * 0x846ca68bu;
    return f32((h ^ (h >> 16u)) >> 8u) / 16777216.0;
}
