//! Transparent surfaces (glTF BLEND materials): shaded after the opaque surfaces in every pipeline,
//! each pixel's layers blended far to near over what lies behind them, hidden behind opaque surfaces, and lit and
//! decaled by the shading core through the frame's methods — which deferred decals, living in the
//! G-buffer, cannot do. Transmissive surfaces (KHR_materials_transmission, KHR_materials_volume):
//! the light behind them through their colour and medium, refracted and blurred by roughness, and
//! no traced shadow.

mod common;

use common::*;
use glam::{Affine3A, Mat4, Vec3, Vec4};
use manylights::{
    renderer::Image,
    scene::{
        demo::demo_scene, generators, generators::ScatterLights, AlphaMode, Camera, Decal, Instance, Material, Mesh, Primitive, Scene,
        Vertex,
    },
    scene::{Light, Specular, Sun, Texture, TextureRef, Transmission, Wrap},
    settings::{DecalMethod, LightMethod, PipelineKind},
    settings::{RaySettings, RenderConfig, SunShadows},
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
fn a_pixel_blends_its_nearest_layers_in_order_however_many_lie_behind() {
    // Twenty panes, red and green in turn, each letting half through: a pixel keeps its nearest
    // sixteen, which leave the farther four less than 2e-5 of the radiance. The panes of each colour
    // are one draw, listed out of depth order, so the order fragments arrive in is not the panes'.
    let (wall, camera) = ambient_wall();
    let (wall_radiance, _) = centre_and_corner(&wall, &camera, PipelineKind::Visbuffer);
    let reflection = wall_radiance - WALL_COLOR;
    let colors = [Vec3::new(0.9, 0.1, 0.1), Vec3::new(0.1, 0.8, 0.2)];
    let mut stacked = wall;
    for (k, color) in colors.into_iter().enumerate() {
        stacked.materials.push(glass(color, 0.5));
        let quad = &quad_mesh().primitives[0];
        let mut panes = Primitive { vertices: Vec::new(), indices: Vec::new(), material: stacked.materials.len() - 1 };
        for pane in [3, 8, 0, 6, 9, 1, 5, 2, 7, 4] {
            let z = 0.1 * (2 * pane + k + 1) as f32;
            let first = panes.vertices.len() as u32;
            panes.vertices.extend(quad.vertices.iter().map(|v| Vertex { position: [v.position[0], v.position[1], z], ..*v }));
            panes.indices.extend(quad.indices.iter().map(|i| first + i));
        }
        stacked.meshes.push(Mesh { name: "panes".into(), primitives: vec![panes] });
        stacked.instances.push(Instance { mesh: stacked.meshes.len() - 1, world_from_local: Mat4::IDENTITY });
    }
    for pipeline in PipelineKind::ALL {
        let (wall_radiance, _) = centre_and_corner(&ambient_wall().0, &camera, pipeline);
        let mut expected = wall_radiance;
        for i in 0..20 {
            expected = (colors[i % 2] + reflection) * 0.5 + expected * 0.5;
        }
        let (centre, _) = centre_and_corner(&stacked, &camera, pipeline);
        assert!((centre - expected).abs().max_element() <= 1e-4, "{}: twenty panes: {centre}, expected {expected}", pipeline.name());
    }
}

#[test]
fn wholly_transparent_fragments_take_none_of_a_pixels_layers() {
    // Sixteen panes of alpha 0 in front of a red one: linked, they would be the sixteen layers the
    // pixel keeps, and the red pane would not show.
    const RED: Vec3 = Vec3::new(0.9, 0.1, 0.1);
    let (wall, camera) = ambient_wall();
    let mut one = wall.clone();
    add_pane(&mut one, 0.5, RED, 0.5);
    let (expected, _) = centre_and_corner(&one, &camera, PipelineKind::Visbuffer);
    let mut veiled = one;
    for i in 0..16 {
        add_pane(&mut veiled, 1.0 + 0.05 * i as f32, Vec3::ONE, 0.0);
    }
    let (centre, _) = centre_and_corner(&veiled, &camera, PipelineKind::Visbuffer);
    let (bare, _) = centre_and_corner(&wall, &camera, PipelineKind::Visbuffer);
    assert!((expected - bare).abs().max_element() > 0.1, "the red pane does not show on its own");
    assert!((centre - expected).abs().max_element() <= 1e-4, "behind sixteen clear panes: {centre}, expected {expected}");
}

#[test]
fn crossing_panes_blend_in_the_order_each_pixel_sees_them() {
    // A pane turned about the vertical crosses an upright one at the centre: its left half lies in
    // front of it, its right half behind. No order of the two draws blends both halves right.
    const RED: Vec3 = Vec3::new(0.9, 0.1, 0.1);
    const GREEN: Vec3 = Vec3::new(0.1, 0.8, 0.2);
    let (wall, camera) = ambient_wall();
    let turned = |scene: &mut Scene| {
        scene.materials.push(glass(GREEN, 0.5));
        scene.meshes.push(quad_mesh());
        scene.meshes.last_mut().unwrap().primitives[0].material = scene.materials.len() - 1;
        let world_from_local = Mat4::from_translation(Vec3::new(0.0, 0.0, 1.0)) * Mat4::from_rotation_y(30f32.to_radians());
        scene.instances.push(Instance { mesh: scene.meshes.len() - 1, world_from_local });
    };
    let columns = [27, 37];
    let at = |scene: &Scene| {
        let (_, hdr) = render_with(scene, &camera, configured(PipelineKind::Visbuffer, LightMethod::Brute, DecalMethod::Brute, (64, 36)));
        columns.map(|x| rgb(pixel(&hdr, x, 18)))
    };
    let behind = at(&wall);
    // Each pane's own radiance, from it alone over the wall.
    let mut upright = wall.clone();
    add_pane(&mut upright, 1.0, RED, 0.5);
    let mut crossing = wall.clone();
    turned(&mut crossing);
    let (upright_alone, crossing_alone) = (at(&upright), at(&crossing));
    let own = |alone: Vec3, behind: Vec3| (alone - behind * 0.5) / 0.5;
    let over = |radiance: Vec3, behind: Vec3| radiance * 0.5 + behind * 0.5;
    for order in ["upright pane listed first", "crossing pane listed first"] {
        let mut both = wall.clone();
        if order.starts_with("upright") {
            add_pane(&mut both, 1.0, RED, 0.5);
            turned(&mut both);
        } else {
            turned(&mut both);
            add_pane(&mut both, 1.0, RED, 0.5);
        }
        let got = at(&both);
        for (i, side) in ["left", "right"].into_iter().enumerate() {
            let (red, green) = (own(upright_alone[i], behind[i]), own(crossing_alone[i], behind[i]));
            assert!(red.x > 0.5 && green.y > 0.5, "{side}: column {} misses a pane ({red}, {green})", columns[i]);
            let expected = if i == 0 { over(green, over(red, behind[i])) } else { over(red, over(green, behind[i])) };
            assert!((got[i] - expected).abs().max_element() <= 1e-4, "{order}, {side}: {}, expected {expected}", got[i]);
        }
    }
}

/// A thin pane at `z` letting `transmission` through, of base colour `color`, reflecting nothing
/// (specular factor 0), with `alpha` in its base colour that its OPAQUE mode ignores.
fn transmissive_pane(scene: &mut Scene, z: f32, color: Vec3, transmission: Transmission) {
    scene.materials.push(Material {
        name: "transmissive".into(),
        base_color_factor: color.extend(0.3),
        metallic_factor: 0.0,
        roughness_factor: 0.0,
        specular: Specular { factor: 0.0, ..Default::default() },
        transmission: Some(transmission),
        ..Default::default()
    });
    let mut pane = quad_mesh();
    pane.primitives[0].material = scene.materials.len() - 1;
    scene.meshes.push(pane);
    scene.instances.push(Instance { mesh: scene.meshes.len() - 1, world_from_local: Mat4::from_translation(Vec3::new(0.0, 0.0, z)) });
}

/// Whether `a` is `b` within the background's precision (half floats), relative to `b`.
fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() <= 2e-3 * b.max_element().max(0.1)
}

