// Transparent surfaces, after the opaque surfaces are shaded, in every pipeline, drawn over the HDR
// image in the fragment stage and tested against the opaque surfaces' depth: first transmissive ones
// that do not blend (KHR_materials_transmission), front to back, writing depth, each carrying the
// light behind it (`shading/transmission.wgsl`) and covering what it is drawn over; then alpha-blended
// ones (glTF BLEND), back to front, blending by their alpha without writing depth. Each fragment is
// lit and decaled by the shading core through the frame's light and decal methods, as an opaque
// surface is — what deferred decals, which exist only in the G-buffer, cannot do — and shadowed by
// the sun through a ray of its own.
#include "shading/shade.wgsl"
#include "passes/surface_raster.wgsl"
#include "shading/sun_shadow.wgsl"

// The pipeline draws alpha-masked (transmissive) surfaces: only they may discard, since a fragment
// shader that can discard writes depth only after it has run.
override ALPHA_MASKED: bool = true;

// How much a draw scales lengths on average: the cube root of its transform's volume change.
fn draw_scale(draw: Draw) -> f32 {
    let m = draw.world_from_local;
    return pow(abs(determinant(mat3x3<f32>(m[0].xyz, m[1].xyz, m[2].xyz))), 1.0 / 3.0);
}

@fragment
fn transparent_shade(in: ForwardVertex, @builtin(front_facing) front_facing: bool) -> @location(0) vec4<f32> {
    let g = UvGradients(in.uv, dpdx(in.uv), dpdy(in.uv));
    let dp = PositionGradients(dpdx(in.relative_position), dpdy(in.relative_position));
    let draw = draws[in.draw_index];
    let material = materials[draw.material];
    var surface = fragment_shading_surface(in, front_facing, g, dp);
    if ALPHA_MASKED && surface.alpha < material.alpha_cutoff {
        discard;
    }
    // The medium's thickness is given in the mesh's units.
    surface.thickness *= draw_scale(draw);
    let s = apply_decals(surface, dp);
    // No shadow mask holds a second surface per pixel: the sun's visibility is traced here, from the
    // interpolated position, on the side the sun lights (behind a transmissive surface, its far one).
    let to_sun = -frame.sun_direction.xyz;
    let lit_side = select(s.ray_normal, -s.ray_normal, lit_from_behind(s) && dot(s.ray_normal, to_sun) < 0.0);
    let sun = sun_visibility_traced(s.position, lit_side, s.ray_clearance);
    // The pipeline blends "over": radiance α + what lies behind (1 − α).
    let alpha = select(1.0, s.alpha, (material.flags & MATERIAL_BLENDED) != 0u);
    return vec4<f32>(shade(s, sun), alpha);
}
