//! Skins and morph targets from glTF (`scene::pose`, `passes/deform.wgsl`): a bar written here as a
//! glTF file, skinned to two joints (the upper one bending) and with a morph target shearing it,
//! both animated. Its vertices are where glTF says at a given time; the GPU's pose renders, shadows
//! and traces as the same bar posed on the CPU, at two times; every frame's ray hierarchy holds the
//! posed bar; and its motion blurs as it moves.

mod common;

use common::*;
use glam::{Mat4, Quat, Vec3, Vec4};
use manylights::{
    renderer::FRAME_INTERVAL,
    scene::{Camera, Instance, Material, Scene, Sun, Vertex},
    settings::{LightMethod, PipelineKind, RaySettings, RenderConfig, SunShadows},
};

/// Rows of the bar's sides, from y = 0 to y = 2.
const ROWS: usize = 8;
/// The upper joint's turn at the end of the 1 s animation, about Z, and the morph target's shear of
/// the top (along +X, growing with height).
const BEND: f32 = std::f32::consts::FRAC_PI_3;
const SHEAR: f32 = 0.3;

fn f32_bytes(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
    values.into_iter().flat_map(f32::to_le_bytes).collect()
}

/// The bar's glTF: four sides of a 0.5 m square column 2 m tall, skinned to a root joint at the
/// origin and a joint 1 m up (weights blending from one to the other between 0.5 and 1.5 m), with
/// one morph target; its node's own translation, which glTF says a skinned mesh ignores, is far off.
/// The animation turns the upper joint by `BEND` and raises the morph weight from 0 to 1 over 1 s.
fn bar_gltf() -> String {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut joints = Vec::new();
    let mut weights = Vec::new();
    let mut shear = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    let sides = [(Vec3::X, Vec3::Z), (Vec3::Z, Vec3::NEG_X), (Vec3::NEG_X, Vec3::NEG_Z), (Vec3::NEG_Z, Vec3::X)];
    for (normal, along) in sides {
        let first = positions.len() as u32;
        for row in 0..=ROWS {
            let y = 2.0 * row as f32 / ROWS as f32;
            let upper = ((y - 0.5) / 1.0).clamp(0.0, 1.0);
            for side in [-0.25f32, 0.25] {
                positions.push(normal * 0.25 + along * side + Vec3::Y * y);
                normals.push(normal);
                joints.extend([0u8, 1, 0, 0]);
                weights.extend([1.0 - upper, upper, 0.0, 0.0]);
                shear.push(Vec3::X * SHEAR * y / 2.0);
            }
        }
        for row in 0..ROWS as u32 {
            let a = first + 2 * row;
            indices.extend([a, a + 3, a + 1, a, a + 2, a + 3]);
        }
    }
    let vertex_count = positions.len();
    let mut buffer = Vec::new();
    let mut views = Vec::new();
    let mut view = |bytes: Vec<u8>| {
        views.push(serde_json::json!({ "buffer": 0, "byteOffset": buffer.len(), "byteLength": bytes.len() }));
        buffer.extend(bytes);
        views.len() - 1
    };
    let v3 = |v: &[Vec3]| f32_bytes(v.iter().flat_map(|v| v.to_array()));
    let positions_view = view(v3(&positions));
    let normals_view = view(v3(&normals));
    let joints_view = view(joints);
    let weights_view = view(f32_bytes(weights));
    let shear_view = view(v3(&shear));
    let indices_view = view(indices.iter().flat_map(|i| i.to_le_bytes()).collect());
    let inverse_bind = [Mat4::IDENTITY, Mat4::from_translation(Vec3::NEG_Y)];
    let inverse_bind_view = view(f32_bytes(inverse_bind.iter().flat_map(|m| m.to_cols_array())));
    let times_view = view(f32_bytes([0.0, 1.0]));
    let turns_view = view(f32_bytes([Quat::IDENTITY, Quat::from_rotation_z(BEND)].iter().flat_map(|q| q.to_array())));
    let weights_key_view = view(f32_bytes([0.0, 1.0]));
    let (min, max) = positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let accessor = |view: usize, component: u32, count: usize, kind: &str| serde_json::json!({ "bufferView": view, "componentType": component, "count": count, "type": kind });
    let mut positions_accessor = accessor(positions_view, 5126, vertex_count, "VEC3");
    positions_accessor["min"] = serde_json::json!(min.to_array());
    positions_accessor["max"] = serde_json::json!(max.to_array());
    let accessors = vec![
        positions_accessor,
        accessor(normals_view, 5126, vertex_count, "VEC3"),
        accessor(joints_view, 5121, vertex_count, "VEC4"),
        accessor(weights_view, 5126, vertex_count, "VEC4"),
        accessor(shear_view, 5126, vertex_count, "VEC3"),
        accessor(indices_view, 5125, indices.len(), "SCALAR"),
        accessor(inverse_bind_view, 5126, 2, "MAT4"),
        serde_json::json!({ "bufferView": times_view, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0.0], "max": [1.0] }),
        accessor(turns_view, 5126, 2, "VEC4"),
        accessor(weights_key_view, 5126, 2, "SCALAR"),
    ];
    let data = base64::encode(&buffer);
    serde_json::json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0, 1] }],
        "nodes": [
            { "name": "bar", "mesh": 0, "skin": 0, "translation": [5.0, 5.0, 5.0] },
            { "name": "root", "children": [2] },
            { "name": "tip", "translation": [0.0, 1.0, 0.0] },
        ],
        "meshes": [{
            "name": "bar",
            "weights": [0.0],
            "primitives": [{
                "attributes": { "POSITION": 0, "NORMAL": 1, "JOINTS_0": 2, "WEIGHTS_0": 3 },
                "indices": 5,
                "material": 0,
                "targets": [{ "POSITION": 4 }],
            }],
        }],
        "materials": [{ "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.7, 0.6, 1.0], "metallicFactor": 0.0 }, "doubleSided": true }],
        "skins": [{ "joints": [1, 2], "inverseBindMatrices": 6 }],
        "animations": [{
            "channels": [
                { "sampler": 0, "target": { "node": 2, "path": "rotation" } },
                { "sampler": 1, "target": { "node": 0, "path": "weights" } },
            ],
            "samplers": [{ "input": 7, "output": 8 }, { "input": 7, "output": 9 }],
        }],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{ "byteLength": buffer.len(), "uri": format!("data:application/octet-stream;base64,{data}") }],
    })
    .to_string()
}

