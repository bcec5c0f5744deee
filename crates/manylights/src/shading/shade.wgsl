// The shading core: one function, used by every pipeline, that lights a `ShadingInput`.
// The light, decal and particle modules (`shading/enumerate/*.wgsl`) are chosen when the shader is
// composed: they define `shade_local_lights`, `shade_particle_lights` and `apply_decals` (which
// pipelines call on the surface before `shade`).
#include "shading/scene_bindings.wgsl"
#include "shading/shading_input.wgsl"
#include "shading/brdf.wgsl"
#include "shading/lights.wgsl"
#include "shading/environment.wgsl"
#include "$LIGHT_ENUMERATION"
#include "$DECAL_ENUMERATION"
#include "$PARTICLE_LIGHTING"
#include "shading/transmission.wgsl"
#include "shading/debug_view.wgsl"
#include "shading/shading_pixel.wgsl"

// The most radiance a point sends: far above any light a scene means, and far enough below the
// largest float that the sums and blends after shading stay finite (a glTF emissive strength may be
// as large as any float).
const MAX_RADIANCE: f32 = 1e30;

// Outgoing radiance towards the viewer: emission, the environment's light (where traced reflections
// replace its specular part, `reflections.wgsl` subtracts it), light let through from behind, sun,
// local and particle lights;
// `sun_visibility` is the fraction of the sun the point sees (`shading/sun_shadow*.wgsl`).
fn shade(s: ShadingInput, sun_visibility: f32) -> vec3<f32> {
    if DEBUG_VIEWS {
        debug_shadow_rays = 0u;
        debug_restir_confidence = 0u;
        debug_restir_weight = 0u;
    }
    if MATERIAL_EXTENSIONS && s.unlit {
        return min(s.base_color, vec3<f32>(MAX_RADIANCE));
    }
    // The environment (sky, image or uniform ambient) stands in for indirect light. A clear coat
    // lies over the emission too, which it dims by its Fresnel term (KHR_materials_clearcoat).
    var radiance = s.emissive * (1.0 - clearcoat_fresnel(s)) + environment_light(s);
    if frame.sun_direction.w > 0.0 && sun_visibility > 0.0 && !sun_seen_through(s) {
        radiance += frame.sun_radiance.rgb * sun_visibility * brdf_times_cosine(s, -frame.sun_direction.xyz);
    }
    if lit_from_behind(s) {
        radiance += transmitted_radiance(s);
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
        case DEBUG_VIEW_SHADOW_RAYS: {
            return heat_map(debug_shadow_rays, frame.debug_view.y);
        }
        case DEBUG_VIEW_RESTIR_CONFIDENCE: {
            return heat_map(debug_restir_confidence, frame.debug_view.y);
        }
        case DEBUG_VIEW_RESTIR_WEIGHT: {
            return heat_map(debug_restir_weight, frame.debug_view.y);
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

// Whether the sun lies behind a transmissive surface whose light from behind (`transmitted_light`)
// already shows its disc: then its transmission lobe would count it twice.
fn sun_seen_through(s: ShadingInput) -> bool {
    return lit_from_behind(s) && dot(s.normal, -frame.sun_direction.xyz) <= 0.0 && transmitted_light_shows_sun(s, transmission_path(s));
}

// `shade` for the opaque surface a pixel shows: what the shading core keeps per pixel from frame to
// frame (`shading/shading_pixel.wgsl`) is read and written for `pixel`.
// Where the frame is denoised, the pixel's sampled light goes to the denoiser's sample instead.
fn shade_pixel(s: ShadingInput, sun_visibility: f32, pixel: vec2<u32>) -> vec3<f32> {
    shading_pixel = pixel;
    sampled_diffuse = vec3<f32>(0.0);
    sampled_specular = vec3<f32>(0.0);
    let radiance = shade(s, sun_visibility);
    if DENOISED_LIGHTING {
        keep_denoise_sample(s, !DEBUG_VIEWS || frame.debug_view.x == DEBUG_VIEW_OFF);
    }
    shading_pixel = vec2<u32>(NO_PIXEL);
    return radiance;
}