/// One texel of R = G = 128 (linear data ≈ 0.5).
fn half_texture() -> Texture {
    Texture { name: "half".into(), width: 1, height: 1, rgba8: vec![128, 128, 0, 255] }
}

fn texture(index: usize) -> TextureRef {
    TextureRef::new(index, Wrap::Repeat, Wrap::Repeat)
}

#[test]
fn transmissive_panes_pass_the_light_behind_them_through_their_colour_and_medium() {
    const TINT: Vec3 = Vec3::new(0.5, 1.0, 0.25);
    let (wall, camera) = ambient_wall();
    for pipeline in PipelineKind::ALL {
        let name = pipeline.name();
        let (wall_radiance, _) = centre_and_corner(&wall, &camera, pipeline);
        // Wholly transmissive: the wall behind, through the pane's colour, however a light in front
        // lights the pane; its alpha does not blend.
        let light = point_light(Vec3::new(0.3, 0.2, 2.0), 2.0, 6.0);
        let (mut lit_wall, _) = ambient_wall();
        lit_wall.lights.push(light);
        let (lit_wall_radiance, lit_corner) = centre_and_corner(&lit_wall, &camera, pipeline);
        let mut full = lit_wall.clone();
        transmissive_pane(&mut full, 1.0, TINT, Transmission::thin(1.0));
        let (centre, corner) = centre_and_corner(&full, &camera, pipeline);
        let expected = TINT * lit_wall_radiance;
        assert!(close(centre, expected), "{name}: through the pane {centre}, expected {expected}");
        assert!(close(corner, lit_corner), "{name}: the pane reaches the corner: {corner}");

        // Fully rough at an index of 1.5, a thin pane reads the chain's coarsest levels: over the
        // nearly uniform wall, nearly the same light (each level is a mean of the one above).
        let (mut rough, _) = ambient_wall();
        transmissive_pane(&mut rough, 1.0, TINT, Transmission::thin(1.0));
        let material = rough.materials.last_mut().unwrap();
        (material.roughness_factor, material.specular.ior) = (1.0, 1.5);
        let (centre, _) = centre_and_corner(&rough, &camera, pipeline);
        let expected = TINT * wall_radiance;
        assert!(
            (centre - expected).abs().max_element() <= 0.03 * expected.max_element(),
            "{name}: rough glass {centre}, expected {expected}"
        );

        // Part: the rest is the diffuse lobe, which the uniform environment lights to the base colour.
        // The factor, then the same through the transmission texture's R.
        let half_texel = 128.0 / 255.0;
        for (transmission, share) in
            [(Transmission::thin(0.5), 0.5), (Transmission { texture: Some(texture(0)), ..Transmission::thin(1.0) }, half_texel)]
        {
            let (mut part, _) = ambient_wall();
            part.textures.push(half_texture());
            transmissive_pane(&mut part, 1.0, TINT, transmission);
            let (centre, _) = centre_and_corner(&part, &camera, pipeline);
            let expected = TINT * wall_radiance * share + TINT * (1.0 - share);
            assert!(close(centre, expected), "{name}: {share} transmissive {centre}, expected {expected}");
        }

        // A medium 1 m × the thickness texture's G (≈ 0.5) deep in the mesh's units, scaled by 2,
        // entered at an index of 1 (unbent): Beer's law leaves the attenuation colour to the power
        // of its depth ÷ 0.25 m.
        let attenuation_color = Vec3::new(0.5, 0.8, 1.0);
        let (mut thick, _) = ambient_wall();
        thick.textures.push(half_texture());
        let medium = Transmission {
            thickness_factor: 1.0,
            thickness_texture: Some(texture(0)),
            attenuation_distance: 0.25,
            attenuation_color,
            ..Transmission::thin(1.0)
        };
        transmissive_pane(&mut thick, 1.0, Vec3::ONE, medium);
        thick.materials.last_mut().unwrap().specular.ior = 1.0;
        thick.instances.last_mut().unwrap().world_from_local =
            Mat4::from_translation(Vec3::new(0.0, 0.0, 1.0)) * Mat4::from_scale(Vec3::splat(2.0));
        let (centre, _) = centre_and_corner(&thick, &camera, pipeline);
        let expected = attenuation_color.powf(2.0 * half_texel / 0.25) * wall_radiance;
        assert!(close(centre, expected), "{name}: through the medium {centre}, expected {expected}");
    }
}

