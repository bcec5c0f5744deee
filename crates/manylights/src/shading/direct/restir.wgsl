// Direct lighting `restir`: resampled importance sampling (Talbot et al. 2005) of the lights that the
// enumeration method finds at a point, streamed through weighted reservoirs, reused across frames and
// pixels as in ReSTIR (Bitterli et al. 2020). The interface: `shading/direct/unshadowed.wgsl`.
//
// Candidates. Each light that reaches the point is a candidate whose target p̂ is the luminance of its
// unshadowed radiance f; a reservoir keeps one, y, with probability p̂(y) / Σ p̂, and weighs it by
// W = Σ p̂ / p̂(y), so that f(y) V(y) W, with V the shadow ray's visibility, has the expectation Σ f V:
// unbiased, the `reference` image on average, for one ray whatever the number of lights. Drawn through
// the light tree instead (`shading/enumerate/lights_tree.wgsl`), M candidates of probability p each
// weigh p̂ / (M p), whose sum estimates Σ p̂ without bias: the same estimator, at a cost that does not
// grow with the lights reaching the point.
//
// Reuse (`frame.direct_lighting.w`, `settings::RestirReuse`), at pixels' opaque surfaces only: the
// first sample's reservoir is kept per pixel — with visibility reuse: its weight zeroed where its
// light proved hidden — and the next frame combines the pixel's own reservoir with the one kept where
// the surface was seen a frame before (the previous camera's projection) and, spatiotemporally, with
// those of a few pixels around it (`RESTIR_REUSED`), each from a surface like the pixel's, its light
// still where it was in its group, its confidence M capped at `RESTIR_MAX_CONFIDENCE`. A reservoir r
// is chosen in proportion to p̂(y_r) W_r M_r, p̂ evaluated at the pixel's surface, and the result's W
// divides the sum by p̂(y) and by Z, the confidence of the reservoirs that could have chosen y: the
// 1/Z weights of Bitterli et al.'s unbiased combination. With visibility reuse, a kept reservoir
// could have chosen y only where its surface sees y, so each other surface that y lights (range,
// horizon, cone: known from the position and normal each reservoir keeps) is asked with a shadow
// ray of its own — one for each reused reservoir but the one y came from, none for the reprojected
// surface under a still camera, where it is the pixel's own point. The estimate stays unbiased
// while reuse steers samples towards lights the surface sees. Further samples (`frame.direct_lighting.y` above 1) are drawn from the
// pixel's candidates alone, each with its ray, and averaged with the first. Where the frame is
// denoised, the samples' light at pixels' opaque surfaces goes to the denoiser instead of into the
// radiance (`add_sampled_light`, `shading/shading_pixel.wgsl`; `passes/denoise/`).
#include "shading/light_bindings.wgsl"
#include "shading/direct/shadow_ray.wgsl"
#include "shading/shading_pixel.wgsl"
#include "shading/octahedral.wgsl"
#include "shading/random.wgsl"

// Keep in sync with `settings::MAX_RESTIR_SHADOW_RAYS`.
const RESTIR_MAX_SAMPLES: u32 = 4u;
const RESTIR_LUMINANCE: vec3<f32> = vec3<f32>(0.2126, 0.7152, 0.0722);
// Reuse (`settings::RestirReuse`).
const RESTIR_REUSE_TEMPORAL: u32 = 1u;
const RESTIR_REUSE_SPATIOTEMPORAL: u32 = 2u;
// A reused reservoir counts as at most this many of the pixel's own (Bitterli et al.'s cap), so a
// surface follows a change of its lighting within about as many frames.
const RESTIR_MAX_CONFIDENCE: u32 = 20u;
// The reservoirs a pixel reuses spatiotemporally: the reprojected pixel's and its neighbours',
// within this many pixels of it.
const RESTIR_REUSED: u32 = 5u;
const RESTIR_NEIGHBOUR_RADIUS: f32 = 16.0;
// A reservoir is reused from a surface whose normal is within about 25° of the pixel's and whose
// position lies within this fraction of the view distance of the pixel's plane.
const RESTIR_MIN_NORMAL_COSINE: f32 = 0.9;
const RESTIR_MAX_PLANE_DISTANCE: f32 = 0.05;
const RESTIR_NO_LIGHT: u32 = 0xffffffffu;

