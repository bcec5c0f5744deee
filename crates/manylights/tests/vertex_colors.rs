//! Vertex colours (glTF's `COLOR_0`): they multiply the material's base colour and alpha wherever a
//! surface is shaded — the visibility-buffer resolve, the deferred G-buffer, forward fragments,
//! transparent surfaces and reflection hits — and in every alpha test; the importer reads each
//! encoding glTF allows.

mod common;

use common::*;
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use manylights::{
    renderer::Image,
    scene::{AlphaMode, Camera, Instance, Material, Mesh, Scene, Vertex},
    settings::{LightMethod, PipelineKind, RaySettings, RenderConfig},
};

/// `quad_mesh` with each vertex's colour from its local (x, y).
fn colored_quad(color: impl Fn(Vec2) -> Vec4) -> Mesh {
    let mut quad = quad_mesh();
    for v in &mut quad.primitives[0].vertices {
        v.color = Vertex::color_from(color(Vec2::new(v.position[0], v.position[1])).to_array());
    }
    quad
}

/// An affine colour over the quad, so that interpolation across either triangle is exact.
fn gradient(p: Vec2) -> Vec4 {
    Vec4::new(0.5 + 0.4 * p.x, 0.5 + 0.4 * p.y, 0.25, 1.0)
}

/// The wall point (local quad coordinates, the wall being scaled by 10) under pixel (x, y) of
/// `wall_scene`'s camera.
fn wall_local(x: u32, y: u32) -> Vec2 {
    let ndc = Vec2::new((x as f32 + 0.5) / WIDTH as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / HEIGHT as f32 * 2.0);
    let half_height = 30f32.to_radians().tan() * 4.0;
    Vec2::new(ndc.x * half_height * WIDTH as f32 / HEIGHT as f32, ndc.y * half_height) / 10.0
}

fn frame(scene: &Scene, camera: &Camera, pipeline: PipelineKind, rays: RaySettings) -> Image<[f32; 4]> {
    render_with(scene, camera, RenderConfig { pipeline, rays, ..config(WIDTH, HEIGHT, LightMethod::Brute) }).1
}

fn rgb(p: [f32; 4]) -> Vec3 {
    Vec4::from(p).truncate()
}

#[test]
fn vertex_colours_interpolate_across_triangles_and_multiply_the_base_colour_in_every_pipeline() {
    let base = Vec4::new(0.5, 1.0, 0.8, 1.0);
    let (mut scene, camera) = wall_scene(Vec::new());
    scene.meshes[0] = colored_quad(gradient);
    scene.materials[0] = Material { base_color_factor: base, unlit: true, ..Default::default() };
    let pixels = [(WIDTH / 2, HEIGHT / 2), (20, 15), (230, 20), (40, 130), (200, 120), (128, 10)];
    for pipeline in PipelineKind::ALL {
        let image = frame(&scene, &camera, pipeline, RaySettings::default());
        for (x, y) in pixels {
            let expected = (base * gradient(wall_local(x, y))).truncate();
            let got = rgb(pixel(&image, x, y));
            // The deferred G-buffer keeps the base colour in 8-bit sRGB.
            assert!((got - expected).abs().max_element() < 5e-3, "{} at ({x}, {y}): {got}, not {expected}", pipeline.name());
        }
    }
}

