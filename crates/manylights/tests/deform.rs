//! Deforming meshes (`scene::deform`, `passes/deform.rs`, `rays/refit.rs`): a sheet waving above a
//! floor under the sun, its vertices moved on the GPU every frame and its BLAS refitted into the copy
//! the frame traces. In test mode every frame's hierarchy is read back and checked — the frame's top
//! level on the copy of its parity, that copy's triangles the sheet deformed to the frame's time,
//! every node bounding its contents — so no frame traced a half-built or stale hierarchy; and the
//! image (raster, shading and ray-traced shadows) equals that of the same sheet deformed on the CPU.

mod common;

use common::*;
use glam::{Mat4, Quat, Vec3, Vec4};
use manylights::{
    renderer::FRAME_INTERVAL,
    scene::{
        deform::{Deformer, Wave},
        Camera, Instance, Material, Mesh, Primitive, Scene, Sun, Vertex,
    },
    settings::RenderConfig,
    settings::{LightMethod, PipelineKind},
    settings::{RaySettings, SunShadows},
};

/// A square sheet of `n`×`n` cells in the XY plane, facing +Z, from −1 to 1.
fn grid_mesh(n: u32) -> Mesh {
    let mut vertices = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32 * 2.0 - 1.0, j as f32 / n as f32 * 2.0 - 1.0);
            vertices.push(Vertex {
                position: [x, y, 0.0],
                u: x * 0.5 + 0.5,
                normal: [0.0, 0.0, 1.0],
                v: 0.5 - y * 0.5,
                tangent: [1.0, 0.0, 0.0, 1.0],
                ..Vertex::default()
            });
        }
    }
    let mut indices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let corner = j * (n + 1) + i;
            indices.extend_from_slice(&[corner, corner + 1, corner + n + 2, corner, corner + n + 2, corner + n + 1]);
        }
    }
    Mesh { name: "sheet".into(), primitives: vec![Primitive { vertices, indices, material: 0 }] }
}

const WAVE: Wave = Wave { amplitude: 0.25, wavelength: 1.0, speed: 1.5, direction: Vec3::X };

/// A floor, a 2 m sheet standing 1.2 m above it facing the sun's side, waving, and a camera seeing
/// both the sheet and its shadow.
fn waving_sheet() -> (Scene, Camera) {
    let white =
        Material { base_color_factor: Vec4::ONE, metallic_factor: 0.0, roughness_factor: 1.0, double_sided: true, ..Default::default() };
    let face_up = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    let scene = Scene {
        meshes: vec![grid_mesh(32), quad_mesh()],
        materials: vec![white],
        instances: vec![
            Instance { mesh: 0, world_from_local: Mat4::from_translation(Vec3::new(0.0, 1.2, 0.0)) },
            Instance { mesh: 1, world_from_local: Mat4::from_scale_rotation_translation(Vec3::new(8.0, 8.0, 1.0), face_up, Vec3::ZERO) },
        ],
        sun: Some(Sun { direction: Vec3::new(0.2, -0.8, -1.0), color: Vec3::ONE, illuminance: 3.0 }),
        ambient: Vec3::splat(0.05),
        deformers: vec![Deformer::wave(0, WAVE)],
        ..Default::default()
    };
    let camera = Camera::look_at("above", Vec3::new(1.5, 4.0, 5.0), Vec3::new(0.0, 0.5, -1.0), 60f32.to_radians(), 0.1);
    (scene, camera)
}

/// The same scene with the sheet deformed to `time` on the CPU and nothing deforming it on the GPU.
fn deformed_on_the_cpu(scene: &Scene, time: f32) -> Scene {
    let mut baked = Scene { deformers: Vec::new(), ..scene.clone() };
    for v in &mut baked.meshes[0].primitives[0].vertices {
        let (p, n) = WAVE.displace(Vec3::from(v.position), Vec3::from(v.normal), time);
        (v.position, v.normal) = (p.to_array(), n.to_array());
    }
    baked
}

fn config(pipeline: PipelineKind) -> RenderConfig {
    RenderConfig {
        pipeline,
        rays: RaySettings { sun_shadows: SunShadows::Hard, ..Default::default() },
        ..common::config(WIDTH, HEIGHT, LightMethod::Off)
    }
}

#[test]
fn every_frame_traces_a_complete_refit_of_its_own_time_from_the_copy_of_its_parity() {
    let (mut scene, camera) = waving_sheet();
    // A second, finer sheet with a wave of its own beside the first: the refit takes both in each
    // dispatch, each with its own primitives.
    scene.meshes.push(grid_mesh(48));
    scene.instances.push(Instance { mesh: 2, world_from_local: Mat4::from_translation(Vec3::new(-2.5, 1.0, -0.5)) });
    let slow = Wave { amplitude: 0.1, wavelength: 0.7, speed: -0.4, direction: Vec3::new(0.6, 0.8, 0.0) };
    scene.deformers.push(Deformer::wave(2, slow));
    let mut renderer = renderer(&scene, config(PipelineKind::Visbuffer));
    renderer.validate_ray_hierarchy = true;
    // Frames submitted back to back, then one by one: each checked right after it.
    renderer.render_frames(&camera, 6).unwrap();
    for _ in 0..3 {
        renderer.render(&camera).unwrap();
    }
    // The check tells stale from current: the last frame (the 9th, parity 0) traced copy 0 at its
    // own time, not copy 1 and not the sheet of a frame earlier.
    let last = renderer.time - FRAME_INTERVAL;
    renderer.check_ray_hierarchy(0, last).unwrap();
    let stale = renderer.check_ray_hierarchy(0, last - FRAME_INTERVAL).unwrap_err().to_string();
    assert!(stale.contains("off its deformation"), "{stale}");
    let other = renderer.check_ray_hierarchy(1, last).unwrap_err().to_string();
    assert!(other.contains("not on copy 1"), "{other}");
}

#[test]
fn a_sheet_deformed_on_the_gpu_looks_and_shadows_as_the_same_sheet_deformed_on_the_cpu() {
    let (scene, camera) = waving_sheet();
    let time = 0.37;
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        let mut gpu = renderer(&scene, config(pipeline));
        gpu.time = time;
        gpu.render(&camera).unwrap();
        let deformed = gpu.read_hdr().unwrap();
        let reference = render_with(&deformed_on_the_cpu(&scene, time), &camera, config(pipeline)).1;
        let at_rest = render_with(&deformed_on_the_cpu(&scene, 0.0), &camera, config(pipeline)).1;
        let differing = |a: &manylights::renderer::Image<[f32; 4]>, b: &manylights::renderer::Image<[f32; 4]>| {
            a.pixels.iter().zip(&b.pixels).filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-3)).count()
        };
        // The GPU's sines and the CPU's round differently: a pixel may flip where a triangle's or a
        // shadow's edge crosses its centre, along the sheet's outline.
        let off = differing(&deformed, &reference);
        let pixels = (WIDTH * HEIGHT) as usize;
        assert!(off * 1000 <= pixels, "{}: {off} pixels differ from the sheet deformed on the CPU", pipeline.name());
        // And the comparison sees the deformation: the sheet at another time looks different.
        let moved = differing(&deformed, &at_rest);
        assert!(moved * 40 >= pixels, "{}: only {moved} pixels differ from the sheet at rest", pipeline.name());
    }
}
