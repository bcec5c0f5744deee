//! glTF extensions that change how geometry and textures are stored (`scene::gltf`): files made from
//! the shared assets by the glTF Transform CLI (`tests/gltf/`, `scripts/make-gltf-test-files.sh`)
//! with meshopt compression, Draco compression, quantized attributes, WebP textures and KTX2 textures
//! in Basis Universal (ETC1S, UASTC) load and render as the files they were made from; and GPU
//! instancing places a mesh at every instance.

mod common;

use std::path::{Path, PathBuf};

use common::*;
use glam::{Mat4, Quat, Vec3};
use manylights::{
    renderer::Image,
    scene::{self, Camera, Scene},
    settings::LightMethod,
};

fn assets() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets")
}

fn test_file(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/gltf").join(name)
}

fn load(path: &Path) -> Scene {
    scene::load_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn frame(scene: &Scene, camera: &Camera) -> Image<[f32; 4]> {
    render_with(scene, camera, config(WIDTH, HEIGHT, LightMethod::Off)).1
}

/// Pixels whose colour differs by more than `tolerance` in some channel.
fn differing(a: &Image<[f32; 4]>, b: &Image<[f32; 4]>, tolerance: f32) -> usize {
    a.pixels.iter().zip(&b.pixels).filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > tolerance)).count()
}

/// Every triangle corner of `scene`, in world space.
fn world_corners(scene: &Scene) -> Vec<Vec3> {
    let mut corners = Vec::new();
    for instance in &scene.instances {
        for p in &scene.meshes[instance.mesh].primitives {
            corners
                .extend(p.indices.iter().map(|&i| instance.world_from_local.transform_point3(Vec3::from(p.vertices[i as usize].position))));
        }
    }
    corners
}

/// The farthest any point of `a` is from all of `b`'s, and the other way round (the Hausdorff
/// distance of the two point sets): the same surface whatever order the files store vertices in
/// (Draco renumbers them).
fn hausdorff(a: &[Vec3], b: &[Vec3]) -> f32 {
    let one_way =
        |a: &[Vec3], b: &[Vec3]| a.iter().map(|p| b.iter().map(|q| p.distance(*q)).fold(f32::INFINITY, f32::min)).fold(0.0, f32::max);
    one_way(a, b).max(one_way(b, a))
}

#[test]
fn compressed_quantized_and_webp_files_render_as_their_originals() {
    // (made file, original, largest distance of a corner from the original's in its diagonals,
    // largest mean difference of a texture's 8-bit values from the original's: Basis Universal's
    // codecs are lossy)
    let cases = [
        ("duck-meshopt.glb", "duck/Duck.glb", 1e-4, 0.0),
        ("duck-draco.glb", "duck/Duck.glb", 1e-4, 0.0),
        ("box_textured-quantized.glb", "box_textured/BoxTextured.glb", 1e-6, 0.0),
        ("box_textured-webp.glb", "box_textured/BoxTextured.glb", 0.0, 0.0),
        ("box_textured-etc1s.glb", "box_textured/BoxTextured.glb", 0.0, 2.5),
        ("box_textured-uastc.glb", "box_textured/BoxTextured.glb", 0.0, 0.5),
    ];
    for (made, original, tolerance, texture_tolerance) in cases {
        let (got, expected) = (load(&test_file(made)), load(&assets().join(original)));
        // As many triangles, their corners where the original's are, within the quantization's rounding.
        let (got_corners, expected_corners) = (world_corners(&got), world_corners(&expected));
        assert_eq!(got_corners.len(), expected_corners.len(), "{made}: corner count");
        let diagonal = expected.bounds().diagonal();
        let far = hausdorff(&got_corners, &expected_corners);
        assert!(far <= tolerance * diagonal + 1e-6, "{made}: a corner is {far} from the original's (diagonal {diagonal})");
        assert_eq!(got.textures.len(), expected.textures.len(), "{made}: textures");
        for (a, b) in got.textures.iter().zip(&expected.textures) {
            assert_eq!((a.width, a.height), (b.width, b.height), "{made}: texture {} size", a.name);
            let mean = a.rgba8.iter().zip(&b.rgba8).map(|(x, y)| f32::from(x.abs_diff(*y))).sum::<f32>() / a.rgba8.len() as f32;
            assert!(mean <= texture_tolerance, "{made}: texture {} is {mean} off the original's on average", a.name);
        }
        // And the images agree: the raster and the shading see the same surface.
        let camera = Camera::framing(&expected.bounds());
        let (got_image, expected_image) = (frame(&got, &camera), frame(&expected, &camera));
        let off = differing(&got_image, &expected_image, 0.02);
        assert!(off * 1000 <= (WIDTH * HEIGHT) as usize, "{made}: {off} pixels differ from {original}'s image");
    }
}