/// A mirror floor seen from above, reflecting a panel outside the view, and a half-transparent pane
/// in front of the floor; ambient light and a point light. `tint` gives each surface its colour and
/// alpha either as its vertices' colour (over a white, opaque base) or as its base colour factor.
fn tinted_scene(as_vertex_color: bool) -> (Scene, Camera) {
    let (floor_tint, panel_tint, pane_tint) = (Vec4::new(0.9, 0.6, 0.3, 1.0), Vec4::new(0.2, 0.7, 0.4, 1.0), Vec4::new(0.3, 0.4, 1.0, 0.5));
    let material = |tint: Vec4, metallic: f32, roughness: f32, alpha_mode: AlphaMode| Material {
        base_color_factor: if as_vertex_color { Vec4::ONE } else { tint },
        metallic_factor: metallic,
        roughness_factor: roughness,
        alpha_mode,
        ..Default::default()
    };
    let mesh = |tint: Vec4, material: usize| {
        let mut quad = if as_vertex_color { colored_quad(|_| tint) } else { quad_mesh() };
        quad.primitives[0].material = material;
        quad
    };
    let scene = Scene {
        meshes: vec![mesh(floor_tint, 0), mesh(panel_tint, 1), mesh(pane_tint, 2)],
        materials: vec![
            material(floor_tint, 1.0, 0.0, AlphaMode::Opaque),
            material(panel_tint, 0.0, 1.0, AlphaMode::Opaque),
            material(pane_tint, 0.0, 0.5, AlphaMode::Blend),
        ],
        instances: vec![
            Instance {
                mesh: 0,
                world_from_local: Mat4::from_scale_rotation_translation(
                    Vec3::new(10.0, 10.0, 1.0),
                    Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2),
                    Vec3::ZERO,
                ),
            },
            Instance {
                mesh: 1,
                world_from_local: Mat4::from_scale_rotation_translation(Vec3::splat(4.0), Quat::IDENTITY, Vec3::new(0.0, 7.0, -6.0)),
            },
            Instance {
                mesh: 2,
                world_from_local: Mat4::from_scale_rotation_translation(Vec3::splat(0.5), Quat::IDENTITY, Vec3::new(0.3, 0.5, 1.0)),
            },
        ],
        lights: vec![point_light(Vec3::new(0.5, 1.0, 1.5), 4.0, 5.0)],
        ambient: Vec3::splat(0.3),
        ..Default::default()
    };
    (scene, Camera::look_at("down", Vec3::new(0.0, 2.0, 4.0), Vec3::ZERO, 40f32.to_radians(), 0.1))
}

#[test]
fn a_vertex_colour_shades_as_the_same_base_colour_in_every_pipeline_pane_and_reflection() {
    let rays = RaySettings { reflection_bounces: 1, ..Default::default() };
    let (by_vertex, camera) = tinted_scene(true);
    let (by_factor, _) = tinted_scene(false);
    let mut white = by_factor.clone();
    for m in &mut white.materials {
        m.base_color_factor = Vec4::ONE;
    }
    for pipeline in PipelineKind::ALL {
        let name = pipeline.name();
        let a = frame(&by_vertex, &camera, pipeline, rays);
        let b = frame(&by_factor, &camera, pipeline, rays);
        let difference = max_abs_difference(&a, &b);
        assert!(difference < 2e-3, "{name}: vertex colours and base colours differ by {difference}");
        let untinted = max_abs_difference(&a, &frame(&white, &camera, pipeline, rays));
        assert!(untinted > 0.1, "{name}: the tints changed the image by only {untinted}");
    }
}

#[test]
fn a_vertex_alpha_cuts_alpha_masked_surfaces_in_every_pipeline() {
    // A masked wall whose vertex alpha runs from 0.1 (left edge) to 0.9 (right edge), cut at 0.5:
    // its left half is a hole onto a red wall behind it.
    let (mut scene, camera) = wall_scene(Vec::new());
    scene.meshes[0] = colored_quad(|p| Vec4::new(1.0, 1.0, 1.0, 0.5 + 0.4 * p.x));
    scene.materials[0] = Material { unlit: true, alpha_mode: AlphaMode::Mask { cutoff: 0.5 }, ..Default::default() };
    let mut back = quad_mesh();
    back.primitives[0].material = 1;
    scene.meshes.push(back);
    scene.materials.push(Material { base_color_factor: Vec4::new(1.0, 0.0, 0.0, 1.0), unlit: true, ..Default::default() });
    scene.instances.push(Instance {
        mesh: 1,
        world_from_local: Mat4::from_scale_rotation_translation(Vec3::new(20.0, 20.0, 1.0), Quat::IDENTITY, Vec3::new(0.0, 0.0, -1.0)),
    });
    for pipeline in PipelineKind::ALL {
        let image = frame(&scene, &camera, pipeline, RaySettings::default());
        for (x, y) in [(20, 30), (100, 100), (156, 40), (240, 120)] {
            let expected = if wall_local(x, y).x < 0.0 { Vec3::X } else { Vec3::ONE };
            let got = rgb(pixel(&image, x, y));
            assert!((got - expected).abs().max_element() < 5e-3, "{} at ({x}, {y}): {got}, not {expected}", pipeline.name());
        }
    }
}

