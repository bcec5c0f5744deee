// The surface every pipeline hands to the shading core: built by the visibility-buffer resolve, the
// G-buffer decode and forward fragments. Decals modify it before `shade`.

struct ShadingInput {
    position: vec3<f32>,
    // Shading normal (after normal mapping), unit, facing the viewer's side.
    normal: vec3<f32>,
    // Unit vector from the surface towards the eye.
    view_dir: vec3<f32>,
    base_color: vec3<f32>,
    alpha: f32,
    metallic: f32,
    // Perceptual roughness (alpha = roughness²).
    roughness: f32,
    emissive: vec3<f32>,
    // Where rays leave the surface (shadow rays towards local lights): its geometric normal on the
    // viewer's side, and how far off the surface `position` may lie — `surface_clearance` for a
    // position rebuilt from depth or interpolated by the raster, 0 at a ray's hit, which is exact.
    ray_normal: vec3<f32>,
    ray_clearance: f32,
}

// World-space change of the shading position from one pixel to the next in x and y (or, at a ray's
// hit, across its cone): decal textures are sampled with gradients from it (compute has no implicit
// derivatives).
struct PositionGradients {
    ddx: vec3<f32>,
    ddy: vec3<f32>,
}