// The point's candidates' weights summed so far (Σ p̂ when enumerated);
// each sample's f / p̂ and where its light is (world space); the first sample's light, its instance
// and p̂.
var<private> restir_weight_sum: f32;
var<private> restir_radiance: array<vec3<f32>, RESTIR_MAX_SAMPLES>;
var<private> restir_light: array<vec3<f32>, RESTIR_MAX_SAMPLES>;
var<private> restir_first_light: u32;
var<private> restir_first_instance: u32;
var<private> restir_first_target: f32;

// Seeds the sequence from the point's position and the frame (`frame.direct_lighting.x`), so every
// pixel, ray hit and frame draws its own samples, and a frame rendered again draws the same.
fn direct_lights_begin(s: ShadingInput) {
    let p = bitcast<vec3<u32>>(s.position);
    random_state = random_hash(p.x ^ random_hash(p.y ^ random_hash(p.z ^ random_hash(frame.direct_lighting.x))));
    restir_weight_sum = 0.0;
    restir_first_light = RESTIR_NO_LIGHT;
}

fn direct_light(index: u32, instance_index: u32, sphere: vec4<f32>, instance: VolumeInstance, s: ShadingInput, radiance: vec3<f32>) -> vec3<f32> {
    restir_candidate(index, instance_index, sphere, instance, radiance, 1.0);
    return vec3<f32>(0.0);
}

// Streams light `index` (of the group `instance` places, `sphere` its sphere there), whose
// unshadowed radiance at the point is `radiance`, into the point's reservoirs as a candidate drawn
// with probability 1 / `inverse_probability`: its weight is p̂ / p. Enumerated lights are each drawn
// once (1); lights drawn through the light tree carry their draw's probability
// (`shading/enumerate/lights_tree.wgsl`).
fn restir_candidate(index: u32, instance_index: u32, sphere: vec4<f32>, instance: VolumeInstance, radiance: vec3<f32>, inverse_probability: f32) {
    let target_value = dot(radiance, RESTIR_LUMINANCE);
    if !(target_value > 0.0) {
        return;
    }
    let weight = target_value * inverse_probability;
    restir_weight_sum += weight;
    let keep = weight / restir_weight_sum;
    for (var k = 0u; k < frame.direct_lighting.y; k += 1u) {
        if random_next() < keep {
            restir_radiance[k] = radiance / target_value;
            restir_light[k] = instance_point_to_world(instance, sphere.xyz);
            if k == 0u {
                restir_first_light = index;
                restir_first_instance = instance_index;
                restir_first_target = target_value;
            }
        }
    }
}

// What identifies a light record as the one a reservoir chose: its sphere in its group's space.
// Records of lights that move within their group, or are written in another order each frame
// (particles), no longer match, and their reservoirs are not reused.
fn restir_light_hash(index: u32) -> u32 {
    let sphere = bitcast<vec4<u32>>(light_sphere(index));
    return random_hash(sphere.x ^ random_hash(sphere.y ^ random_hash(sphere.z ^ random_hash(sphere.w))));
}

// Whether light `index`, placed by `instance`, lights the surface at `position` facing `normal` (world
// space) at all: the support of the target there, for the combination's Z.
fn restir_light_reaches(index: u32, instance: VolumeInstance, position: vec3<f32>, normal: vec3<f32>) -> bool {
    let sphere = light_sphere(index);
    let p = instance_point_to_group(instance, position);
    let to_light = sphere.xyz - p;
    if !sphere_reaches(sphere, p) || dot(instance_vector_to_group(instance, normal), to_light) <= 0.0 {
        return false;
    }
    return lights[index].kind != LIGHT_SPOT
        || spot_cone_attenuation(lights[index].direction, lights[index].spot_scale, lights[index].spot_offset, normalize(to_light)) > 0.0;
}

// The pixel where the surface at `position` was seen a frame ago.
fn restir_previous_pixel(position: vec3<f32>) -> vec2<f32> {
    let clip = frame.previous_clip_from_world * vec4<f32>(position, 1.0);
    let ndc = clip.xy / clip.w;
    return select(vec2<f32>(-1.0), vec2<f32>((ndc.x * 0.5 + 0.5) * frame.viewport.x, (0.5 - ndc.y * 0.5) * frame.viewport.y), clip.w > 0.0);
}

