//! Decals: each blending rule of `shading/decals.wgsl` has the effect the formula says, through both
//! enumeration methods. Per attribute c, within a layer:
//! (Σ cᵢαᵢwᵢ / Σ αᵢwᵢ)(1 − Π(1−αᵢ)) + c₀ Π(1−αᵢ); layers bottom to top.
//!
//! The wall is lit by a uniform environment only, so its linear radiance is its albedo plus a specular
//! reflection that neither its albedo nor a decal's colour changes: decal colours can be read back
//! exactly.

mod common;

use common::*;
use glam::{Affine3A, Quat, Vec3, Vec4};
use manylights::{
    scene::{Camera, Decal, Material, Scene, Texture, TextureRef, Wrap},
    settings::RenderConfig,
    settings::{DecalMethod, LightMethod},
};

/// The methods that blend through the shading core's formula: `off` applies no decals, and deferred
/// decals blend in draw order in the deferred pipeline (`tests/pipelines.rs` compares them).
const BLENDING_METHODS: [DecalMethod; 3] = [DecalMethod::Brute, DecalMethod::Bvh, DecalMethod::Clustered];

const WALL_COLOR: Vec3 = AMBIENT_WALL_COLOR;

/// A solid decal material: colour and alpha from the factor.
fn solid(scene: &mut Scene, color: Vec3, alpha: f32) -> usize {
    scene.materials.push(Material {
        base_color_factor: color.extend(alpha),
        metallic_factor: 0.0,
        roughness_factor: 0.8,
        ..Default::default()
    });
    scene.materials.len() - 1
}

/// A 2 m square decal on the wall's centre, projecting onto it.
fn decal(material: usize, layer: u32, weight: f32) -> Decal {
    Decal { world_from_decal: Affine3A::from_scale(Vec3::new(2.0, 2.0, 0.5)), material, layer, weight }
}

/// The albedo each method shows at the centre and at a corner: the radiance less the undecaled wall's
/// specular reflection, which decals of the wall's metallic (0) and roughness (0.8) leave unchanged.
fn render_methods(scene: &Scene, camera: &Camera) -> Vec<(DecalMethod, Vec3, Vec3)> {
    let undecaled = Scene { decals: Vec::new(), ..scene.clone() };
    BLENDING_METHODS
        .iter()
        .map(|&method| {
            let config = RenderConfig { decal_method: method, ..config(64, 36, LightMethod::Brute) };
            let (hdr, wall) = (render_with(scene, camera, config.clone()).1, render_with(&undecaled, camera, config).1);
            let rgb = |p: [f32; 4]| Vec3::new(p[0], p[1], p[2]);
            let albedo = |x, y| rgb(pixel(&hdr, x, y)) - (rgb(pixel(&wall, x, y)) - WALL_COLOR);
            // The centre is inside every decal here; the corner is outside all of them.
            (method, albedo(32, 18), albedo(2, 2))
        })
        .collect()
}

/// Renders the decals over the wall and checks the centre against `expected` and that the corner is
/// untouched, for every method.
fn assert_centre(decals: Vec<Decal>, materials: &[(Vec3, f32)], expected: Vec3, rule: &str) {
    let (mut scene, camera) = ambient_wall();
    for &(color, alpha) in materials {
        solid(&mut scene, color, alpha);
    }
    scene.decals = decals;
    for (method, centre, corner) in render_methods(&scene, &camera) {
        assert!((centre - expected).abs().max_element() <= 1e-4, "{rule} ({}): centre {centre}, expected {expected}", method.name());
        assert!(
            (corner - WALL_COLOR).abs().max_element() <= 1e-5,
            "{rule} ({}): corner {corner} outside the decals changed",
            method.name()
        );
    }
}

const RED: Vec3 = Vec3::new(0.9, 0.1, 0.1);
const GREEN: Vec3 = Vec3::new(0.1, 0.8, 0.2);

#[test]
fn an_opaque_decal_replaces_the_albedo() {
    assert_centre(vec![decal(1, 0, 1.0)], &[(RED, 1.0)], RED, "opaque");
}

#[test]
fn alpha_mixes_with_the_surface_below() {
    assert_centre(vec![decal(1, 0, 1.0)], &[(RED, 0.25)], RED * 0.25 + WALL_COLOR * 0.75, "alpha 0.25");
}

#[test]
fn weights_average_opaque_decals_of_one_layer_in_any_order() {
    let expected = (RED * 1.0 + GREEN * 3.0) / 4.0;
    assert_centre(vec![decal(1, 2, 1.0), decal(2, 2, 3.0)], &[(RED, 1.0), (GREEN, 1.0)], expected, "weights");
    assert_centre(vec![decal(2, 2, 3.0), decal(1, 2, 1.0)], &[(RED, 1.0), (GREEN, 1.0)], expected, "weights, reversed");
}