/// A glTF triangle without normals (so flat-shaded copies of its vertices) with COLOR_0 as
/// `color_accessor`'s JSON over `data`, `stride` bytes apart, after the positions.
fn triangle_with_colors(color_accessor: &str, data: &[u8], stride: usize) -> Result<Scene, manylights::Error> {
    let positions: Vec<u8> = [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
    let mut buffer = positions.clone();
    buffer.extend_from_slice(data);
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "COLOR_0": 1}}}}]}}],
        "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": {}, "byteStride": {stride}}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
                      {{"bufferView": 1, "count": 3, {color_accessor}}}]}}"#,
        buffer.len(),
        base64::encode(&buffer),
        data.len()
    );
    let path = std::env::temp_dir().join(format!("manylights-colors-{}-{}-{stride}.gltf", std::process::id(), data.len()));
    std::fs::write(&path, json).unwrap();
    let scene = manylights::scene::gltf::import(&path);
    std::fs::remove_file(&path).ok();
    scene
}

#[test]
fn the_importer_reads_every_encoding_of_vertex_colours() {
    let colors = |scene: &Scene| scene.meshes[0].primitives[0].vertices.iter().map(|v| v.color).collect::<Vec<_>>();
    let unorm8: Vec<u8> = vec![255, 0, 51, 0, 0, 255, 0, 0, 0, 0, 255, 0];
    // Vertex attributes' elements start 4-byte aligned: RGB bytes are 4 apart.
    let scene = triangle_with_colors(r#""componentType": 5121, "normalized": true, "type": "VEC3""#, &unorm8, 4).unwrap();
    let h = u16::MAX;
    assert_eq!(colors(&scene), vec![[h, 0, 13107, h], [0, h, 0, h], [0, 0, h, h]], "RGB unorm8 gets an alpha of 1");
    let floats: Vec<u8> =
        [[1.0f32, 0.5, 0.25, 0.0], [0.0, 0.0, 0.0, 1.0], [2.0, -1.0, 0.5, 0.5]].iter().flatten().flat_map(|f| f.to_le_bytes()).collect();
    let scene = triangle_with_colors(r#""componentType": 5126, "type": "VEC4""#, &floats, 16).unwrap();
    assert_eq!(colors(&scene), vec![[h, 32768, 16384, 0], [0, 0, 0, h], [h, 0, 32768, 32768]], "RGBA floats, clamped to 0..1");
    let unorm16: Vec<u8> =
        [[65535u16, 0, 1000, 65535], [1, 2, 3, 4], [0, 0, 0, 0]].iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    let scene = triangle_with_colors(r#""componentType": 5123, "normalized": true, "type": "VEC4""#, &unorm16, 8).unwrap();
    assert_eq!(colors(&scene), vec![[h, 0, 1000, h], [1, 2, 3, 4], [0; 4]], "RGBA unorm16, as they are");
    let error = triangle_with_colors(r#""componentType": 5120, "normalized": true, "type": "VEC4""#, &unorm8, 4).unwrap_err().to_string();
    assert!(error.contains("COLOR_0") && error.contains("glTF allows"), "{error}");
    let error = triangle_with_colors(r#""componentType": 5126, "type": "VEC2""#, &floats[..24], 8).unwrap_err().to_string();
    assert!(error.contains("COLOR_0") && error.contains("Vec3 or Vec4"), "{error}");
}
