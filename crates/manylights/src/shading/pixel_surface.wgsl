// The surface a pixel sees through a visibility id (draw and triangle), as the compute passes that
// shade raster output rebuild it: the triangle met by the pixel's camera ray, with texture and
// position derivatives from the next pixels' rays, its material evaluated and decals applied. The
// visibility-buffer, transmissive and blended passes share it, so a surface shades alike in each.
#include "shading/shade.wgsl"
#include "shading/triangle_surface.wgsl"
#include "shading/draws.wgsl"

struct PixelSurface {
    // Material and decals: what the shading core lights.
    shading: ShadingInput,
    // Relative to the camera.
    triangle: TriangleSurface,
}

fn pixel_surface(visibility_id: u32, pixel: vec2<f32>) -> PixelSurface {
    let ray = camera_ray(pixel);
    let draw = draws[find_draw(visibility_id)];
    let eye = frame.world_from_view[3].xyz;
    let surface = triangle_surface(
        draw,
        visibility_id - draw.first_visibility_id,
        eye,
        ray,
        camera_ray(pixel + vec2<f32>(1.0, 0.0)),
        camera_ray(pixel + vec2<f32>(0.0, 1.0)),
    );
    let position = surface.relative_position + eye;
    var s = evaluate_material(materials[draw.material], surface.frame, surface.g, surface.vertex_color, position, -ray.dir);
    s.ray_normal = surface.geometric_normal;
    s.ray_clearance = surface_clearance(surface.relative_position);
    // The medium's thickness is given in the mesh's units.
    s.thickness *= draw_scale(draw);
    return PixelSurface(apply_decals(s, surface.dp), surface);
}