/// A Draco primitive may keep attributes outside its stream, read as usual (here texture
/// coordinates in an accessor with no data, which holds zeros).
#[test]
fn draco_primitives_read_attributes_left_out_of_their_stream() {
    let bytes = std::fs::read(test_file("duck-draco.glb")).unwrap();
    let json_length = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_length]).unwrap();
    let position = json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].as_u64().unwrap() as usize;
    let count = json["accessors"][position]["count"].clone();
    let accessors = json["accessors"].as_array_mut().unwrap();
    accessors.push(serde_json::json!({"componentType": 5126, "count": count, "type": "VEC2"}));
    let zeros = accessors.len() - 1;
    let primitive = &mut json["meshes"][0]["primitives"][0];
    let draco = primitive["extensions"]["KHR_draco_mesh_compression"]["attributes"].as_object_mut().unwrap();
    assert!(draco.remove("TEXCOORD_0").is_some(), "the stream holds texture coordinates");
    primitive["attributes"]["TEXCOORD_0"] = zeros.into();

    let mut chunk = serde_json::to_vec(&json).unwrap();
    chunk.resize(chunk.len().next_multiple_of(4), b' ');
    let binary = &bytes[20 + json_length..];
    let mut glb = Vec::new();
    glb.extend_from_slice(&bytes[..8]);
    glb.extend_from_slice(&((20 + chunk.len() + binary.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(chunk.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&chunk);
    glb.extend_from_slice(binary);
    let path = std::env::temp_dir().join(format!("manylights-draco-outside-{}.glb", std::process::id()));
    std::fs::write(&path, glb).unwrap();

    let (got, original) = (load(&path), load(&test_file("duck-draco.glb")));
    std::fs::remove_file(&path).ok();
    assert_eq!(world_corners(&got), world_corners(&original), "the stream's positions and indices");
    let vertices = || got.meshes.iter().flat_map(|m| &m.primitives).flat_map(|p| &p.vertices);
    assert!(vertices().all(|v| (v.u, v.v) == (0.0, 0.0)), "texture coordinates from the zero accessor");
    let original_uv = original.meshes.iter().flat_map(|m| &m.primitives).flat_map(|p| &p.vertices).any(|v| (v.u, v.v) != (0.0, 0.0));
    assert!(original_uv, "the original's come from the stream");
}

/// `EXT_mesh_gpu_instancing`'s translations, rotations and scales.
type Instancing = (Vec<[f32; 3]>, Vec<[f32; 4]>, Vec<[f32; 3]>);

/// A glTF file of one quad mesh, placed by `nodes` (JSON), with an animation turning node 0.
fn quad_file(nodes: serde_json::Value, instancing: Option<Instancing>) -> PathBuf {
    let floats = |v: &[f32]| v.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
    let mut buffer = floats(&[-1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0]);
    buffer.extend(floats(&[0.0, 0.0, 1.0].repeat(4)));
    buffer.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    let mut views = vec![
        serde_json::json!({ "buffer": 0, "byteOffset": 0, "byteLength": 48 }),
        serde_json::json!({ "buffer": 0, "byteOffset": 48, "byteLength": 48 }),
        serde_json::json!({ "buffer": 0, "byteOffset": 96, "byteLength": 12 }),
    ];
    let mut accessors = vec![
        serde_json::json!({ "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0] }),
        serde_json::json!({ "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" }),
        serde_json::json!({ "bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR" }),
    ];
    let mut add = |data: Vec<u8>, count: usize, kind: &str, buffer: &mut Vec<u8>| {
        buffer.resize(buffer.len().next_multiple_of(4), 0);
        views.push(serde_json::json!({ "buffer": 0, "byteOffset": buffer.len(), "byteLength": data.len() }));
        buffer.extend(data);
        accessors.push(serde_json::json!({ "bufferView": views.len() - 1, "componentType": 5126, "count": count, "type": kind }));
        accessors.len() - 1
    };
    let times = add(floats(&[0.0, 1.0]), 2, "SCALAR", &mut buffer);
    let turns = add(floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.38268343, 0.0, 0.9238795]), 2, "VEC4", &mut buffer);
    let mut nodes = nodes;
    let mut used = vec![];
    if let Some((t, r, s)) = instancing {
        let count = t.len();
        let translation = add(floats(&t.concat()), count, "VEC3", &mut buffer);
        let rotation = add(floats(&r.concat()), count, "VEC4", &mut buffer);
        let scale = add(floats(&s.concat()), count, "VEC3", &mut buffer);
        nodes[0]["extensions"] = serde_json::json!({ "EXT_mesh_gpu_instancing": {
            "attributes": { "TRANSLATION": translation, "ROTATION": rotation, "SCALE": scale } } });
        used.push("EXT_mesh_gpu_instancing");
    }
    let document = serde_json::json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": used,
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": nodes,
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1 }, "indices": 2 }] }],
        "animations": [{
            "channels": [{ "sampler": 0, "target": { "node": 0, "path": "rotation" } }],
            "samplers": [{ "input": times, "output": turns }],
        }],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{ "byteLength": buffer.len(), "uri": format!("data:application/octet-stream;base64,{}", base64::encode(&buffer)) }],
    });
    let path = std::env::temp_dir().join(format!("manylights-instancing-{}-{}.gltf", std::process::id(), used.len()));
    std::fs::write(&path, document.to_string()).unwrap();
    path
}

