//! Transparent surfaces (glTF BLEND materials): drawn after the opaque surfaces in every pipeline,
//! blended back to front over what lies behind them, hidden behind opaque surfaces, and lit and
//! decaled by the shading core through the frame's methods — which deferred decals, living in the
//! G-buffer, cannot do.

mod common;

use common::*;
use glam::{Affine3A, Mat4, Vec3, Vec4};
use manylights::{
    gpu::GpuContext,
    renderer::{Image, Renderer},
    scene::{demo::demo_scene, generators, generators::ScatterLights, AlphaMode, Camera, Decal, Instance, Material, Scene},
    settings::RenderConfig,
    settings::{DecalMethod, LightMethod, PipelineKind},
};

const TOLERANCE: f32 = 1e-3;
const WALL_COLOR: Vec3 = AMBIENT_WALL_COLOR;

fn rgb(p: [f32; 4]) -> Vec3 {
    Vec3::new(p[0], p[1], p[2])
}

/// A blended material of one colour and alpha.
fn glass(color: Vec3, alpha: f32) -> Material {
    Material {
        name: "glass".into(),
        base_color_factor: color.extend(alpha),
        metallic_factor: 0.0,
        roughness_factor: 0.8,
        alpha_mode: AlphaMode::Blend,
        ..Default::default()
    }
}

/// Adds a 2 m square pane at height `z` over the wall's centre, facing the camera.
fn add_pane(scene: &mut Scene, z: f32, color: Vec3, alpha: f32) {
    scene.materials.push(glass(color, alpha));
    scene.meshes.push(quad_mesh());
    scene.meshes.last_mut().unwrap().primitives[0].material = scene.materials.len() - 1;
    scene.instances.push(Instance { mesh: scene.meshes.len() - 1, world_from_local: Mat4::from_translation(Vec3::new(0.0, 0.0, z)) });
}

fn configured(pipeline: PipelineKind, lights: LightMethod, decals: DecalMethod, (width, height): (u32, u32)) -> RenderConfig {
    RenderConfig { pipeline, decal_method: decals, ..config(width, height, lights) }
}

/// The centre (inside every pane) and a corner (outside them) of a 64×36 image, per pipeline.
fn centre_and_corner(scene: &Scene, camera: &Camera, pipeline: PipelineKind) -> (Vec3, Vec3) {
    let (_, hdr) = render_with(scene, camera, configured(pipeline, LightMethod::Brute, DecalMethod::Brute, (64, 36)));
    (rgb(pixel(&hdr, 32, 18)), rgb(pixel(&hdr, 2, 2)))
}

#[test]
fn panes_blend_back_to_front_over_what_lies_behind_them() {
    const RED: Vec3 = Vec3::new(0.9, 0.1, 0.1);
    const GREEN: Vec3 = Vec3::new(0.1, 0.8, 0.2);
    // Panes and wall are dielectrics of one roughness facing the camera, so a pane reflects the uniform
    // environment as the wall does at the same pixel: its radiance is its colour plus that reflection,
    // measured where the wall's albedo is exact (the G-buffer stores it in 8 bits).
    let (wall, camera) = ambient_wall();
    let reflection = centre_and_corner(&wall, &camera, PipelineKind::Visbuffer).0 - WALL_COLOR;
    let pane = |color: Vec3| color + reflection;
    for pipeline in PipelineKind::ALL {
        let name = pipeline.name();
        // The wall as this pipeline renders it, behind the pane.
        let (wall_radiance, _) = centre_and_corner(&wall, &camera, pipeline);
        assert!((wall_radiance - WALL_COLOR - reflection).abs().max_element() < 3e-3, "{name}: wall {wall_radiance}");
        let (mut one, _) = ambient_wall();
        add_pane(&mut one, 1.0, RED, 0.25);
        let (centre, _) = centre_and_corner(&one, &camera, pipeline);
        let expected = pane(RED) * 0.25 + wall_radiance * 0.75;
        assert!((centre - expected).abs().max_element() <= 1e-4, "{name}: one pane: {centre}, expected {expected}");

        // Two panes blend nearest last whatever order the scene lists them in.
        let expected = pane(GREEN) * 0.5 + (pane(RED) * 0.25 + wall_radiance * 0.75) * 0.5;
        for (near_first, order) in [(false, "far pane listed first"), (true, "near pane listed first")] {
            let (mut two, _) = ambient_wall();
            let panes = [(1.0, RED, 0.25), (2.0, GREEN, 0.5)];
            for i in 0..2 {
                let (z, color, alpha) = panes[if near_first { 1 - i } else { i }];
                add_pane(&mut two, z, color, alpha);
            }
            let (centre, _) = centre_and_corner(&two, &camera, pipeline);
            assert!((centre - expected).abs().max_element() <= 1e-4, "{name}, {order}: {centre}, expected {expected}");
        }

        // A pane behind the wall is hidden by it.
        let (mut hidden, _) = ambient_wall();
        add_pane(&mut hidden, -1.0, RED, 0.9);
        let (centre, _) = centre_and_corner(&hidden, &camera, pipeline);
        assert!((centre - wall_radiance).abs().max_element() <= 1e-4, "{name}: pane behind the wall shows: {centre}");
    }
}