/// Where `split_wall` changes colour.
const EDGE_X: f32 = 1.6;

/// A wall whose part left of `EDGE_X` is `ambient_wall`'s and the rest orange, lit by the uniform
/// environment, seen as `ambient_wall` is.
fn split_wall() -> (Scene, Camera) {
    let (mut scene, camera) = ambient_wall();
    scene.materials.push(Material { base_color_factor: Vec4::new(0.9, 0.5, 0.1, 1.0), ..scene.materials[0].clone() });
    let mut right = quad_mesh();
    right.primitives[0].material = 1;
    scene.meshes.push(right);
    // The right part, 1 mm in front of the left one.
    scene.instances.push(Instance {
        mesh: 1,
        world_from_local: Mat4::from_translation(Vec3::new(EDGE_X + 5.0, 0.0, 0.001)) * Mat4::from_scale(Vec3::new(5.0, 10.0, 1.0)),
    });
    (scene, camera)
}

/// The split wall seen through a pane at z = 2 (2 m from the eye at z = 4) bounding a medium 1.5 m
/// deep of index 1.5 and of `roughness`, spreading its index over the colours by `dispersion`.
fn refracting(roughness: f32, dispersion: f32) -> (Scene, Camera) {
    let (mut scene, camera) = split_wall();
    let medium = Transmission { thickness_factor: MEDIUM_DEPTH, dispersion, ..Transmission::thin(1.0) };
    transmissive_pane(&mut scene, PANE_Z, Vec3::ONE, medium);
    let material = scene.materials.last_mut().unwrap();
    material.specular.ior = 1.5;
    material.roughness_factor = roughness;
    scene.instances.last_mut().unwrap().world_from_local = Mat4::from_translation(Vec3::new(0.0, 0.0, PANE_Z));
    (scene, camera)
}

