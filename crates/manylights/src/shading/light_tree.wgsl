// Drawing a light through the light tree (Conty Estevez & Kulla 2018): from a group's root, each step
// picks one of a node's two children in proportion to its importance at the shading point, down to a
// leaf; the probability of the leaf is the product of the choices made (`accel/light_tree.rs` builds
// the nodes' emitters). The importance is zero only where no light below can light the point — the
// point outside the node's box, which bounds its lights' spheres, or every light below the horizon of
// a surface lit from above only — so every light that lights the point can be drawn.
#include "shading/light_bindings.wgsl"
#include "shading/random.wgsl"

// A node's importance at group-space point `p` facing `n`: its lights' power over the squared
// distance to their positions' box, that distance taken as at least the box's half-diagonal (Conty
// Estevez & Kulla's clamp, which keeps a box around the point from claiming every draw), times the
// largest cosine at the surface of a direction into the box (their orientation bound), through the
// range window (`light_distance_attenuation`'s) of the nearest any of them can be with the largest
// range: zero only where none reaches. A surface lit from both sides (`two_sided`: transmissive ones)
// takes the cosine as 1.
fn light_tree_importance(node: u32, p: vec3<f32>, n: vec3<f32>, two_sided: bool) -> f32 {
    let bounds = light_nodes[node];
    if any(p < bounds.min) || any(p > bounds.max) {
        return 0.0;
    }
    let emitters = light_tree[node];
    let gap = max(max(emitters.min - p, p - emitters.max), vec3<f32>(0.0));
    let nearest_ratio_sq = dot(gap, gap) / (emitters.range * emitters.range);
    if !(nearest_ratio_sq < 1.0) {
        return 0.0;
    }
    let window = 1.0 - nearest_ratio_sq * nearest_ratio_sq;
    let centre = 0.5 * (emitters.min + emitters.max);
    let half_extent = 0.5 * (emitters.max - emitters.min);
    // The highest any of the box's corners lies above the surface's plane.
    if !two_sided && dot(n, centre - p) + dot(abs(n), half_extent) <= 0.0 {
        return 0.0;
    }
    let to_centre = centre - p;
    let distance_sq = dot(to_centre, to_centre);
    let radius_sq = dot(half_extent, half_extent);
    // The largest cosine at the surface of a direction to the box: that of the angle to its centre
    // less the angle its bounding sphere subtends (1 where the sphere holds the point).
    var cosine = 1.0;
    if !two_sided && distance_sq > radius_sq {
        let cos_centre = dot(n, to_centre) * inverseSqrt(max(distance_sq * dot(n, n), 1e-30));
        let cos_sphere = sqrt(1.0 - radius_sq / distance_sq);
        if cos_centre < cos_sphere {
            let sin_centre = sqrt(max(1.0 - cos_centre * cos_centre, 0.0));
            cosine = max(cos_centre * cos_sphere + sin_centre * sqrt(radius_sq / distance_sq), 1e-6);
        }
    }
    return emitters.power * cosine * window * window / max(distance_sq, max(radius_sq, 1e-8));
}

// Where a draw from the subtree under `root` ended and with what probability: at a leaf (`drawn`;
// `entry` names its range, `bvh_leaf_range`), or at a node below which no light lights the point.
// Each step draws `random_next()`.
struct LightTreeDraw {
    entry: u32,
    probability: f32,
    drawn: bool,
}

fn light_tree_draw_leaf(root: u32, p: vec3<f32>, n: vec3<f32>, two_sided: bool) -> LightTreeDraw {
    var node = root;
    var probability = 1.0;
    loop {
        let entry = light_nodes[node].entry;
        if (entry & BVH_LEAF) != 0u {
            return LightTreeDraw(entry, probability, true);
        }
        let second = light_nodes[entry].skip;
        let first_weight = light_tree_importance(entry, p, n, two_sided);
        let total = first_weight + light_tree_importance(second, p, n, two_sided);
        if !(total > 0.0) {
            return LightTreeDraw(entry, probability, false);
        }
        let first_chance = first_weight / total;
        if random_next() < first_chance {
            node = entry;
            probability *= first_chance;
        } else {
            node = second;
            probability *= 1.0 - first_chance;
        }
    }
    return LightTreeDraw(0u, 0.0, false);
}
