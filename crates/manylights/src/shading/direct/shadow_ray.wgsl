// A shadow ray towards a local light, shared by the direct-lighting modules that trace them.
#include "shading/shading_input.wgsl"
#include "shading/camera.wgsl"
#include "$RAY_TRACE"
#include "shading/debug_view.wgsl"

// Whether something lies between the surface `s` and the light at `light` (world space).
fn light_occluded(light: vec3<f32>, s: ShadingInput) -> bool {
    if DEBUG_VIEWS {
        debug_shadow_rays += 1u;
    }
    let origin = ray_offset_origin(s.position, s.ray_normal, s.ray_clearance);
    // The segment to the light, short of it by a hair: t runs from 0 at the origin to 1 at the light.
    return ray_occluded(origin, light - origin, 0.9999);
}

// Whether something lies between the light at `light` and a surface seen at `position`, facing
// `normal`, rebuilt from a depth buffer like a pixel's (world space).
fn light_occluded_from(position: vec3<f32>, normal: vec3<f32>, light: vec3<f32>) -> bool {
    if DEBUG_VIEWS {
        debug_shadow_rays += 1u;
    }
    let origin = ray_offset_origin(position, normal, surface_clearance(position - frame.world_from_view[3].xyz));
    return ray_occluded(origin, light - origin, 0.9999);
}