const PANE_Z: f32 = 2.0;
const MEDIUM_DEPTH: f32 = 1.5;
const EYE_Z: f32 = 4.0;
/// The refraction tests' image.
const REFRACTED_WIDTH: u32 = 160;
const REFRACTED_HEIGHT: u32 = 90;

/// The middle row of `scene` in the visibility buffer.
fn middle_row(scene: &Scene, camera: &Camera) -> Vec<Vec3> {
    let (width, height) = (REFRACTED_WIDTH, REFRACTED_HEIGHT);
    let (_, hdr) = render_with(scene, camera, configured(PipelineKind::Visbuffer, LightMethod::Brute, DecalMethod::Brute, (width, height)));
    (0..width).map(|x| rgb(pixel(&hdr, x, height / 2))).collect()
}

/// Where the eye's ray through the centre of column `x` of the middle row, refracted into the medium
/// at index `ior`, sees the wall (the background image is read at that point's pixel), and where the
/// straight ray does; `None` off the pane or within a pixel and a half of the wall's edge.
fn wall_seen(x: u32, ior: f32) -> Option<(f32, f32)> {
    let (width, height) = (REFRACTED_WIDTH as f32, REFRACTED_HEIGHT as f32);
    let half_width = (30f32.to_radians().tan() * width / height) * (EYE_Z - PANE_Z);
    let pane_x = ((x as f32 + 0.5) / width * 2.0 - 1.0) * half_width;
    if pane_x.abs() > 1.0 {
        return None;
    }
    let view = Vec3::new(pane_x, 0.0, PANE_Z - EYE_Z).normalize();
    let cos_in = -view.z;
    let sin_out = (1.0 - cos_in * cos_in).sqrt() / ior;
    let refracted = Vec3::new(sin_out * pane_x.signum(), 0.0, -(1.0 - sin_out * sin_out).sqrt());
    let exit = Vec3::new(pane_x, 0.0, PANE_Z) + refracted * MEDIUM_DEPTH;
    let wall_x = exit.x * EYE_Z / (EYE_Z - exit.z);
    let straight_x = pane_x * EYE_Z / (EYE_Z - PANE_Z);
    let pixel_on_wall = 2.0 * 30f32.to_radians().tan() * EYE_Z / height;
    ((wall_x - EDGE_X).abs() >= 1.5 * pixel_on_wall).then_some((wall_x, straight_x))
}

