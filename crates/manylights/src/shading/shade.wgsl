// The shading core: one function, used by every pipeline, that lights a `ShadingInput`.
// The light, decal and particle modules (`shading/enumerate/*.wgsl`) are chosen when the shader is
// composed: they define `shade_local_lights`, `shade_particle_lights` and `apply_decals` (which
// pipelines call on the surface before `shade`).
#include "shading/scene_bindings.wgsl"
#include "shading/shading_input.wgsl"
#include "shading/brdf.wgsl"
#include "shading/lights.wgsl"
#include "$LIGHT_ENUMERATION"
#include "$DECAL_ENUMERATION"
#include "$PARTICLE_LIGHTING"
#include "shading/debug_view.wgsl"

// The most radiance a point sends: far above any light a scene means, and far enough below the
// largest float that the sums and blends after shading stay finite (a glTF emissive strength may be
// as large as any float).
const MAX_RADIANCE: f32 = 1e30;

// Outgoing radiance towards the viewer; `sun_visibility` is the fraction of the sun the point sees
// (`shading/sun_shadow*.wgsl`).
fn shade(s: ShadingInput, sun_visibility: f32) -> vec3<f32> {
    // Ambient stands in for indirect light: diffuse only, with the metal's tint kept as a crude
    // specular term so metals do not turn black.
    let ambient_albedo = mix(s.base_color, s.base_color * 0.5, s.metallic);
    var radiance = s.emissive + frame.ambient.rgb * ambient_albedo;
    if frame.sun_direction.w > 0.0 && sun_visibility > 0.0 {
        radiance += frame.sun_radiance.rgb * sun_visibility * brdf_times_cosine(s, -frame.sun_direction.xyz);
    }
    radiance += shade_local_lights(s);
    let particles = shade_particle_lights(s);
    radiance = min(radiance + particles, vec3<f32>(MAX_RADIANCE));
    if !DEBUG_VIEWS {
        return radiance;
    }
    switch frame.debug_view.x {
        case DEBUG_VIEW_LIGHTS_REACHING: {
            return heat_map(debug_lights_reaching, frame.debug_view.y);
        }
        case DEBUG_VIEW_LIGHT_WORK: {
            return heat_map(debug_light_work, frame.debug_view.y);
        }
        case DEBUG_VIEW_DECALS_COVERING: {
            return heat_map(debug_decals_covering, frame.debug_view.y);
        }
        case DEBUG_VIEW_PARTICLE_LIGHT: {
            return particles;
        }
        case DEBUG_VIEW_PARTICLE_GRID_SLICE: {
            let eye = frame.world_from_view[3].xyz;
            let to_surface = s.position - eye;
            let t = (bitcast<f32>(frame.debug_view.z) - eye.y) / to_surface.y;
            if to_surface.y != 0.0 && t > 0.0 && t < 1.0 {
                return particle_grid_at(eye + to_surface * t);
            }
            return radiance * 0.1;
        }
        default: {
            return radiance;
        }
    }
}

// Radiance seen where no geometry was drawn: a simple sky from the ambient colour.
fn sky_radiance(view_ray_dir: vec3<f32>) -> vec3<f32> {
    let up = saturate(view_ray_dir.y * 0.5 + 0.5);
    return frame.ambient.rgb * mix(0.6, 1.6, up);
}
