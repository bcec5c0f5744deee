// What both ray back ends (`rays/trace.wgsl`, `rays/trace_ray_query.wgsl`) share: the hit they
// return, alpha masks, and where rays leaving a surface start.
#include "shading/material.wgsl"

const RAY_NO_HIT: u32 = 0xffffffffu;

struct RayHit {
    // Distance along the world ray's direction (in units of its length); t_max when nothing was hit.
    t: f32,
    // Index into `ray_triangles`; RAY_NO_HIT when nothing was hit.
    triangle: u32,
    // Index into `ray_instances`.
    instance: u32,
    // Barycentrics of v1 and v2.
    b1: f32,
    b2: f32,
}

// The draw a triangle of an instance belongs to.
fn ray_triangle_draw(instance: RayInstance, tri: RayTriangle) -> u32 {
    return instance.first_draw + (tri.draw_offset & ~RAY_ALPHA_MASKED);
}

// Whether an alpha-masked triangle is solid at barycentrics (b1, b2): its material's alpha at the
// finest mip, as the raster's alpha test sees it up close.
fn ray_alpha_covers(instance: RayInstance, tri: RayTriangle, b1: f32, b2: f32) -> bool {
    let draw = draws[ray_triangle_draw(instance, tri)];
    let first = draw.first_index + tri.triangle * 3u;
    let v0 = vertices[draw.base_vertex + indices[first]];
    let v1 = vertices[draw.base_vertex + indices[first + 1u]];
    let v2 = vertices[draw.base_vertex + indices[first + 2u]];
    let b0 = 1.0 - b1 - b2;
    let uv = vertex_uvs(v0) * b0 + vertex_uvs(v1) * b1 + vertex_uvs(v2) * b2;
    let vertex_color = vertex_color(v0) * b0 + vertex_color(v1) * b1 + vertex_color(v2) * b2;
    let material = materials[draw.material];
    return material_base_color(material, UvGradients(uv, vec4<f32>(0.0), vec4<f32>(0.0)), vertex_color).a >= material.alpha_cutoff;
}

// A ray origin off the surface at `p` with geometric normal `n` (facing the side the ray leaves
// from), far enough that the ray cannot hit the surface it starts on through rounding, yet close
// enough to keep contact shadows: Wächter and Binder's integer-ulp offset ("A Fast and Robust Method
// for Avoiding Self-Intersection", Ray Tracing Gems, 2019), plus `extra` metres along n for origins
// known only to `extra`'s precision (a position rebuilt from depth).
fn ray_offset_origin(p: vec3<f32>, n: vec3<f32>, extra: f32) -> vec3<f32> {
    let offset_int = vec3<i32>(n * 256.0);
    let p_int = bitcast<vec3<f32>>(bitcast<vec3<i32>>(p) + select(offset_int, -offset_int, p < vec3<f32>(0.0)));
    let near_origin = abs(p) < vec3<f32>(1.0 / 32.0);
    return select(p_int, p + n * (1.0 / 65536.0), near_origin) + n * extra;
}