#[test]
fn thick_media_refract_and_rough_ones_blur_the_light_behind_them() {
    // Rays bend towards the pane's normal, so the wall's edge is seen further out than straight through.
    let (wall, camera) = split_wall();
    let bare = middle_row(&wall, &camera);
    let (left, right) = (bare[REFRACTED_WIDTH as usize / 2], bare[REFRACTED_WIDTH as usize - 1]);
    let seen = middle_row(&refracting(0.0, 0.0).0, &camera);
    let mut bent_columns = 0;
    for x in 0..REFRACTED_WIDTH {
        let Some((wall_x, straight_x)) = wall_seen(x, 1.5) else { continue };
        let expected = if wall_x < EDGE_X { left } else { right };
        let got = seen[x as usize];
        assert!(
            (got - expected).abs().max_element() < 0.02 * expected.max_element(),
            "column {x}: {got}, expected {expected} (wall x {wall_x})"
        );
        bent_columns += usize::from((wall_x < EDGE_X) != (straight_x < EDGE_X));
    }
    assert!(bent_columns >= 3, "only {bent_columns} columns see across the edge through the medium");

    // Fully rough: the edge spreads over many columns.
    let blurred = middle_row(&refracting(1.0, 0.0).0, &camera);
    let mixed =
        |row: &[Vec3]| row.iter().filter(|c| (**c - left).abs().max_element() > 0.05 && (**c - right).abs().max_element() > 0.05).count();
    assert!(mixed(&seen) <= 3 && mixed(&blurred) >= 8, "edge columns: sharp {}, rough {}", mixed(&seen), mixed(&blurred));
}

#[test]
fn dispersion_bends_red_less_and_blue_more_than_green() {
    // Dispersion 30 spreads the index by (1.5 − 1) × 0.025 × 30 = 0.375 either side of green's 1.5
    // (far beyond any glass, so that the parting spans pixels here): each channel shows the side of
    // the edge its own refraction reaches, so the edge's colours part.
    let (wall, camera) = split_wall();
    let bare = middle_row(&wall, &camera);
    let (left, right) = (bare[REFRACTED_WIDTH as usize / 2], bare[REFRACTED_WIDTH as usize - 1]);
    let seen = middle_row(&refracting(0.0, 30.0).0, &camera);
    let mut fringe_columns = 0;
    for x in 0..REFRACTED_WIDTH {
        let sides = [1.125, 1.5, 1.875].map(|ior| wall_seen(x, ior).map(|(wall_x, _)| wall_x < EDGE_X));
        for (channel, side) in sides.iter().enumerate() {
            let Some(on_left) = side else { continue };
            let expected = if *on_left { left[channel] } else { right[channel] };
            let got = seen[x as usize][channel];
            assert!((got - expected).abs() < 0.02 * expected.max(0.1), "column {x}, channel {channel}: {got}, expected {expected}");
        }
        fringe_columns += usize::from(matches!(sides, [Some(red), _, Some(blue)] if red != blue));
    }
    assert!(fringe_columns >= 2, "only {fringe_columns} columns part red from blue");
}