#[test]
fn gpu_instancing_places_the_mesh_at_every_instance_under_its_moving_node() {
    let translations = vec![[-2.0, 0.0, 0.0], [0.0, 1.0, -1.0], [2.5, -0.5, 0.0]];
    let rotations = vec![[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.38268343, 0.9238795], [0.0, 0.38268343, 0.0, 0.9238795]];
    let scales = vec![[1.0, 1.0, 1.0], [0.5, 0.5, 0.5], [1.0, 2.0, 1.0]];
    let node = serde_json::json!({ "mesh": 0, "translation": [0.0, 0.5, 0.0] });
    let instanced = load(&quad_file(serde_json::json!([node]), Some((translations.clone(), rotations.clone(), scales.clone()))));
    // The twin: the same placements as plain child nodes of the animated node.
    let children: Vec<serde_json::Value> = (0..3)
        .map(|i| serde_json::json!({ "mesh": 0, "translation": translations[i], "rotation": rotations[i], "scale": scales[i] }))
        .collect();
    let mut nodes = vec![serde_json::json!({ "translation": [0.0, 0.5, 0.0], "children": [1, 2, 3] })];
    nodes.extend(children);
    let twin = load(&quad_file(serde_json::Value::Array(nodes), None));
    assert_eq!(instanced.instances.len(), 3, "one instance per EXT_mesh_gpu_instancing entry");
    for (a, b) in instanced.instances.iter().zip(&twin.instances) {
        assert!(a.world_from_local.abs_diff_eq(b.world_from_local, 1e-6), "{} vs {}", a.world_from_local, b.world_from_local);
    }
    let expected = Mat4::from_translation(Vec3::new(0.0, 0.5, 0.0))
        * Mat4::from_scale_rotation_translation(
            Vec3::new(1.0, 2.0, 1.0),
            Quat::from_rotation_y(std::f32::consts::FRAC_PI_4),
            Vec3::new(2.5, -0.5, 0.0),
        );
    assert!(instanced.instances[2].world_from_local.abs_diff_eq(expected, 1e-6));
    // The node's animation moves every instance as it moves the twin's children.
    let (a, b) = (instanced.animation.as_ref().unwrap(), twin.animation.as_ref().unwrap());
    let (moved, twin_moved) = (a.instance_transforms(0.7), b.instance_transforms(0.7));
    assert_eq!(moved.len(), 3);
    for ((i, m), (j, n)) in moved.iter().zip(&twin_moved) {
        assert_eq!(i, j);
        assert!(m.abs_diff_eq(*n, 1e-5), "instance {i} at 0.7 s: {m} vs {n}");
    }
    // And renders as the twin does.
    let camera = Camera::look_at("front", Vec3::new(0.0, 0.5, 8.0), Vec3::new(0.0, 0.5, 0.0), 60f32.to_radians(), 0.1);
    let (got, twin_image) = (frame(&instanced, &camera), frame(&twin, &camera));
    assert_eq!(differing(&got, &twin_image, 1e-4), 0);
    let empty = frame(&Scene { instances: Vec::new(), animation: None, ..instanced.clone() }, &camera);
    assert!(differing(&got, &empty, 0.01) * 20 > (WIDTH * HEIGHT) as usize, "the instances are in the picture");
}
