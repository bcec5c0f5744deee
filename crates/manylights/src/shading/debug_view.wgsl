// Debug views (`settings::DebugView`, `frame.debug_view`): instead of its radiance, a pixel shows what
// shading counted there as a heat map from black (none) through blue, cyan, green and yellow to red
// (`frame.debug_view.y` or more). The enumeration modules count as they work; `shade` shows the view.
// Keep `heat_map` in sync with `settings::heat_map`.

const DEBUG_VIEW_OFF: u32 = 0u;
// Lights whose light reaches the point (after the tight test), in any method.
const DEBUG_VIEW_LIGHTS_REACHING: u32 = 1u;
// The light method's work: BVH nodes visited (bvh), lights in the froxel's list (clustered:
// cluster occupancy), lights tested (brute force).
const DEBUG_VIEW_LIGHT_WORK: u32 = 2u;
// Decals covering the point (inside the box, facing, with alpha), in any method.
const DEBUG_VIEW_DECALS_COVERING: u32 = 3u;
// The particle lights' radiance alone, as the grid or the exact method gives it.
const DEBUG_VIEW_PARTICLE_LIGHT: u32 = 4u;
// A horizontal slice through the particle grid at height `frame.debug_view.z` (f32 bits): where a
// pixel's ray crosses it before its surface, the grid's colour sum there; elsewhere the surface,
// dimmed.
const DEBUG_VIEW_PARTICLE_GRID_SLICE: u32 = 5u;
// Shadow rays the direct lighting traced for the point towards local lights (`shading/direct/`):
// lamps within the budget, one per light for `reference`, restir's samples and the rays its reuse
// asks of neighbours.
const DEBUG_VIEW_SHADOW_RAYS: u32 = 6u;
// The confidence M of the reservoir `restir` keeps at the pixel: how many candidates' worth of
// samples, its own and reused, its choice stands on (0 where nothing is kept).
const DEBUG_VIEW_RESTIR_CONFIDENCE: u32 = 7u;
// The weight of the sample `restir` shades the pixel with, as its unshadowed estimate p̂(y) W over the
// pixel's own Σ p̂, in quarters: 4 where reuse agrees with the pixel's own candidates, more where a
// reused sample weighs more (a firefly), 0 where nothing lights the pixel.
const DEBUG_VIEW_RESTIR_WEIGHT: u32 = 8u;

// Whether this pipeline shows a debug view (`ShadingMethods::debug_views`): otherwise the counters are
// compiled out, as counting every node, light and decal slows shading (benchmarks/LOG.md, topic 4).
override DEBUG_VIEWS: bool = false;

var<private> debug_lights_reaching: u32;
var<private> debug_light_work: u32;
var<private> debug_decals_covering: u32;
var<private> debug_shadow_rays: u32;
var<private> debug_restir_confidence: u32;
var<private> debug_restir_weight: u32;

fn heat_map(count: u32, scale: u32) -> vec3<f32> {
    if count == 0u {
        return vec3<f32>(0.0);
    }
    let t = saturate(f32(count) / f32(max(scale, 1u))) * 4.0;
    let stops = array<vec3<f32>, 5>(
        vec3<f32>(0.0, 0.0, 1.0),
        vec3<f32>(0.0, 1.0, 1.0),
        vec3<f32>(0.0, 1.0, 0.0),
        vec3<f32>(1.0, 1.0, 0.0),
        vec3<f32>(1.0, 0.0, 0.0),
    );
    let i = min(u32(t), 3u);
    return mix(stops[i], stops[i + 1u], t - f32(i));
}