#[test]
fn only_the_nearest_transmissive_surface_shows_blended_ones_in_front_blend_over_it_and_masks_cut_it() {
    const NEAR: Vec3 = Vec3::new(1.0, 0.5, 0.5);
    const FAR: Vec3 = Vec3::new(0.5, 1.0, 0.5);
    let (wall, camera) = ambient_wall();
    for pipeline in PipelineKind::ALL {
        let name = pipeline.name();
        let (wall_radiance, _) = centre_and_corner(&wall, &camera, pipeline);
        // One draw holding a near quad (z = 2) before a far one (z = 1), told apart by their
        // vertex colours: drawn in the order listed, the far one would cover the near one.
        let (mut scene, _) = ambient_wall();
        transmissive_pane(&mut scene, 0.0, Vec3::ONE, Transmission::thin(1.0));
        let mesh = scene.meshes.last_mut().unwrap();
        let primitive = &mut mesh.primitives[0];
        let quad = primitive.vertices.clone();
        primitive.vertices = [(2.0, NEAR), (1.0, FAR)]
            .iter()
            .flat_map(|&(z, color)| {
                quad.iter().map(move |v| Vertex {
                    position: [v.position[0], v.position[1], z],
                    color: Vertex::color_from(color.extend(1.0).to_array()),
                    ..*v
                })
            })
            .collect();
        primitive.indices = [0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7].to_vec();
        let (centre, _) = centre_and_corner(&scene, &camera, pipeline);
        assert!(close(centre, NEAR * wall_radiance), "{name}: {centre}, expected the near quad's {}", NEAR * wall_radiance);

        // A blended pane in front of the glass blends over it; one behind it is hidden.
        let mut front = scene.clone();
        add_pane(&mut front, 3.0, Vec3::new(0.9, 0.1, 0.1), 0.25);
        let mut behind = scene.clone();
        add_pane(&mut behind, 0.5, Vec3::new(0.9, 0.1, 0.1), 0.9);
        let (in_front, _) = centre_and_corner(&front, &camera, pipeline);
        let (hidden, _) = centre_and_corner(&behind, &camera, pipeline);
        assert!(close(hidden, centre), "{name}: a blended pane behind the glass shows: {hidden} against {centre}");
        let blended_over = (in_front - centre * 0.75) / 0.25;
        assert!(blended_over.x > 0.8 && blended_over.y < 0.3, "{name}: the pane in front does not blend over the glass: {in_front}");

        // Alpha-masked glass is cut where its alpha (0.3) falls below the cutoff, and drawn where not.
        for (cutoff, expected) in [(0.5, wall_radiance), (0.2, NEAR * wall_radiance)] {
            let mut masked = scene.clone();
            masked.materials.last_mut().unwrap().alpha_mode = AlphaMode::Mask { cutoff };
            let (centre, _) = centre_and_corner(&masked, &camera, pipeline);
            assert!(close(centre, expected), "{name}: masked at {cutoff}: {centre}, expected {expected}");
        }
    }
}

#[test]
fn transmissive_surfaces_cast_no_traced_shadow() {
    // The sun shines from +X, 2 m across for every metre down: a pane at z = 1 over x in [-1, 1]
    // shades the wall over x in [-3, -1], left of where the eye sees the pane.
    // No pane, a transmissive one, or the same pane opaque.
    let sunlit = |pane: Option<Option<Transmission>>| {
        let (mut scene, camera) = ambient_wall();
        scene.sun = Some(Sun { direction: Vec3::new(-2.0, 0.0, -1.0).normalize(), color: Vec3::ONE, illuminance: 2.0 });
        if let Some(transmission) = pane {
            transmissive_pane(&mut scene, 1.0, Vec3::ONE, Transmission::thin(1.0));
            scene.materials.last_mut().unwrap().transmission = transmission;
        }
        let rays = RaySettings { sun_shadows: SunShadows::Hard, ..config(64, 36, LightMethod::Brute).rays };
        let config = RenderConfig { rays, ..configured(PipelineKind::Visbuffer, LightMethod::Brute, DecalMethod::Brute, (64, 36)) };
        let (_, hdr) = render_with(&scene, &camera, config);
        // Wall x = -2.2 m, on the middle row.
        rgb(pixel(&hdr, 14, 18))
    };
    let bare = sunlit(None);
    let through_glass = sunlit(Some(Some(Transmission::thin(1.0))));
    let behind_opaque = sunlit(Some(None));
    assert!((through_glass - bare).abs().max_element() <= 1e-4, "the transmissive pane shades the wall: {through_glass} against {bare}");
    assert!(
        behind_opaque.max_element() < 0.8 * bare.max_element(),
        "the opaque pane casts no shadow there: {behind_opaque} against {bare}"
    );
}