/// The bar loaded from its file, on a floor under the sun, and a camera seeing it and its shadow.
fn bar_scene() -> (Scene, Camera) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bar.gltf");
    std::fs::write(&path, bar_gltf()).unwrap();
    let mut scene = manylights::scene::gltf::import(&path).unwrap();
    let floor = scene.meshes.len();
    scene.meshes.push(quad_mesh());
    scene.materials.push(Material { base_color_factor: Vec4::ONE, metallic_factor: 0.0, roughness_factor: 1.0, ..Default::default() });
    for p in &mut scene.meshes[floor].primitives {
        p.material = scene.materials.len() - 1;
    }
    let face_up = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    scene.instances.push(Instance {
        mesh: floor,
        world_from_local: Mat4::from_scale_rotation_translation(Vec3::new(6.0, 6.0, 1.0), face_up, Vec3::ZERO),
    });
    scene.sun = Some(Sun { direction: Vec3::new(0.6, -0.7, 0.4), color: Vec3::ONE, illuminance: 3.0 });
    scene.ambient = Vec3::splat(0.05);
    let camera = Camera::look_at("side", Vec3::new(1.5, 2.0, -3.5), Vec3::new(-0.2, 0.9, 0.0), 50f32.to_radians(), 0.1);
    (scene, camera)
}

/// The same scene with the bar posed to `time` on the CPU and nothing posing it on the GPU.
fn posed_on_the_cpu(scene: &Scene, time: f32) -> Scene {
    let mut twin = Scene { deformers: Vec::new(), animation: None, ..scene.clone() };
    for deformer in &scene.deformers {
        let mesh = &mut twin.meshes[deformer.mesh];
        let rest: Vec<Vertex> = mesh.primitives.iter().flat_map(|p| p.vertices.clone()).collect();
        let mut posed = deformer.deformed(&rest, time, scene.animation.as_ref()).into_iter();
        for v in mesh.primitives.iter_mut().flat_map(|p| &mut p.vertices) {
            *v = posed.next().unwrap();
        }
    }
    twin
}

fn config(pipeline: PipelineKind) -> RenderConfig {
    RenderConfig {
        pipeline,
        rays: RaySettings { sun_shadows: SunShadows::Hard, ..common::config(WIDTH, HEIGHT, LightMethod::Off).rays },
        ..common::config(WIDTH, HEIGHT, LightMethod::Off)
    }
}

#[test]
fn the_bar_is_posed_where_gltf_says_by_its_joints_and_morph_weights() {
    let (scene, _) = bar_scene();
    let [deformer] = &scene.deformers[..] else { panic!("{:?}", scene.deformers.len()) };
    let bar = scene.instances.iter().find(|i| i.mesh == deformer.mesh).unwrap();
    assert_eq!(bar.world_from_local, Mat4::IDENTITY, "a skinned mesh's node transform is ignored");
    let rest: Vec<Vertex> = scene.meshes[deformer.mesh].primitives.iter().flat_map(|p| p.vertices.clone()).collect();
    let animation = scene.animation.as_ref().expect("the joints' animation");
    assert!(animation.instances.is_empty(), "the skinned instance is placed by its joints, not its node");
    for time in [0.25f32, 0.8] {
        let posed = deformer.deformed(&rest, time, Some(animation));
        // The top of the bar follows the upper joint alone: sheared by the weight, then turned by
        // the joint's angle about its pivot 1 m up.
        let turn = Mat4::from_translation(Vec3::Y) * Mat4::from_rotation_z(BEND * time) * Mat4::from_translation(Vec3::NEG_Y);
        for (v, p) in rest.iter().zip(&posed).filter(|(v, _)| v.position[1] == 2.0) {
            let expected = turn.transform_point3(Vec3::from(v.position) + Vec3::X * SHEAR * time);
            assert!((Vec3::from(p.position) - expected).length() < 1e-5, "{:?} at {time}: {:?}, not {expected}", v.position, p.position);
        }
        // The foot follows the root, which stays: sheared by nothing, moved by nothing.
        for (v, p) in rest.iter().zip(&posed).filter(|(v, _)| v.position[1] == 0.0) {
            assert_eq!(v.position, p.position);
        }
    }
}

