// Alpha-blended surfaces (glTF BLEND), after the opaque and the transmissive surfaces are shaded, in
// every pipeline: drawn back to front over the HDR image in the fragment stage, tested against the
// depth of what is shaded and not writing it, blending by their alpha. Each fragment is lit and
// decaled by the shading core through the frame's light and decal methods, as an opaque surface is
// — what deferred decals, which exist only in the G-buffer, cannot do — carries the light behind it
// where it is transmissive too (`shading/transmission.wgsl`), and is shadowed by the sun through a
// ray of its own.
#include "shading/shade.wgsl"
#include "passes/surface_raster.wgsl"
#include "shading/sun_shadow.wgsl"
#include "shading/draws.wgsl"

@fragment
fn transparent_shade(in: ForwardVertex, @builtin(front_facing) front_facing: bool) -> @location(0) vec4<f32> {
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    let dp = PositionGradients(dpdx(in.relative_position), dpdy(in.relative_position));
    let draw = draws[in.draw_index];
    var surface = fragment_shading_surface(in, front_facing, g, dp);
    // The medium's thickness is given in the mesh's units.
    surface.thickness *= draw_scale(draw);
    let s = apply_decals(surface, dp);
    // The pipeline blends "over": radiance α + what lies behind (1 − α).
    return vec4<f32>(shade(s, sun_visibility_of_transparent(s)), s.alpha);
}