// The chosen light of the combination so far, its radiance at the pixel, p̂ there and where it is.
struct RestirChoice {
    light: u32,
    instance: u32,
    radiance: vec3<f32>,
    target_value: f32,
    position: vec3<f32>,
}

// Where pixel `pixel`'s reservoir lies in `restir_reservoirs`, in half `half` (0 or 1).
fn restir_reservoir_index(half: u32, pixel: vec2<u32>) -> u32 {
    let width = u32(frame.viewport.x);
    return (half * u32(frame.viewport.y) + pixel.y) * width + pixel.x;
}

// A combination's result: the chosen light's W, and the confidence of all it combined.
struct RestirReused {
    weight: f32,
    count: u32,
}

// Combines the pixel's own reservoir (`choice`, whose weight sum is `restir_weight_sum`) with those
// kept at and around where its surface was a frame before; the chosen light becomes `choice`.
fn restir_reuse(s: ShadingInput, choice: ptr<function, RestirChoice>) -> RestirReused {
    // The pixel's own candidates: one reservoir of confidence 1 whose weight sum is Σ p̂.
    var weight_sum = restir_weight_sum;
    var count = 1u;
    // Reused reservoirs' surfaces and confidences, for Z.
    var positions: array<vec3<f32>, RESTIR_REUSED>;
    var normals: array<vec3<f32>, RESTIR_REUSED>;
    var counts: array<u32, RESTIR_REUSED>;
    // The light (and its instance) each kept with no weight, its surface not seeing it when it was
    // made (RESTIR_NO_LIGHT for the others): that light could not have been chosen there, whatever
    // its surface sees now.
    var hidden: array<vec2<u32>, RESTIR_REUSED>;
    var reused = 0u;
    // Which reused reservoir the choice came from (RESTIR_REUSED: the pixel's own).
    var source = RESTIR_REUSED;
    let plane_tolerance = RESTIR_MAX_PLANE_DISTANCE * length(s.position - frame.world_from_view[3].xyz);
    // The surface a frame before: where an animated instance carried it, seen by the camera then.
    let previous_position = previous_surface_position(shading_pixel, s.position);
    let previous = restir_previous_pixel(previous_position);
    let tries = select(1u, RESTIR_REUSED, frame.direct_lighting.w == RESTIR_REUSE_SPATIOTEMPORAL);
    for (var t = 0u; t < tries; t += 1u) {
        var at = previous;
        if t > 0u {
            let angle = 6.2831853 * random_next();
            at += RESTIR_NEIGHBOUR_RADIUS * sqrt(random_next()) * vec2<f32>(cos(angle), sin(angle));
        }
        if any(at < vec2<f32>(0.0)) || any(at >= frame.viewport.xy) {
            continue;
        }
        let kept = restir_reservoirs[restir_reservoir_index(1u - frame.direct_lighting.z, vec2<u32>(at))];
        let kept_count = min(kept.normal_count >> 24u, RESTIR_MAX_CONFIDENCE);
        let kept_normal = octahedral_unpack(kept.normal_count, 12u);
        if kept_count == 0u || dot(kept_normal, s.normal) < RESTIR_MIN_NORMAL_COSINE
            || abs(dot(s.normal, kept.position - previous_position)) > plane_tolerance {
            continue;
        }
        var weight = 0.0;
        var candidate: RestirChoice;
        if kept.light != RESTIR_NO_LIGHT {
            if kept.light >= arrayLength(&lights) || kept.instance >= frame.light_instance_count || restir_light_hash(kept.light) != kept.light_hash {
                continue;
            }
            let instance = light_instances[kept.instance];
            let local = shading_input_in_group(s, instance);
            let sphere = light_sphere(kept.light);
            let radiance = light_contribution(kept.light, sphere, local) * instance_light_falloff(instance);
            let target_value = dot(radiance, RESTIR_LUMINANCE);
            candidate = RestirChoice(kept.light, kept.instance, radiance, target_value, instance_point_to_world(instance, sphere.xyz));
            weight = target_value * kept.weight * f32(kept_count);
        }
        // Its surface as it is now, for Z's tests in the frame's scene: carried as far as the pixel's.
        positions[reused] = kept.position + (s.position - previous_position);
        normals[reused] = kept_normal;
        counts[reused] = kept_count;
        hidden[reused] = select(vec2<u32>(RESTIR_NO_LIGHT), vec2<u32>(kept.light, kept.instance), kept.weight == 0.0);
        count += kept_count;
        weight_sum += weight;
        if weight > 0.0 && random_next() * weight_sum < weight {
            *choice = candidate;
            source = reused;
        }
        reused += 1u;
    }
    var weight = 0.0;
    if (*choice).target_value > 0.0 {
        // Z: the confidence of every reservoir that could have chosen y — the pixel's own, the one it
        // came from, and each other whose surface y lights and sees, since kept reservoirs hold only
        // lights their surface saw (their weight is zeroed otherwise). A ray asks whether it sees y,
        // unless the surface is the pixel's own point, as it is under a still camera. Where blockers
        // move, a surface may see now what it did not then: one that kept y's light without weight
        // did not see it.
        let instance = light_instances[(*choice).instance];
        var z = 1u;
        for (var r = 0u; r < reused; r += 1u) {
            if r == source || (any(hidden[r] != vec2<u32>((*choice).light, (*choice).instance)) && restir_light_reaches((*choice).light, instance, positions[r], normals[r])
                && (all(positions[r] == s.position) || !light_occluded_from(positions[r], normals[r], (*choice).position))) {
                z += counts[r];
            }
        }
        weight = weight_sum / (f32(z) * (*choice).target_value);
    }
    return RestirReused(weight, count);
}