#[test]
fn the_gpu_poses_the_bar_as_the_cpu_does_for_the_raster_the_shadows_and_the_rays() {
    let (scene, camera) = bar_scene();
    let differing = |a: &manylights::renderer::Image<[f32; 4]>, b: &manylights::renderer::Image<[f32; 4]>| {
        a.pixels.iter().zip(&b.pixels).filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-3)).count()
    };
    let pixels = (WIDTH * HEIGHT) as usize;
    let mut images = Vec::new();
    for (pipeline, time) in [(PipelineKind::Visbuffer, 0.3), (PipelineKind::Deferred, 0.85), (PipelineKind::Forward, 0.85)] {
        let mut gpu = renderer(&scene, config(pipeline));
        gpu.validate_ray_hierarchy = true;
        gpu.time = time;
        gpu.render(&camera).unwrap();
        let posed = gpu.read_hdr().unwrap();
        let reference = render_with(&posed_on_the_cpu(&scene, time), &camera, config(pipeline)).1;
        // Rounding differs between the GPU's blend and the CPU's: a pixel may flip where an edge
        // of the bar or its shadow crosses its centre.
        let off = differing(&posed, &reference);
        assert!(off * 500 <= pixels, "{} at {time}: {off} pixels differ from the bar posed on the CPU", pipeline.name());
        images.push(posed);
    }
    // The two times pose it differently, and the comparison sees it.
    let moved = differing(&images[0], &images[1]);
    assert!(moved * 50 >= pixels, "only {moved} pixels differ between 0.3 s and 0.85 s");
}

#[test]
fn every_frame_traces_the_bar_posed_at_its_own_time() {
    let (scene, camera) = bar_scene();
    let mut renderer = renderer(&scene, config(PipelineKind::Visbuffer));
    renderer.validate_ray_hierarchy = true;
    renderer.time = 0.2;
    renderer.render_frames(&camera, 4).unwrap();
    let last = renderer.time - FRAME_INTERVAL;
    renderer.check_ray_hierarchy(1, last).unwrap();
    let stale = renderer.check_ray_hierarchy(1, last - 10.0 * FRAME_INTERVAL).unwrap_err().to_string();
    assert!(stale.contains("off its deformation"), "{stale}");
}

#[test]
fn the_raster_culls_the_bar_by_its_posed_box() {
    let (scene, side) = bar_scene();
    // Looking away from the bar over the floor's far corner: only the floor is drawn.
    let away = Camera::look_at("away", Vec3::new(4.0, 1.0, 4.0), Vec3::new(6.0, 0.0, 6.0), 50f32.to_radians(), 0.1);
    // A narrow view of where the bent bar's top reaches at the end of its bend, left of the
    // straight bar's box: the bar is drawn there only when bent.
    let bent_top = Camera::look_at("bent top", Vec3::new(-0.8, 1.7, -3.0), Vec3::new(-0.8, 1.7, 0.0), 8f32.to_radians(), 0.1);
    let mut gpu = renderer(&scene, config(PipelineKind::Visbuffer));
    for (camera, time, drawn) in [(&side, 0.5, 2), (&away, 0.5, 1), (&bent_top, 0.0, 0), (&bent_top, 0.95, 1)] {
        gpu.time = time;
        gpu.render(camera).unwrap();
        assert_eq!(gpu.scene.drawn_count(), drawn, "{} at {time}", camera.name);
    }
    // The bent bar drawn there is the bar posed on the CPU, and fills much of the view, which
    // shows no bar at rest.
    gpu.time = 0.95;
    gpu.render(&bent_top).unwrap();
    let posed = gpu.read_hdr().unwrap();
    let differing = |a: &manylights::renderer::Image<[f32; 4]>, b: &manylights::renderer::Image<[f32; 4]>| {
        a.pixels.iter().zip(&b.pixels).filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-3)).count()
    };
    let reference = render_with(&posed_on_the_cpu(&scene, 0.95), &bent_top, config(PipelineKind::Visbuffer)).1;
    let at_rest = render_with(&posed_on_the_cpu(&scene, 0.0), &bent_top, config(PipelineKind::Visbuffer)).1;
    let pixels = (WIDTH * HEIGHT) as usize;
    let (off, bar) = (differing(&posed, &reference), differing(&posed, &at_rest));
    assert!(off * 500 <= pixels, "{off} pixels differ from the bar posed on the CPU");
    assert!(bar * 10 >= pixels, "the bar covers only {bar} pixels of the view");
}
