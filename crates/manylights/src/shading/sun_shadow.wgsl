// The sun's visibility at a shading point where no mask was traced for it (transparent surfaces,
// reflections' hits): a ray of its own. 1 when the sun casts no shadows. Pixels of the opaque
// surfaces read the ray-traced mask instead (`shading/sun_shadow_mask.wgsl`).
#include "$RAY_TRACE"
#include "shading/brdf.wgsl"

// One ray towards the sun's centre from `position`, off the surface along its geometric normal `n`
// (on the side being lit) by `clearance` metres beyond rounding's reach (for positions known only
// that well); 0 where `n` faces away from the sun.
fn sun_visibility_traced(position: vec3<f32>, n: vec3<f32>, clearance: f32) -> f32 {
    if frame.ray_options.x == RAY_SHADOWS_OFF || frame.sun_direction.w == 0.0 {
        return 1.0;
    }
    let to_sun = -frame.sun_direction.xyz;
    if dot(n, to_sun) <= 0.0 {
        return 0.0;
    }
    return select(1.0, 0.0, ray_occluded(ray_offset_origin(position, n, clearance), to_sun, 3.0e38));
}

// The sun's visibility at a transparent surface, whose pixel no mask holds: traced from it on the
// side the sun lights (behind a transmissive surface, its far one).
fn sun_visibility_of_transparent(s: ShadingInput) -> f32 {
    let to_sun = -frame.sun_direction.xyz;
    let lit_side = select(s.ray_normal, -s.ray_normal, lit_from_behind(s) && dot(s.ray_normal, to_sun) < 0.0);
    return sun_visibility_traced(s.position, lit_side, s.ray_clearance);
}