/// The demo with a pane in front of the camera carrying one decal at its centre, and lights.
fn demo_with_decaled_pane() -> (Scene, Camera, (u32, u32)) {
    let mut scene = demo_scene();
    let camera = scene.cameras[0].clone();
    // 3 m in front of the eye, 1.2 m across, facing the camera (the quad faces +Z, the camera looks down −Z).
    let pane_from_local = camera.world_from_view * Mat4::from_translation(Vec3::new(0.0, 0.0, -3.0)) * Mat4::from_scale(Vec3::splat(0.6));
    scene.materials.push(glass(Vec3::new(0.6, 0.8, 0.9), 0.4));
    let mut pane = quad_mesh();
    pane.primitives[0].material = scene.materials.len() - 1;
    scene.meshes.push(pane);
    scene.instances.push(Instance { mesh: scene.meshes.len() - 1, world_from_local: pane_from_local });
    generators::add_scattered_lights(&mut scene, &ScatterLights { count: 300, seed: 2, ..Default::default() }).unwrap();
    // An opaque orange decal over the pane's centre, 0.1 m deep: it reaches nothing behind the pane.
    scene.materials.push(Material { base_color_factor: Vec4::new(1.0, 0.4, 0.0, 1.0), metallic_factor: 0.0, ..Default::default() });
    let decal_from_local = pane_from_local * Mat4::from_scale(Vec3::new(0.8, 0.8, 0.1 / 0.6));
    scene.decals.push(Decal {
        world_from_decal: Affine3A::from_mat4(decal_from_local),
        material: scene.materials.len() - 1,
        layer: 0,
        weight: 1.0,
    });
    (scene, camera, (64, 36))
}

fn render(scene: &Scene, camera: &Camera, config: RenderConfig) -> Image<[f32; 4]> {
    render_with(scene, camera, config).1
}

#[test]
fn panes_are_lit_and_decaled_through_every_method_in_every_pipeline() {
    let (scene, camera, size) = demo_with_decaled_pane();
    let centre = |image: &Image<[f32; 4]>| rgb(pixel(image, size.0 / 2, size.1 / 2));
    let methods = [(LightMethod::Bvh, DecalMethod::Bvh), (LightMethod::Clustered, DecalMethod::Clustered)];
    for pipeline in PipelineKind::ALL {
        let name = pipeline.name();
        let brute = render(&scene, &camera, configured(pipeline, LightMethod::Brute, DecalMethod::Brute, size));
        for &(lights, decals) in &methods {
            let image = render(&scene, &camera, configured(pipeline, lights, decals, size));
            let difference = max_abs_difference(&brute, &image);
            assert!(difference <= TOLERANCE, "{name}, lights {}, decals {}: max abs difference {difference}", lights.name(), decals.name());
        }
        // The decal and the lights reach the pane: turning either off changes its centre.
        let undecaled = render(&scene, &camera, configured(pipeline, LightMethod::Brute, DecalMethod::Off, size));
        let unlit = render(&scene, &camera, configured(pipeline, LightMethod::Off, DecalMethod::Brute, size));
        let decal_effect = (centre(&brute) - centre(&undecaled)).abs().max_element();
        let light_effect = (centre(&brute) - centre(&unlit)).abs().max_element();
        assert!(decal_effect > 0.05, "{name}: the decal does not show on the pane ({decal_effect})");
        assert!(light_effect > 0.01, "{name}: the lights do not reach the pane ({light_effect})");
    }
    // Deferred decals live in the G-buffer, which holds no transparent surface: the pane shows none.
    let deferred_decals =
        render(&scene, &camera, configured(PipelineKind::Deferred, LightMethod::Brute, DecalMethod::DeferredDecals, size));
    let undecaled = render(&scene, &camera, configured(PipelineKind::Deferred, LightMethod::Brute, DecalMethod::Off, size));
    let difference = (centre(&deferred_decals) - centre(&undecaled)).abs().max_element();
    assert!(difference <= TOLERANCE, "deferred decals reached the pane ({difference})");
}

#[test]
fn transparent_surfaces_need_float32_blending() {
    let (mut scene, _) = ambient_wall();
    add_pane(&mut scene, 1.0, Vec3::ONE, 0.5);
    let ctx = GpuContext::without(wgpu::Features::FLOAT32_BLENDABLE).expect("a GPU adapter");
    let error = Renderer::new(ctx, &scene, config(32, 18, LightMethod::Brute)).err().expect("an error without float32 blending");
    let message = error.to_string();
    assert!(message.contains("BLEND") && message.contains("float32-blendable"), "{message}");
}
