// Ray traversal of the scene's two-level hierarchy (`rays/mod.rs`) by the software back end, in any
// stage: closest hit for reflections, any hit for shadows (the hardware back end's twin:
// `rays/trace_ray_query.wgsl`; the plan picks one as `$RAY_TRACE`). Like the point query
// (`accel/volume_query.wgsl`) it needs no stack for any hit: every node says where to go if the ray
// meets its box (`entry`) and if not (`skip`), and a top-level leaf moves the ray into its instance's
// mesh space until that BLAS ends (its last `skip` is BVH_END), then resumes the top level. The ray's
// direction is mapped into mesh space without normalising, so a hit's distance means the same in
// every instance and prunes them all.
#include "rays/ray_hit.wgsl"

// 1 / d with zero components turned into huge finite values of the right sign: slab tests then stay
// free of 0 · ∞ = NaN for rays starting on a slab's plane.
fn ray_inverse_direction(d: vec3<f32>) -> vec3<f32> {
    let tiny = 1e-30;
    let safe = select(d, select(vec3<f32>(tiny), vec3<f32>(-tiny), d < vec3<f32>(0.0)), abs(d) < vec3<f32>(tiny));
    return 1.0 / safe;
}

// Where the ray enters the node's box between 0 and `t_max`, or -1 if it misses it.
fn ray_box_entry(node: BvhNode, origin: vec3<f32>, inverse_dir: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (node.min - origin) * inverse_dir;
    let t1 = (node.max - origin) * inverse_dir;
    let near = min(t0, t1);
    let far = max(t0, t1);
    let enter = max(max(near.x, near.y), max(near.z, 0.0));
    let exit = min(min(far.x, far.y), min(far.z, t_max));
    return select(-1.0, enter, enter <= exit);
}

// A ray in the space of the level being walked: the world's in the top level, an instance's mesh
// space in its BLAS.
struct RaySpace {
    origin: vec3<f32>,
    dir: vec3<f32>,
    inverse_dir: vec3<f32>,
}

fn ray_space(origin: vec3<f32>, dir: vec3<f32>) -> RaySpace {
    return RaySpace(origin, dir, ray_inverse_direction(dir));
}

// The world ray in an instance's mesh space. The direction is mapped, not normalised: hit distances
// mean the same in every instance.
fn ray_space_of(instance: RayInstance, origin: vec3<f32>, dir: vec3<f32>) -> RaySpace {
    return ray_space(vec4<f32>(origin, 1.0) * instance.local_from_world, vec4<f32>(dir, 0.0) * instance.local_from_world);
}

// Möller–Trumbore, both faces: (t, b1, b2) of the hit, or t = -1 when the ray misses the triangle
// (or is parallel to its plane).
fn ray_triangle(origin: vec3<f32>, dir: vec3<f32>, tri: RayTriangle) -> vec3<f32> {
    let p = cross(dir, tri.e2);
    let det = dot(tri.e1, p);
    if det == 0.0 {
        return vec3<f32>(-1.0, 0.0, 0.0);
    }
    let inverse_det = 1.0 / det;
    let s = origin - tri.v0;
    let b1 = dot(s, p) * inverse_det;
    let q = cross(s, tri.e1);
    let b2 = dot(dir, q) * inverse_det;
    if b1 < 0.0 || b2 < 0.0 || b1 + b2 > 1.0 {
        return vec3<f32>(-1.0, 0.0, 0.0);
    }
    return vec3<f32>(dot(tri.e2, q) * inverse_det, b1, b2);
}

// `hit` updated with the triangles of a BLAS leaf (the range [x, y) of `ray_triangles`) that the ray
// meets before it, alpha masks applied; with `any_hit`, the first such triangle.
fn ray_hit_leaf(leaf: vec2<u32>, ray: RaySpace, instance: RayInstance, instance_index: u32, hit: RayHit, any_hit: bool) -> RayHit {
    var nearest = hit;
    for (var k = leaf.x; k < leaf.y; k += 1u) {
        let tri = ray_triangles[k];
        let candidate = ray_triangle(ray.origin, ray.dir, tri);
        if candidate.x > 0.0 && candidate.x < nearest.t {
            if (tri.draw_offset & RAY_ALPHA_MASKED) != 0u && !ray_alpha_covers(instance, tri, candidate.y, candidate.z) {
                continue;
            }
            nearest = RayHit(candidate.x, k, instance_index, candidate.y, candidate.z);
            if any_hit {
                break;
            }
        }
    }
    return nearest;
}

