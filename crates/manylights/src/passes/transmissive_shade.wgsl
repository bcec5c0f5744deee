// Transmissive surfaces that do not blend (KHR_materials_transmission), shaded in compute after the
// opaque ones: `transmissive_raster` (the visibility-buffer raster over the transmissive draws,
// tested against and writing the opaque surfaces' depth) leaves each pixel the id of its nearest
// transmissive triangle, or none; here each such pixel rebuilds that surface as the visibility
// buffer's resolve does, lights and decals it through the shading core, carries the light behind it
// from the opaque image's mip chain (`shading/transmitted_screen.wgsl`, group 1 bindings 0 and 1)
// and covers the pixel with it. The sun's visibility is traced from the surface: no mask holds a
// second surface per pixel.
#include "shading/pixel_surface.wgsl"
#include "shading/sun_shadow.wgsl"

@group(1) @binding(2) var transmissive_ids: texture_2d<u32>;
@group(1) @binding(3) var hdr_output: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8)
fn transmissive_shade(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= vec2<u32>(frame.viewport.xy)) {
        return;
    }
    let visibility_id = textureLoad(transmissive_ids, id.xy, 0).x;
    // No transmissive surface in front of the opaque one.
    if visibility_id == NO_VISIBILITY_ID {
        return;
    }
    let s = pixel_surface(visibility_id, vec2<f32>(id.xy) + 0.5).shading;
    textureStore(hdr_output, id.xy, vec4<f32>(shade(s, sun_visibility_of_transparent(s)), 1.0));
}
