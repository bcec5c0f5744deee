// A triangle's surface where a ray meets it: barycentrics from the ray meeting the triangle's plane,
// and their derivatives from two neighbouring rays meeting it too, which give texture (UV) and
// position gradients analytically. The visibility-buffer resolve uses the next pixels' camera rays;
// a reflection's hit uses rays offset across the ray's cone. Rays and triangle are relative to a
// reference point (the camera, the reflecting point), which keeps f32 precision far from the origin.
#include "shading/material.wgsl"
#include "shading/camera.wgsl"

struct TriangleSurface {
    frame: SurfaceFrame,
    g: UvGradients,
    vertex_color: vec4<f32>,
    // Relative to the reference point.
    relative_position: vec3<f32>,
    dp: PositionGradients,
    // Unit, on the side the ray came from.
    geometric_normal: vec3<f32>,
}

// Barycentrics (b0, b1, b2) where the ray meets the triangle's plane (Möller–Trumbore without the
// inside test: neighbouring rays may pass outside the triangle, which is what derivatives need).
fn ray_plane_barycentrics(ray: Ray, p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>) -> vec3<f32> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pvec = cross(ray.dir, e2);
    let det = dot(e1, pvec);
    let inv_det = 1.0 / select(det, 1e-20, abs(det) < 1e-20);
    let tvec = ray.origin - p0;
    let b1 = dot(tvec, pvec) * inv_det;
    let b2 = dot(ray.dir, cross(tvec, e1)) * inv_det;
    return vec3<f32>(1.0 - b1 - b2, b1, b2);
}

fn interpolate4(b: vec3<f32>, a0: vec4<f32>, a1: vec4<f32>, a2: vec4<f32>) -> vec4<f32> {
    return a0 * b.x + a1 * b.y + a2 * b.z;
}

fn interpolate3(b: vec3<f32>, a0: vec3<f32>, a1: vec3<f32>, a2: vec3<f32>) -> vec3<f32> {
    return a0 * b.x + a1 * b.y + a2 * b.z;
}

// Triangle `triangle` of `draw` seen along `ray`, with `ray_dx` and `ray_dy` its neighbours; all
// relative to `reference`. Back faces (of double-sided materials in the raster, of any material for
// rays) turn their whole tangent frame over, so they are lit from the side they are seen from and
// normal maps bump the same way on both sides; mirrored instances reverse the winding, hence the
// handedness sign.
fn triangle_surface(draw: Draw, triangle: u32, reference: vec3<f32>, ray: Ray, ray_dx: Ray, ray_dy: Ray) -> TriangleSurface {
    let first = draw.first_index + triangle * 3u;
    let v0 = vertices[draw.base_vertex + indices[first]];
    let v1 = vertices[draw.base_vertex + indices[first + 1u]];
    let v2 = vertices[draw.base_vertex + indices[first + 2u]];
    let p0 = (draw.world_from_local * vec4<f32>(v0.position, 1.0)).xyz - reference;
    let p1 = (draw.world_from_local * vec4<f32>(v1.position, 1.0)).xyz - reference;
    let p2 = (draw.world_from_local * vec4<f32>(v2.position, 1.0)).xyz - reference;

    let b = ray_plane_barycentrics(ray, p0, p1, p2);
    let b_dx = ray_plane_barycentrics(ray_dx, p0, p1, p2);
    let b_dy = ray_plane_barycentrics(ray_dy, p0, p1, p2);

    var out: TriangleSurface;
    // Without SECOND_UV_SET nothing reads the second set (zw), and the compiler drops it.
    let uv0 = vertex_uvs(v0);
    let uv1 = vertex_uvs(v1);
    let uv2 = vertex_uvs(v2);
    let uv = interpolate4(b, uv0, uv1, uv2);
    out.g = UvGradients(uv, interpolate4(b_dx, uv0, uv1, uv2) - uv, interpolate4(b_dy, uv0, uv1, uv2) - uv);
    out.vertex_color = vertex_color(v0) * b.x + vertex_color(v1) * b.y + vertex_color(v2) * b.z;
    out.relative_position = interpolate3(b, p0, p1, p2);
    out.dp = PositionGradients(interpolate3(b_dx, p0, p1, p2) - out.relative_position, interpolate3(b_dy, p0, p1, p2) - out.relative_position);

    out.frame.normal = normalize(world_normal(draw, interpolate3(b, v0.normal, v1.normal, v2.normal)));
    out.frame.tangent = world_direction(draw, interpolate3(b, v0.tangent.xyz, v1.tangent.xyz, v2.tangent.xyz));
    out.frame.bitangent_sign = v0.tangent.w * sign(draw.normal_from_local[0].w);
    let winding_normal = cross(p1 - p0, p2 - p0) * sign(draw.normal_from_local[0].w);
    out.geometric_normal = normalize(winding_normal);
    if dot(winding_normal, ray.dir) > 0.0 {
        out.frame.normal = -out.frame.normal;
        out.frame.tangent = -out.frame.tangent;
        out.frame.bitangent_sign = -out.frame.bitangent_sign;
        out.geometric_normal = -out.geometric_normal;
    }
    return out;
}