// Keeps the pixel's reservoir for the next frame: `choice` with weight `weight` and confidence `count`.
fn restir_keep(s: ShadingInput, choice: RestirChoice, weight: f32, count: u32) {
    if DEBUG_VIEWS {
        debug_restir_confidence = count;
    }
    var light_hash = 0u;
    if choice.light != RESTIR_NO_LIGHT {
        light_hash = restir_light_hash(choice.light);
    }
    restir_reservoirs[restir_reservoir_index(frame.direct_lighting.z, shading_pixel)] = Reservoir(choice.light, choice.instance, light_hash, weight, s.position, octahedral_pack_counted(s.normal, count));
}

fn direct_lights_end(s: ShadingInput) -> vec3<f32> {
    let samples = frame.direct_lighting.y;
    var radiance = vec3<f32>(0.0);
    for (var k = 1u; k < samples; k += 1u) {
        if restir_weight_sum > 0.0 && !light_occluded(restir_light[k], s) {
            radiance += add_sampled_light(s, restir_light[k], restir_radiance[k] * restir_weight_sum / f32(samples));
        }
    }
    // The first sample: the pixel's own choice, or the one its reuse makes.
    var choice = RestirChoice(RESTIR_NO_LIGHT, 0u, vec3<f32>(0.0), 0.0, vec3<f32>(0.0));
    var weight = 0.0;
    if restir_first_light != RESTIR_NO_LIGHT {
        choice = RestirChoice(restir_first_light, restir_first_instance, restir_radiance[0] * restir_first_target, restir_first_target, restir_light[0]);
        weight = restir_weight_sum / restir_first_target;
    }
    let keeps = frame.direct_lighting.w != 0u && shading_pixel.x != NO_PIXEL;
    var count = 1u;
    if keeps {
        let reused = restir_reuse(s, &choice);
        weight = reused.weight;
        count = reused.count;
    }
    if DEBUG_VIEWS && restir_weight_sum > 0.0 {
        debug_restir_weight = u32(round(4.0 * choice.target_value * weight / restir_weight_sum));
    }
    let visible = weight > 0.0 && !light_occluded(choice.position, s);
    if visible {
        radiance += add_sampled_light(s, choice.position, choice.radiance * weight / f32(samples));
    }
    if keeps {
        // Visibility reuse: a reservoir whose light its surface does not see keeps no weight.
        restir_keep(s, choice, select(0.0, weight, visible), count);
    }
    return radiance;
}
