// `$TRANSMITTED_LIGHT` for the transmissive and transparent passes: the light behind a transmissive surface is read from
// the image of the opaque surfaces (`passes/transmission_background.rs`), where the refracted ray
// leaves the medium, from the mip level its roughness blurs it to (the Khronos sample viewer's
// screen-space transmission). Transparent surfaces behind it are not seen through it.
#include "shading/scene_bindings.wgsl"
#include "shading/shading_input.wgsl"
#include "shading/environment.wgsl"

@group(1) @binding(0) var transmission_background: texture_2d<f32>;
@group(1) @binding(1) var transmission_sampler: sampler;

// The background's mip level the surface reads: rough surfaces blur as much as they bend, none at an
// index of 1, fully from 1.5 up.
fn transmitted_lod(s: ShadingInput) -> f32 {
    let size = vec2<f32>(textureDimensions(transmission_background));
    return log2(max(size.x, size.y)) * s.roughness * saturate(s.ior * 2.0 - 2.0);
}

fn transmitted_light(s: ShadingInput, path: vec3<f32>) -> vec3<f32> {
    let clip = frame.clip_from_world * vec4<f32>(s.position + path, 1.0);
    let uv = clip.xy / max(clip.w, 1e-6) * vec2<f32>(0.5, -0.5) + 0.5;
    return textureSampleLevel(transmission_background, transmission_sampler, uv, transmitted_lod(s)).rgb;
}

// Whether the light read behind the surface holds the sun's disc: the sky shows it, and the eye's
// ray to where the refracted ray leaves points into it, widened by the level's blur (its texels'
// width in pixels, each the angle of the view's height over its pixels).
fn transmitted_light_shows_sun(s: ShadingInput, path: vec3<f32>) -> bool {
    if !sun_disc_seen() {
        return false;
    }
    let seen = normalize(s.position + path - frame.world_from_view[3].xyz);
    let pixel_angle = 2.0 * frame.view_from_clip[1][1] / frame.viewport.y;
    let blur = exp2(transmitted_lod(s)) * pixel_angle;
    return dot(seen, -frame.sun_direction.xyz) > cos(min(frame.ray_settings.x + blur, PI));
}
