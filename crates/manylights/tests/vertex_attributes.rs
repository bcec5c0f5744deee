//! Vertex attributes beyond position and frame, wherever a surface is shaded — the visibility-buffer
//! resolve, the deferred G-buffer, forward fragments, transparent surfaces and reflection hits — and
//! in every alpha test:
//! - colours (glTF's `COLOR_0`) multiply the material's base colour and alpha; the importer reads
//!   each encoding glTF allows;
//! - a texture may read the second set of coordinates (`TEXCOORD_1`), as glTF's `texCoord` says.

mod common;

use common::*;
use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use manylights::{
    renderer::Image,
    scene::{AlphaMode, Camera, Instance, Material, Mesh, Scene, Sun, Texture, TextureRef, Vertex, Wrap},
    settings::{LightMethod, PipelineKind, RaySettings, RenderConfig, SunShadows},
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
    import_gltf_json(&json)
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

/// A 4 × 4 image of distinct texels; alpha 0.2 in a checker, 1 elsewhere.
fn checker(name: &str, seed: u8) -> Texture {
    let rgba8 = (0..16u8)
        .flat_map(|i| {
            let alpha = if (i + i / 4) % 2 == 0 { 255 } else { 51 };
            [40 + 13 * i, 230 - 11 * i, seed.wrapping_add(i.wrapping_mul(29)), alpha]
        })
        .collect();
    Texture { name: name.into(), width: 4, height: 4, rgba8 }
}

/// Where a texture's coordinates run as the quad's own, the other set takes a different map of the
/// quad, so that reading the wrong set shows.
fn other_uv([u, v]: [f32; 2]) -> [f32; 2] {
    [0.3 * v + 0.1, 0.7 - 0.5 * u]
}

/// `tinted_scene`'s mirror floor, reflected panel and blended pane, with a masked panel casting a sun
/// shadow onto the floor, every material textured: base colours (with the mask's alpha), a normal
/// map on the panel, occlusion and an emissive texture on the floor. Each texture reads the quad's
/// own coordinates from `TEXCOORD_1` where `second_set`, else from `TEXCOORD_0`; `read_set` is the set
/// the materials name.
fn textured_scene(second_set: bool, read_set: u32) -> (Scene, Camera) {
    let (mut scene, camera) = tinted_scene(false);
    for mesh in &mut scene.meshes {
        for v in &mut mesh.primitives[0].vertices {
            let own = [v.u, v.v];
            let [u, w] = if second_set { other_uv(own) } else { own };
            (v.u, v.v) = (u, w);
            v.uv1 = if second_set { own } else { other_uv(own) };
        }
    }
    let mut masked = scene.meshes[1].clone();
    masked.primitives[0].material = 3;
    scene.meshes.push(masked);
    scene.materials.push(Material { alpha_mode: AlphaMode::Mask { cutoff: 0.5 }, ..scene.materials[1].clone() });
    scene.instances.push(Instance {
        mesh: 3,
        world_from_local: Mat4::from_scale_rotation_translation(Vec3::splat(0.8), Quat::IDENTITY, Vec3::new(-1.2, 1.0, 0.5)),
    });
    scene.sun = Some(Sun { direction: Vec3::new(0.3, -1.0, -0.4).normalize(), color: Vec3::ONE, illuminance: 2.0 });
    scene.textures = vec![checker("colour", 7), checker("data", 101)];
    let texture = |index| Some(TextureRef { tex_coord: read_set, ..TextureRef::new(index, Wrap::Repeat, Wrap::Repeat) });
    for material in &mut scene.materials {
        material.base_color_texture = texture(0);
    }
    scene.materials[0].occlusion_texture = texture(1);
    scene.materials[0].emissive_texture = texture(0);
    scene.materials[0].emissive_factor = Vec3::splat(0.2);
    scene.materials[1].normal_texture = texture(1);
    (scene, camera)
}

#[test]
fn textures_on_the_second_coordinates_read_them_in_every_pipeline_pane_mask_shadow_and_reflection() {
    let rays = RaySettings { reflection_bounces: 1, sun_shadows: SunShadows::Hard, ..Default::default() };
    let (first, camera) = textured_scene(false, 0);
    let second = textured_scene(true, 1).0;
    let wrong = textured_scene(true, 0).0;
    for pipeline in PipelineKind::ALL {
        let name = pipeline.name();
        let a = frame(&first, &camera, pipeline, rays);
        let difference = max_abs_difference(&a, &frame(&second, &camera, pipeline, rays));
        assert!(difference < 2e-3, "{name}: textures read through TEXCOORD_1 differ from TEXCOORD_0's by {difference}");
        let misread = max_abs_difference(&a, &frame(&wrong, &camera, pipeline, rays));
        assert!(misread > 0.1, "{name}: reading the other set changed the image by only {misread}");
    }
}

/// A glTF of three triangles in the z = 0 plane facing +Z, the second without TEXCOORD_1, each with
/// a material of `materials` (JSON) and one image; TEXCOORD_0 runs u along +X, TEXCOORD_1 along +Y.
fn triangles_with_two_sets(materials: &str) -> Result<Scene, manylights::Error> {
    let floats = |values: &[[f32; 3]]| values.iter().flatten().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
    let mut buffer = floats(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    buffer.extend(floats(&[[0.0, 0.0, 1.0]; 3]));
    let pairs = |values: &[[f32; 2]]| values.iter().flatten().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
    buffer.extend(pairs(&[[0.0, 1.0], [1.0, 1.0], [0.0, 0.0]]));
    buffer.extend(pairs(&[[0.0, 0.5], [0.0, 0.0], [1.0, 0.5]]));
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
        "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2, "TEXCOORD_1": 3}}, "material": 0}},
                                   {{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}, "material": 1}},
                                   {{"attributes": {{"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2, "TEXCOORD_1": 3}}, "material": 2}}]}}],
        "extensionsUsed": ["KHR_materials_clearcoat", "KHR_texture_transform"],
        "materials": [{materials}], "textures": [{{"source": 0}}],
        "images": [{{"uri": "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg=="}}],
        "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}],
        "bufferViews": [{{"buffer": 0, "byteLength": 72}}, {{"buffer": 0, "byteOffset": 72, "byteLength": 48}}],
        "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
                      {{"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"}},
                      {{"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}},
                      {{"bufferView": 1, "byteOffset": 24, "componentType": 5126, "count": 3, "type": "VEC2"}}]}}"#,
        buffer.len(),
        base64::encode(&buffer),
    );
    import_gltf_json(&json)
}

#[test]
fn the_importer_reads_the_second_coordinates_and_the_sets_textures_name() {
    let scene = triangles_with_two_sets(
        r#"{"normalTexture": {"index": 0, "texCoord": 1}, "occlusionTexture": {"index": 0, "texCoord": 1},
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 2}}},
           {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"texCoord": 1}}}}},
           {"extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1.0, "clearcoatNormalTexture": {"index": 0, "texCoord": 1}}}}"#,
    )
    .unwrap();
    let (with_set, without_set) = (&scene.meshes[0].primitives[0], &scene.meshes[0].primitives[1]);
    assert_eq!(with_set.vertices.iter().map(|v| v.uv1).collect::<Vec<_>>(), vec![[0.0, 0.5], [0.0, 0.0], [1.0, 0.5]]);
    let set = |t: Option<TextureRef>| t.map(|t| t.tex_coord);
    let first = &scene.materials[0];
    // Occlusion and the normal map read TEXCOORD_1; a set past the second reads TEXCOORD_0.
    assert_eq!((set(first.normal_texture), set(first.occlusion_texture), set(first.base_color_texture)), (Some(1), Some(1), Some(0)));
    assert_eq!(set(scene.materials[1].base_color_texture), Some(1), "the transform's texCoord overrides");
    // The normal maps' tangents follow their set, the surface's or else the clear coat's:
    // TEXCOORD_1's u runs along +Y.
    for v in with_set.vertices.iter().chain(&scene.meshes[0].primitives[2].vertices) {
        assert!(Vec3::from_slice(&v.tangent[..3]).abs_diff_eq(Vec3::Y, 1e-5), "{:?}", v.tangent);
    }
    // A primitive without the set its material names reads TEXCOORD_0 there.
    assert!(without_set.vertices.iter().all(|v| v.uv1 == [v.u, v.v]), "{:?}", without_set.vertices);
}
