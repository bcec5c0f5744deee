// Transparent surfaces (glTF BLEND materials), after the opaque surfaces are shaded, in every
// pipeline: drawn back to front over the HDR image in the fragment stage, tested against the opaque
// surfaces' depth without writing it. Each fragment is lit and decaled by the shading core through
// the frame's light and decal methods, as an opaque surface is — what deferred decals, which exist
// only in the G-buffer, cannot do — and shadowed by the sun through a ray of their own.
#include "shading/shade.wgsl"
#include "passes/surface_raster.wgsl"
#include "shading/sun_shadow.wgsl"

@fragment
fn transparent_shade(in: ForwardVertex, @builtin(front_facing) front_facing: bool) -> @location(0) vec4<f32> {
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    let dp = PositionGradients(dpdx(in.relative_position), dpdy(in.relative_position));
    let s = apply_decals(fragment_shading_surface(in, front_facing, g, dp), dp);
    // No shadow mask holds a second surface per pixel: the sun's visibility is traced here, from the
    // interpolated position.
    let sun = sun_visibility_traced(s.position, s.ray_normal, s.ray_clearance);
    // The pipeline blends "over": radiance α + what lies behind (1 − α).
    return vec4<f32>(shade(s, sun), s.alpha);
}