// The first hit found along origin + t · dir with 0 < t < t_max, in stored order: shadow rays need no
// more (closest hits: `trace_closest`). Origins must be offset off the surface they leave
// (`ray_offset_origin`).
fn trace_any_hit(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> RayHit {
    var hit = RayHit(t_max, RAY_NO_HIT, 0u, 0.0, 0.0);
    var ray = ray_space(origin, dir);
    var in_blas = false;
    var instance_index = 0u;
    var instance: RayInstance;
    var resume = BVH_END;
    var node_index = 0u;
    loop {
        if node_index == BVH_END {
            if !in_blas {
                break;
            }
            // The instance's BLAS is done: back to the top level, in world space.
            in_blas = false;
            node_index = resume;
            ray = ray_space(origin, dir);
            continue;
        }
        let node = ray_nodes[node_index];
        // A link to the node itself ends the walk: no valid tree has one, but lanes run on zeroed
        // memory (lavapipe's fragment helpers) must not loop (see `volume_query.wgsl`).
        let skip = select(node.skip, BVH_END, node.skip == node_index);
        if ray_box_entry(node, ray.origin, ray.inverse_dir, hit.t) < 0.0 {
            node_index = skip;
            continue;
        }
        if (node.entry & BVH_LEAF) == 0u {
            node_index = select(node.entry, BVH_END, node.entry == node_index);
            continue;
        }
        let leaf = bvh_leaf_range(node.entry);
        if !in_blas {
            // A top-level leaf: one instance. Continue in its mesh's space.
            instance_index = leaf.x;
            instance = ray_instances[instance_index];
            ray = ray_space_of(instance, origin, dir);
            resume = skip;
            in_blas = true;
            node_index = instance.blas_root;
            continue;
        }
        hit = ray_hit_leaf(leaf, ray, instance, instance_index, hit, true);
        if hit.triangle != RAY_NO_HIT {
            return hit;
        }
        node_index = skip;
    }
    return hit;
}

// Whether anything lies on the segment from `origin` along `dir` before `t_max`.
fn ray_occluded(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    return trace_any_hit(origin, dir, t_max).triangle != RAY_NO_HIT;
}

// Entries of the closest-hit traversal's stack: far children still to visit, at most one per level of
// the top level and of one BLAS together (the CPU builder bounds each tree's depth by 48: 94 at most).
const RAY_STACK_SIZE: u32 = 96u;

// The nearest hit along origin + t · dir with 0 < t < t_max, visiting the nearer child of each node first and keeping the farther on a stack with the distance
// where the ray enters it: once a hit is nearer than that, the subtree is skipped unvisited. The
// stackless walk must visit children in their stored order; for closest hits that visits far more
// nodes (benchmarks/LOG.md, topic 7).
fn trace_closest(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> RayHit {
    var hit = RayHit(t_max, RAY_NO_HIT, 0u, 0.0, 0.0);
    // Not zero-filled on Vulkan (`gpu/spirv.rs`, UNZEROED_VARIABLES): entries below `depth` only are read.
    var stack_nodes: array<u32, RAY_STACK_SIZE>;
    var stack_entry: array<f32, RAY_STACK_SIZE>;
    var depth = 0u;
    var ray = ray_space(origin, dir);
    var in_blas = false;
    // The stack depth at which the current BLAS began: popping below it leaves the instance.
    var blas_base = 0u;
    var instance_index = 0u;
    var instance: RayInstance;
    // The node to visit, its box known to be met; BVH_END when the next one comes off the stack.
    var node_index = select(BVH_END, 0u, ray_box_entry(ray_nodes[0], ray.origin, ray.inverse_dir, hit.t) >= 0.0);
    loop {
        if node_index == BVH_END {
            // Pop the nearest pending subtree the ray still enters before the hit found.
            loop {
                if in_blas && depth == blas_base {
                    in_blas = false;
                    ray = ray_space(origin, dir);
                }
                if depth == 0u {
                    break;
                }
                depth -= 1u;
                if stack_entry[depth] < hit.t {
                    node_index = stack_nodes[depth];
                    break;
                }
            }
            if node_index == BVH_END {
                break;
            }
        }
        let node = ray_nodes[node_index];
        if (node.entry & BVH_LEAF) != 0u {
            let leaf = bvh_leaf_range(node.entry);
            node_index = BVH_END;
            if !in_blas {
                // A top-level leaf: one instance. Continue in its mesh's space, at its BLAS's root.
                instance_index = leaf.x;
                instance = ray_instances[instance_index];
                ray = ray_space_of(instance, origin, dir);
                in_blas = true;
                blas_base = depth;
                if ray_box_entry(ray_nodes[instance.blas_root], ray.origin, ray.inverse_dir, hit.t) >= 0.0 {
                    node_index = instance.blas_root;
                }
                continue;
            }
            hit = ray_hit_leaf(leaf, ray, instance, instance_index, hit, false);
            continue;
        }
        // Both children: the first is `entry`, the second the first's `skip`.
        let first_index = node.entry;
        let first = ray_nodes[first_index];
        let second_index = first.skip;
        // A link back to the node ends the walk: lanes run on zeroed memory must not loop (see
        // `trace_any_hit`).
        if first_index == node_index || second_index == node_index {
            break;
        }
        let first_entry = ray_box_entry(first, ray.origin, ray.inverse_dir, hit.t);
        let second_entry = ray_box_entry(ray_nodes[second_index], ray.origin, ray.inverse_dir, hit.t);
        if first_entry >= 0.0 && second_entry >= 0.0 {
            let first_nearer = first_entry <= second_entry;
            node_index = select(second_index, first_index, first_nearer);
            // Never full for trees the CPU builder makes (depth ≤ 48 each); the test keeps a
            // corrupt tree from writing past it.
            if depth < RAY_STACK_SIZE {
                stack_nodes[depth] = select(first_index, second_index, first_nearer);
                stack_entry[depth] = max(first_entry, second_entry);
                depth += 1u;
            }
        } else if first_entry >= 0.0 {
            node_index = first_index;
        } else if second_entry >= 0.0 {
            node_index = second_index;
        } else {
            node_index = BVH_END;
        }
    }
    return hit;
}