/// The transmission lobe of `shading/brdf.wgsl` times |n·l|, for a thin transmissive dielectric
/// reflecting nothing (specular weight 0) with normal `n`, towards `light_dir` below its surface.
fn transmission_lobe(n: Vec3, view_dir: Vec3, light_dir: Vec3, roughness: f32, ior: f32, color: Vec3) -> Vec3 {
    let mirrored = light_dir - 2.0 * n.dot(light_dir) * n;
    let (n_dot_l, n_dot_v) = (n.dot(mirrored), n.dot(view_dir));
    let h = (mirrored + view_dir).normalize();
    let alpha = (roughness * (ior * 2.0 - 2.0).clamp(0.0, 1.0)).max(0.045).powi(2);
    let a2 = alpha * alpha;
    let d = n.dot(h).powi(2) * (a2 - 1.0) + 1.0;
    let distribution = a2 / (std::f32::consts::PI * d * d);
    let visibility =
        0.5 / (n_dot_l * (n_dot_v * n_dot_v * (1.0 - a2) + a2).sqrt() + n_dot_v * (n_dot_l * n_dot_l * (1.0 - a2) + a2).sqrt());
    color * distribution * visibility * n_dot_l
}

#[test]
fn lights_and_the_sun_behind_a_transmissive_pane_shine_through_its_lobe() {
    const TINT: Vec3 = Vec3::new(0.5, 1.0, 0.25);
    let (roughness, ior) = (0.5, 1.5);
    // A lone pane at z = 1 before the uniform environment, 3 m from the eye; nothing behind it for
    // the lights to light but the pane itself.
    let (mut bare, camera) = ambient_wall();
    bare.instances.clear();
    transmissive_pane(&mut bare, 1.0, TINT, Transmission::thin(1.0));
    bare.materials.last_mut().unwrap().roughness_factor = roughness;
    let light = point_light(Vec3::new(0.3, 0.2, 0.0), 2.0, 6.0);
    let sun = Sun { direction: Vec3::new(0.1, 0.2, 1.0).normalize(), color: Vec3::new(1.0, 0.8, 0.6), illuminance: 0.5 };
    let (mut lit, mut sunlit, mut crowd) = (bare.clone(), bare.clone(), bare.clone());
    lit.lights.push(light);
    sunlit.sun = Some(sun);
    // Crowded enough for `bvh` to share its leaves out among a subgroup's lanes (`plan.rs`).
    let crowd_offsets: Vec<Vec3> = (0..32).map(|i| Vec3::new((i % 4) as f32, (i / 4 % 4) as f32, (i / 16) as f32) * 0.05).collect();
    crowd.lights.extend(crowd_offsets.iter().map(|&offset| Light { position: light.position - offset, intensity: 0.1, ..light }));

    // The point the centre pixel (32, 18) of a 64×36 image sees on the pane.
    let world_from_clip = camera.clip_from_world(64, 36).inverse();
    let ndc = Vec3::new(32.5 / 64.0 * 2.0 - 1.0, 1.0 - 18.5 / 36.0 * 2.0, 0.5);
    let far = world_from_clip.project_point3(ndc);
    let eye = camera.position();
    let point = eye + (far - eye) * ((1.0 - eye.z) / (far.z - eye.z));
    let view_dir = (eye - point).normalize();
    let through_pane = |light: &Light| {
        let to_light = light.position - point;
        let distance_sq = to_light.length_squared();
        let window = (1.0 - (distance_sq / (light.range * light.range)).powi(2)).clamp(0.0, 1.0);
        light.color * light.intensity * window * window / distance_sq
            * transmission_lobe(Vec3::Z, view_dir, to_light.normalize(), roughness, ior, TINT)
    };
    let from_light = through_pane(&light);
    let from_crowd: Vec3 = crowd.lights.iter().map(through_pane).sum();
    let from_sun = sun.color * sun.illuminance * transmission_lobe(Vec3::Z, view_dir, -sun.direction, roughness, ior, TINT);
    assert!(from_light.min_element() > 0.01 && from_sun.min_element() > 0.01, "the test's lobes are too faint to tell");

    for pipeline in PipelineKind::ALL {
        let name = pipeline.name();
        let (background, _) = centre_and_corner(&bare, &camera, pipeline);
        let (with_sun, _) = centre_and_corner(&sunlit, &camera, pipeline);
        let got = with_sun - background;
        assert!(close(got, from_sun), "{name}: the sun through the pane adds {got}, expected {from_sun}");
        // Its shadow ray leaves the pane's far side, towards the sun.
        let rays = RaySettings { sun_shadows: SunShadows::Hard, ..config(64, 36, LightMethod::Brute).rays };
        let shadowed = RenderConfig { rays, ..configured(pipeline, LightMethod::Brute, DecalMethod::Brute, (64, 36)) };
        let got = rgb(pixel(&render_with(&sunlit, &camera, shadowed).1, 32, 18)) - background;
        assert!(close(got, from_sun), "{name}: with sun shadows the sun through the pane adds {got}, expected {from_sun}");
        // Through every light method, and through crowds, whose loops skip lights below the horizon
        // of surfaces lit from above only.
        let runs =
            [(LightMethod::Brute, &lit, from_light), (LightMethod::Bvh, &lit, from_light), (LightMethod::Clustered, &lit, from_light)];
        for (method, scene, expected) in runs.into_iter().chain([(LightMethod::Bvh, &crowd, from_crowd)]) {
            let (_, hdr) = render_with(scene, &camera, configured(pipeline, method, DecalMethod::Brute, (64, 36)));
            let got = rgb(pixel(&hdr, 32, 18)) - background;
            let lights = scene.lights.len();
            assert!(close(got, expected), "{name}, {}: {lights} lights through the pane add {got}, expected {expected}", method.name());
        }
    }
}