#[test]
fn a_layer_covers_by_one_minus_the_product_of_transmittances() {
    // Two half-transparent decals in one layer cover 1 − 0.5 · 0.5 = 0.75 with their weighted mean.
    let mean = (RED * 0.5 * 1.0 + GREEN * 0.5 * 2.0) / (0.5 * 1.0 + 0.5 * 2.0);
    let expected = mean * 0.75 + WALL_COLOR * 0.25;
    assert_centre(vec![decal(1, 1, 1.0), decal(2, 1, 2.0)], &[(RED, 0.5), (GREEN, 0.5)], expected, "coverage");
}

#[test]
fn a_weight_alone_changes_nothing() {
    assert_centre(vec![decal(1, 0, 7.5)], &[(RED, 0.5)], RED * 0.5 + WALL_COLOR * 0.5, "single weighted decal");
}

#[test]
fn higher_layers_cover_lower_ones_whatever_the_order_or_weight() {
    let materials = [(RED, 1.0), (GREEN, 1.0)];
    assert_centre(vec![decal(1, 0, 100.0), decal(2, 3, 1.0)], &materials, GREEN, "green on top");
    assert_centre(vec![decal(2, 3, 1.0), decal(1, 0, 100.0)], &materials, GREEN, "green on top, listed first");
    assert_centre(vec![decal(1, 1, 1.0), decal(2, 0, 1.0)], &materials, RED, "red on top");
    // A half-transparent layer over an opaque one mixes the two.
    assert_centre(vec![decal(1, 0, 1.0), decal(2, 1, 1.0)], &[(RED, 1.0), (GREEN, 0.5)], GREEN * 0.5 + RED * 0.5, "translucent top");
}

#[test]
fn metallic_blends_like_albedo() {
    let (mut scene, camera) = ambient_wall();
    scene.materials.push(Material {
        base_color_factor: RED.extend(0.5),
        metallic_factor: 1.0,
        roughness_factor: 0.8,
        ..Default::default()
    });
    scene.decals = vec![decal(1, 0, 1.0)];
    // Albedo 0.5 RED + 0.5 WALL, metallic 0.5: as a wall of that material without decals.
    let (mut blended, _) = ambient_wall();
    blended.materials[0].base_color_factor = (RED * 0.5 + WALL_COLOR * 0.5).extend(1.0);
    blended.materials[0].metallic_factor = 0.5;
    let centre = |scene: &Scene, method| {
        let hdr = render_with(scene, &camera, RenderConfig { decal_method: method, ..config(64, 36, LightMethod::Brute) }).1;
        Vec4::from(pixel(&hdr, 32, 18)).truncate()
    };
    let expected = centre(&blended, DecalMethod::Off);
    for method in BLENDING_METHODS {
        let decaled = centre(&scene, method);
        assert!((decaled - expected).abs().max_element() <= 1e-4, "{}: {decaled} vs {expected}", method.name());
    }
}

/// A scene lit by one point light in front of the wall, where roughness and normals show.
fn lit_wall() -> (Scene, Camera) {
    let (mut scene, camera) = ambient_wall();
    scene.ambient = Vec3::ZERO;
    scene.lights = vec![point_light(Vec3::new(0.6, 0.4, 1.5), 8.0, 10.0)];
    (scene, camera)
}

fn render_lit(scene: &Scene, camera: &Camera, method: DecalMethod) -> manylights::renderer::Image<[f32; 4]> {
    render_with(scene, camera, RenderConfig { decal_method: method, ..config(64, 36, LightMethod::Brute) }).1
}

/// Largest difference inside the decal's footprint (the middle of the image).
fn centre_difference(a: &manylights::renderer::Image<[f32; 4]>, b: &manylights::renderer::Image<[f32; 4]>) -> f32 {
    let mut worst = 0f32;
    for y in 12..24 {
        for x in 26..38 {
            let (p, q) = (pixel(a, x, y), pixel(b, x, y));
            worst = worst.max((0..3).map(|c| (p[c] - q[c]).abs() / q[c].abs().max(1e-3)).fold(0.0, f32::max));
        }
    }
    worst
}

#[test]
fn roughness_blends_like_albedo() {
    // A wall-coloured decal of roughness 0.2 at alpha 0.5 over roughness 0.8 looks like roughness 0.5.
    let (mut scene, camera) = lit_wall();
    scene.materials.push(Material {
        base_color_factor: WALL_COLOR.extend(0.5),
        metallic_factor: 0.0,
        roughness_factor: 0.2,
        ..Default::default()
    });
    scene.decals = vec![decal(1, 0, 1.0)];
    let (mut reference, _) = lit_wall();
    reference.materials[0].roughness_factor = 0.5;
    let expected = render_lit(&reference, &camera, DecalMethod::Brute);
    let plain = render_lit(&lit_wall().0, &camera, DecalMethod::Brute);
    assert!(centre_difference(&plain, &expected) > 0.05, "roughness 0.5 and 0.8 must look different for this test to mean anything");
    for method in BLENDING_METHODS {
        let image = render_lit(&scene, &camera, method);
        let difference = centre_difference(&image, &expected);
        assert!(difference <= 1e-3, "{}: relative difference {difference} from a roughness-0.5 wall", method.name());
    }
}

