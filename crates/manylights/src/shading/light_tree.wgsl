// Drawing a light through the light tree (Conty Estevez & Kulla 2018): from a group's root, each step
// picks one of a node's two children in proportion to its importance at the shading point, down to a
// leaf; the probability of the leaf is the product of the choices made (`accel/light_tree.rs` builds
// the nodes' emitters). The importance is zero only where no light below can light the point — the
// point outside the node's box, which bounds its lights' spheres, or every light below the surface's
// horizon — so every light that lights the point can be drawn.
#include "shading/light_bindings.wgsl"
#include "shading/random.wgsl"

// A node's importance at group-space point `p` facing `n`: its lights' power over the squared
// distance to their positions' box, that distance taken as at least the box's half-diagonal (Conty
// Estevez & Kulla's clamp, which keeps a box around the point from claiming every draw), through the
// range window (`light_distance_attenuation`'s) of the nearest any of them can be with the largest
// range: zero only where none reaches.
fn light_tree_importance(node: u32, p: vec3<f32>, n: vec3<f32>) -> f32 {
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
    if dot(n, centre - p) + dot(abs(n), half_extent) <= 0.0 {
        return 0.0;
    }
    let to_centre = centre - p;
    return emitters.power * window * window / max(dot(to_centre, to_centre), max(dot(half_extent, half_extent), 1e-8));
}

// Where a draw from the subtree under `root` ended and with what probability: at a leaf (`drawn`;
// `entry` names its range, `bvh_leaf_range`), or at a node below which no light lights the point.
// Each step draws `random_next()`.
struct LightTreeDraw {
    entry: u32,
    probability: f32,
    drawn: bool,
}

fn light_tree_draw_leaf(root: u32, p: vec3<f32>, n: vec3<f32>) -> LightTreeDraw {
    var node = root;
    var probability = 1.0;
    loop {
        let entry = light_nodes[node].entry;
        if (entry & BVH_LEAF) != 0u {
            return LightTreeDraw(entry, probability, true);
        }
        let second = light_nodes[entry].skip;
        let first_weight = light_tree_importance(entry, p, n);
        let total = first_weight + light_tree_importance(second, p, n);
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
