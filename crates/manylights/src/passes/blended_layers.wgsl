// The alpha-blended surfaces' layers (glTF BLEND): the raster over the blended draws
// (`visbuffer_blended`) links each fragment in front of the shaded surfaces into its pixel's list;
// `blended_shade` sorts each list and shades its layers in compute. Heads and links hold a layer's
// index + 1, 0 ending the list: the heads are cleared to 0 each frame.
struct BlendedLayer {
    visibility_id: u32,
    // Reverse Z: nearer is greater.
    depth: f32,
    next: u32,
}

// The raster's counts: layers linked this frame, and the most any frame needed since the renderer
// last read it.
struct BlendedLayerStatus {
    count: atomic<u32>,
    needed: atomic<u32>,
}

const END_OF_LAYERS: u32 = 0u;

// The pixel's head in the heads array: rows of the viewport's width.
fn layer_head_index(pixel: vec2<u32>) -> u32 {
    return pixel.y * u32(frame.viewport.x) + pixel.x;
}