/// A 4×4 normal map of one tilted normal, in the glTF encoding.
fn tilted_normal_map(scene: &mut Scene) -> TextureRef {
    let n = Vec3::new(0.5, 0.3, 0.8).normalize();
    let texel = ((n * 0.5 + 0.5) * 255.0).round();
    let rgba = [texel.x as u8, texel.y as u8, texel.z as u8, 255];
    scene.textures.push(Texture { name: "tilted".into(), width: 4, height: 4, rgba8: rgba.repeat(16) });
    TextureRef::new(scene.textures.len() - 1, Wrap::ClampToEdge, Wrap::ClampToEdge)
}

#[test]
fn normal_decals_bend_the_normal_in_the_surface_tangent_frame() {
    // An opaque decal with a normal map, axes along the wall's tangent frame (x right, y up), shades
    // like the wall with that normal map as its own.
    let (mut scene, camera) = lit_wall();
    let normal = tilted_normal_map(&mut scene);
    scene.materials.push(Material { normal_texture: Some(normal), ..scene.materials[0].clone() });
    scene.decals = vec![decal(1, 0, 1.0)];
    let (mut reference, _) = lit_wall();
    let normal = tilted_normal_map(&mut reference);
    reference.materials[0].normal_texture = Some(normal);
    let expected = render_lit(&reference, &camera, DecalMethod::Brute);
    let plain = render_lit(&lit_wall().0, &camera, DecalMethod::Brute);
    assert!(centre_difference(&plain, &expected) > 0.05, "the normal map must change the shading for this test to mean anything");
    for method in BLENDING_METHODS {
        let image = render_lit(&scene, &camera, method);
        let difference = centre_difference(&image, &expected);
        assert!(difference <= 1e-3, "{}: relative difference {difference} from the normal-mapped wall", method.name());
    }
}

#[test]
fn decals_skip_surfaces_facing_away_and_fade_edge_on() {
    let (mut scene, camera) = ambient_wall();
    solid(&mut scene, RED, 1.0);
    // Projecting from behind the wall: its +Z faces away from the wall's normal.
    let behind = Affine3A::from_rotation_translation(Quat::from_rotation_y(std::f32::consts::PI), Vec3::ZERO)
        * Affine3A::from_scale(Vec3::new(2.0, 2.0, 0.5));
    scene.decals = vec![Decal { world_from_decal: behind, material: 1, layer: 0, weight: 1.0 }];
    for (method, centre, _) in render_methods(&scene, &camera) {
        assert!((centre - WALL_COLOR).abs().max_element() <= 1e-5, "{}: a decal facing away changed the wall to {centre}", method.name());
    }
    // Tilted 80° from the wall's normal: cos 80° ≈ 0.17 is inside the fade (full from 0.25).
    let tilted = Affine3A::from_rotation_translation(Quat::from_rotation_y(80f32.to_radians()), Vec3::ZERO)
        * Affine3A::from_scale(Vec3::new(2.0, 2.0, 2.0));
    scene.decals = vec![Decal { world_from_decal: tilted, material: 1, layer: 0, weight: 1.0 }];
    for (method, centre, _) in render_methods(&scene, &camera) {
        let red_share = (centre - WALL_COLOR).length() / (RED - WALL_COLOR).length();
        assert!(red_share > 0.05 && red_share < 0.95, "{}: an edge-on decal should be partly faded, got {red_share}", method.name());
    }
}

#[test]
fn textured_decals_sample_their_image_in_decal_space() {
    // Left half red, right half green: the decal's u runs along its +X.
    let (mut scene, camera) = ambient_wall();
    let mut rgba = Vec::new();
    for _y in 0..8 {
        for x in 0..8 {
            rgba.extend_from_slice(if x < 4 { &[255, 0, 0, 255] } else { &[0, 255, 0, 255] });
        }
    }
    image_decal(&mut scene, rgba, Wrap::ClampToEdge);
    for method in BLENDING_METHODS {
        let hdr = render_lit_ambient(&scene, &camera, method);
        let (left, right) = (pixel(&hdr, 28, 18), pixel(&hdr, 36, 18));
        assert!(left[0] > 0.9 && left[1] < 0.05, "{}: left of the decal should be red, got {left:?}", method.name());
        assert!(right[1] > 0.9 && right[0] < 0.05, "{}: right of the decal should be green, got {right:?}", method.name());
    }
}

