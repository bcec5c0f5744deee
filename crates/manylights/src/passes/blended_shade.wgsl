// Alpha-blended surfaces (glTF BLEND), shaded in compute after the opaque and transmissive surfaces
// in every pipeline. The raster over the blended draws left each pixel a list of the layers in front
// of what is shaded (`blended_layers.wgsl`); here each pixel keeps its nearest MAX_BLENDED_LAYERS,
// orders them far to near, rebuilds and shades each as the visibility buffer's resolve does, and
// blends it "over" what lies behind (the shaded image's copy, `behind`). Each layer is lit and
// decaled by the shading core through the frame's methods — what deferred decals, which exist only
// in the G-buffer, cannot do — carries the light behind it where it is transmissive too
// (`shading/transmitted_screen.wgsl`, group 1 bindings 0 and 1), and is shadowed by the sun through
// a ray of its own. Sorting per pixel, not per draw, blends intersecting surfaces right.
#include "shading/pixel_surface.wgsl"
#include "shading/sun_shadow.wgsl"
#include "passes/blended_layers.wgsl"

@group(1) @binding(2) var<storage, read> layer_heads: array<u32>;
@group(1) @binding(3) var<storage, read> layers: array<BlendedLayer>;
@group(1) @binding(4) var behind: texture_2d<f32>;
@group(1) @binding(5) var hdr_output: texture_storage_2d<rgba32float, write>;

// Layers behind the nearest sixteen are dropped: they show through at most the product of sixteen
// layers' (1 − α).
const MAX_BLENDED_LAYERS: u32 = 16u;

// Whether layer a lies behind layer b; equal depths are ordered by id, so the order does not depend
// on which fragment was linked first.
fn behind_layer(a_depth: f32, a_id: u32, b_depth: f32, b_id: u32) -> bool {
    return a_depth < b_depth || (a_depth == b_depth && a_id < b_id);
}

@compute @workgroup_size(8, 8)
fn blended_shade(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= vec2<u32>(frame.viewport.xy)) {
        return;
    }
    var link = layer_heads[layer_head_index(id.xy)];
    if link == END_OF_LAYERS {
        return;
    }
    // The nearest layers, far to near, by insertion.
    var ids: array<u32, MAX_BLENDED_LAYERS>;
    var depths: array<f32, MAX_BLENDED_LAYERS>;
    var count = 0u;
    while link != END_OF_LAYERS {
        let layer = layers[link - 1u];
        link = layer.next;
        var i = count;
        if count < MAX_BLENDED_LAYERS {
            count += 1u;
            while i > 0u && behind_layer(layer.depth, layer.visibility_id, depths[i - 1u], ids[i - 1u]) {
                depths[i] = depths[i - 1u];
                ids[i] = ids[i - 1u];
                i -= 1u;
            }
        } else {
            // Full: the farthest of the kept and the new layer is dropped.
            if behind_layer(layer.depth, layer.visibility_id, depths[0], ids[0]) {
                continue;
            }
            i = 0u;
            while i + 1u < MAX_BLENDED_LAYERS && behind_layer(depths[i + 1u], ids[i + 1u], layer.depth, layer.visibility_id) {
                depths[i] = depths[i + 1u];
                ids[i] = ids[i + 1u];
                i += 1u;
            }
        }
        depths[i] = layer.depth;
        ids[i] = layer.visibility_id;
    }
    let pixel = vec2<f32>(id.xy) + 0.5;
    var radiance = textureLoad(behind, id.xy, 0).rgb;
    for (var i = 0u; i < count; i += 1u) {
        let s = pixel_surface(ids[i], pixel).shading;
        // "Over": the layer's radiance α plus what lies behind it (1 − α).
        radiance = mix(radiance, shade(s, sun_visibility_of_transparent(s)), s.alpha);
    }
    textureStore(hdr_output, id.xy, vec4<f32>(radiance, 1.0));
}