#[test]
fn the_sun_shines_through_glass_once_under_the_daylight_sky() {
    // Under the daylight sky the light read behind glass holds the sun's disc where the eye looks at
    // it through the glass: there the sun's transmission lobe is left out, elsewhere it adds.
    const TINT: Vec3 = Vec3::new(0.5, 1.0, 0.25);
    let sunlit = |direction: Vec3, roughness: f32, wall: bool| {
        let (mut scene, camera) = ambient_wall();
        if !wall {
            scene.instances.clear();
        }
        // A wall reflecting no specular light is uniform behind the pane, however blurred.
        scene.materials[0].specular.factor = 0.0;
        scene.ambient = Vec3::ZERO;
        scene.sun = Some(Sun { direction: direction.normalize(), color: Vec3::ONE, illuminance: 0.5 });
        manylights::scene::sky::light_with_sky(&mut scene, manylights::settings::Sky::Daylight);
        let bare = scene.clone();
        transmissive_pane(&mut scene, 1.0, TINT, Transmission::thin(1.0));
        scene.materials.last_mut().unwrap().roughness_factor = roughness;
        let centre = |scene: &Scene| rgb(pixel(&render_with(scene, &camera, config(64, 36, LightMethod::Brute)).1, 32, 18));
        (centre(&bare), centre(&scene), camera)
    };
    // The sun far off the view behind the wall: its lobe through the rough pane adds as without a sky.
    let oblique = Vec3::new(0.6, 0.4, 1.0);
    let (wall, through, camera) = sunlit(oblique, 0.5, true);
    let world_from_clip = camera.clip_from_world(64, 36).inverse();
    let far = world_from_clip.project_point3(Vec3::new(32.5 / 64.0 * 2.0 - 1.0, 1.0 - 18.5 / 36.0 * 2.0, 0.5));
    let eye = camera.position();
    let point = eye + (far - eye) * ((1.0 - eye.z) / (far.z - eye.z));
    let lobe = 0.5 * transmission_lobe(Vec3::Z, (eye - point).normalize(), -oblique.normalize(), 0.5, 1.5, TINT);
    let got = through - TINT * wall;
    assert!(close(got, lobe), "the sun off the view adds {got} through the pane, expected {lobe}");
    // The sun straight behind the centre pixel of a smooth pane, the sky around it: the pane shows
    // the disc behind it, and no lobe on top.
    let (sky, through, _) = sunlit(eye - point, 0.0, false);
    assert!(sky.max_element() > 100.0, "the centre pixel misses the disc: {sky}");
    assert!(close(through, TINT * sky), "through the pane {through}, the disc behind it {}", TINT * sky);
}