/// Decals sample their textures clamped to the edges whatever the material's wrap modes: a decal
/// projects its image once (`shading/decals.wgsl`). Repeated, the left edge of an image whose left
/// half is red and right half green would blend in the green of its right edge.
#[test]
fn decal_textures_are_clamped_to_their_edges_whatever_their_wrap_modes() {
    let halves: Vec<u8> = (0..64).flat_map(|i| if i % 8 < 4 { [255, 0, 0, 255] } else { [0, 255, 0, 255] }).collect();
    let render = |wrap: Wrap, method: DecalMethod| {
        let (mut scene, camera) = ambient_wall();
        image_decal(&mut scene, halves.clone(), wrap);
        render_with(&scene, &camera, RenderConfig { decal_method: method, ..config(256, 144, LightMethod::Brute) }).1
    };
    let wall = render_with(&ambient_wall().0, &ambient_wall().1, config(256, 144, LightMethod::Brute)).1;
    let on_wall = |x: u32, p: [f32; 4]| (Vec4::from(p) - Vec4::from(pixel(&wall, x, 72))).abs().max_element() < 1e-4;
    for method in BLENDING_METHODS {
        // Magnified, mirrored repeat would read the texels clamping reads: repeat is the mode that differs.
        let clamped = render(Wrap::ClampToEdge, method);
        let difference = max_abs_difference(&clamped, &render(Wrap::Repeat, method));
        assert!(difference == 0.0, "{}: the decal changed by {difference} with its texture repeated", method.name());
        // The decal's leftmost pixel on the middle row, within a seventh of a texel of its edge: repeated,
        // over a third of it would be green.
        let edge = (0..256).map(|x| (x, pixel(&clamped, x, 72))).find(|&(x, p)| !on_wall(x, p)).expect("the decal is not visible").1;
        // (The environment's specular reflection adds about 0.01 to every channel.)
        assert!(edge[0] > 0.9 && edge[1] < 0.03, "{}: the decal's left edge should be red alone, got {edge:?}", method.name());
    }
}

/// An 8×8 image as the only decal over the wall's centre: its material's base colour, wrapped by `wrap`.
fn image_decal(scene: &mut Scene, rgba8: Vec<u8>, wrap: Wrap) {
    scene.textures.push(Texture { name: "decal".into(), width: 8, height: 8, rgba8 });
    let texture = TextureRef::new(scene.textures.len() - 1, wrap, wrap);
    scene.materials.push(Material {
        base_color_factor: Vec4::ONE,
        base_color_texture: Some(texture),
        metallic_factor: 0.0,
        ..Default::default()
    });
    scene.decals = vec![decal(scene.materials.len() - 1, 0, 1.0)];
}

fn render_lit_ambient(scene: &Scene, camera: &Camera, method: DecalMethod) -> manylights::renderer::Image<[f32; 4]> {
    render_with(scene, camera, RenderConfig { decal_method: method, ..config(64, 36, LightMethod::Brute) }).1
}

/// Decal textures sit in arrays of their own size: a decal looks the same whether the scene's
/// surfaces have small textures or large ones (sharing the surfaces' arrays, its image would be
/// resampled to their layer size and filtered from that).
#[test]
fn decals_look_the_same_whatever_the_size_of_the_surfaces_textures() {
    let (mut scene, camera) = ambient_wall();
    // An 8×8 image of distinct texels.
    let rgba: Vec<u8> = (0..64u32).flat_map(|i| [(i * 37 % 256) as u8, (i * 91 % 256) as u8, (i * 13 % 256) as u8, 255]).collect();
    image_decal(&mut scene, rgba, Wrap::ClampToEdge);
    // The same wall with a 1024² white texture: its colour is unchanged, its arrays' layers are 1024².
    let mut large = scene.clone();
    large.textures.push(Texture { name: "white".into(), width: 1024, height: 1024, rgba8: vec![255; 1024 * 1024 * 4] });
    large.materials[0].base_color_texture = Some(TextureRef::new(1, Wrap::Repeat, Wrap::Repeat));
    for method in BLENDING_METHODS {
        let config = RenderConfig { decal_method: method, max_texture_size: 1024, ..config(64, 36, LightMethod::Brute) };
        let (small_image, large_image) = (render_with(&scene, &camera, config.clone()).1, render_with(&large, &camera, config).1);
        let centre = pixel(&small_image, 32, 18);
        assert!((Vec3::new(centre[0], centre[1], centre[2]) - WALL_COLOR).abs().max_element() > 0.05, "the decal is not visible");
        let difference = max_abs_difference(&small_image, &large_image);
        assert!(difference <= 1e-6, "{}: the decal changed by {difference} with the surfaces' textures", method.name());
    }
}
