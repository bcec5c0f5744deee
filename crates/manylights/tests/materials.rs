//! The glTF material extensions the shading core honours (`shading/brdf.wgsl`, `material.wgsl`):
//! `KHR_materials_ior`, `KHR_materials_specular` and `KHR_materials_clearcoat` shade a wall under a
//! point light as their specifications' formulas say, computed here on the CPU, in every pipeline;
//! their textures scale their factors; `KHR_materials_unlit` shows its base colour whatever lights
//! it; and the importer reads all four from a glTF file, and `KHR_materials_transmission` with
//! `KHR_materials_volume` (rendered in `transparent.rs`). glTF's occlusion texture darkens the
//! environment's light alone, and not what traced reflections see.

mod common;

use std::f32::consts::PI;

use common::*;
use glam::{Vec3, Vec4};
use manylights::{
    scene::{ibl, AlphaMode, Clearcoat, Light, Material, Scene, Sheen, Specular, Texture, TextureRef, Transmission, Wrap},
    settings::{LightMethod, PipelineKind, RenderConfig},
};

/// The wall's material parameters the reference needs.
struct Params {
    base: Vec3,
    metallic: f32,
    roughness: f32,
    ior: f32,
    specular: f32,
    specular_color: Vec3,
    clearcoat: f32,
    clearcoat_roughness: f32,
}

impl Params {
    fn material(&self) -> Material {
        Material {
            base_color_factor: self.base.extend(1.0),
            metallic_factor: self.metallic,
            roughness_factor: self.roughness,
            specular: Specular { ior: self.ior, factor: self.specular, color_factor: self.specular_color, ..Default::default() },
            clearcoat: (self.clearcoat > 0.0).then_some(Clearcoat::untextured(self.clearcoat, self.clearcoat_roughness)),
            ..Default::default()
        }
    }
}

fn schlick(f0: Vec3, cos: f32) -> Vec3 {
    f0 + (Vec3::ONE - f0) * (1.0 - cos).powi(5)
}

/// GGX D · V (height-correlated Smith) for perceptual roughness `roughness`.
fn ggx(n_l: f32, n_v: f32, n_h: f32, roughness: f32) -> f32 {
    let alpha = roughness.max(0.045).powi(2);
    let a2 = alpha * alpha;
    let d = a2 / (PI * (n_h * n_h * (a2 - 1.0) + 1.0).powi(2));
    let gv = n_l * (n_v * n_v * (1.0 - a2) + a2).sqrt();
    let gl = n_v * (n_l * n_l * (1.0 - a2) + a2).sqrt();
    d * 0.5 / (gv + gl)
}

/// The specifications' BRDF on the CPU: `mix(dielectric, metal, metallic)` with the dielectric's
/// `fresnel_mix` of KHR_materials_specular, under KHR_materials_clearcoat's `fresnel_coat`, for the
/// wall's normal +Z, times the point light's irradiance.
fn reference(m: &Params, light: &Light, point: Vec3, eye: Vec3) -> Vec3 {
    let n = Vec3::Z;
    let to_light = light.position - point;
    let d2 = to_light.length_squared();
    let (l, v) = (to_light.normalize(), (eye - point).normalize());
    let h = (l + v).normalize();
    let (n_l, n_v, n_h, v_h) = (n.dot(l), n.dot(v), n.dot(h), v.dot(h));
    let ratio2 = d2 / (light.range * light.range);
    let irradiance = light.intensity * (1.0 - ratio2 * ratio2).clamp(0.0, 1.0).powi(2) / d2 * n_l;
    let f0 = (((m.ior - 1.0) / (m.ior + 1.0)).powi(2) * m.specular_color).min(Vec3::ONE);
    let fr = schlick(f0, v_h);
    let specular = ggx(n_l, n_v, n_h, m.roughness);
    let dielectric = m.base / PI * (1.0 - m.specular * fr.max_element()) + m.specular * fr * specular;
    let metal = schlick(m.base, v_h) * specular;
    let material = dielectric * (1.0 - m.metallic) + metal * m.metallic;
    let coat = m.clearcoat * (0.04 + 0.96 * (1.0 - n_v).powi(5));
    let coated = material * (1.0 - coat) + Vec3::splat(coat * ggx(n_l, n_v, n_h, m.clearcoat_roughness));
    coated * irradiance
}

/// The wall point under pixel (x, y) of `wall_scene`'s camera.
fn wall_point(x: u32, y: u32) -> Vec3 {
    let ndc = glam::Vec2::new((x as f32 + 0.5) / WIDTH as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / HEIGHT as f32 * 2.0);
    let half_height = 30f32.to_radians().tan() * 4.0;
    Vec3::new(ndc.x * half_height * WIDTH as f32 / HEIGHT as f32, ndc.y * half_height, 0.0)
}

/// A material whose coat alone reflects: a black base without specular reflection.
fn coat_only(coat: Clearcoat) -> Material {
    Material {
        base_color_factor: Vec4::new(0.0, 0.0, 0.0, 1.0),
        metallic_factor: 0.0,
        specular: Specular { factor: 0.0, ..Default::default() },
        clearcoat: Some(coat),
        ..Default::default()
    }
}

fn wall(material: Material, lights: Vec<Light>) -> (Scene, manylights::scene::Camera) {
    let (mut scene, camera) = wall_scene(lights);
    scene.materials[0] = material;
    (scene, camera)
}

fn frame(scene: &Scene, camera: &manylights::scene::Camera, pipeline: PipelineKind) -> manylights::renderer::Image<[f32; 4]> {
    render_with(scene, camera, RenderConfig { pipeline, ..config(WIDTH, HEIGHT, LightMethod::Brute) }).1
}

#[test]
fn ior_specular_and_clearcoat_shade_as_their_specifications_say_in_every_pipeline() {
    let light = point_light(Vec3::new(0.6, -0.3, 1.2), 3.0, 6.0);
    let plain = Params {
        base: Vec3::new(0.6, 0.3, 0.2),
        metallic: 0.0,
        roughness: 0.4,
        ior: 1.5,
        specular: 1.0,
        specular_color: Vec3::ONE,
        clearcoat: 0.0,
        clearcoat_roughness: 0.0,
    };
    let cases = [
        ("ior 2.4", Params { ior: 2.4, ..plain }),
        ("tinted, half-weight specular", Params { specular: 0.5, specular_color: Vec3::new(1.0, 0.5, 0.25), ior: 1.8, ..plain }),
        ("ior 1 (no reflection at normal incidence)", Params { ior: 1.0, ..plain }),
        (
            "clear coat over a rough half-metal",
            Params { roughness: 0.9, metallic: 0.5, clearcoat: 0.8, clearcoat_roughness: 0.15, ..plain },
        ),
    ];
    let pixels = [(WIDTH / 2, HEIGHT / 2), (150, 60), (170, 85), (60, 110)];
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        let (scene, camera) = wall(plain.material(), vec![light]);
        let base_image = frame(&scene, &camera, pipeline);
        for (name, params) in &cases {
            let (scene, camera) = wall(params.material(), vec![light]);
            let image = frame(&scene, &camera, pipeline);
            let mut changed = false;
            for (x, y) in pixels {
                let expected = reference(params, &light, wall_point(x, y), camera.position());
                let got = Vec4::from(pixel(&image, x, y)).truncate();
                let error = (got - expected).abs().max_element() / expected.max_element().max(1e-4);
                // The deferred G-buffer keeps the surface in 8 and 16 bits.
                let tolerance = if pipeline == PipelineKind::Deferred { 0.02 } else { 0.005 };
                assert!(error < tolerance, "{} {name} at ({x}, {y}): GPU {got}, reference {expected}", pipeline.name());
                changed |= (got - Vec4::from(pixel(&base_image, x, y)).truncate()).abs().max_element() > 0.01 * expected.max_element();
            }
            assert!(changed, "{} {name}: the image is the plain material's", pipeline.name());
        }
    }
}

#[test]
fn the_extensions_textures_scale_their_factors() {
    // One-texel textures: a value v in a texture times a factor f shades as the factor f · v.
    let texel = |rgba: [u8; 4]| Texture { name: "texel".into(), width: 1, height: 1, rgba8: rgba.to_vec() };
    let textured = Material {
        base_color_factor: Vec4::new(0.5, 0.5, 0.5, 1.0),
        metallic_factor: 0.0,
        roughness_factor: 0.5,
        specular: Specular {
            ior: 1.5,
            factor: 1.0,
            texture: Some(TextureRef::new(0, Wrap::Repeat, Wrap::Repeat)),
            color_factor: Vec3::ONE,
            color_texture: Some(TextureRef::new(1, Wrap::Repeat, Wrap::Repeat)),
        },
        clearcoat: Some(Clearcoat {
            factor: 1.0,
            texture: Some(TextureRef::new(2, Wrap::Repeat, Wrap::Repeat)),
            roughness_factor: 1.0,
            roughness_texture: Some(TextureRef::new(2, Wrap::Repeat, Wrap::Repeat)),
            normal_texture: None,
            normal_scale: 1.0,
        }),
        ..Default::default()
    };
    let light = point_light(Vec3::new(0.2, 0.1, 1.0), 3.0, 6.0);
    let (mut scene, camera) = wall(textured.clone(), vec![light]);
    // Specular weight 0.6 (alpha); colour (1, 0.5, 0.5) in sRGB; clearcoat 0.4 (R), its roughness 0.2 (G).
    scene.textures = vec![texel([0, 0, 0, 153]), texel([255, 188, 188, 255]), texel([102, 51, 0, 255])];
    let srgb = |c: f32| ((c + 0.055) / 1.055).powf(2.4);
    let factors = Material {
        specular: Specular { factor: 0.6, color_factor: Vec3::new(1.0, srgb(188.0 / 255.0), srgb(188.0 / 255.0)), ..Default::default() },
        clearcoat: Some(Clearcoat::untextured(0.4, 0.2)),
        ..textured
    };
    let (reference_scene, _) = wall(factors, vec![light]);
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        let (got, expected) = (frame(&scene, &camera, pipeline), frame(&reference_scene, &camera, pipeline));
        let peak = expected.pixels.iter().map(|&p| luminance(p)).fold(0.0, f32::max);
        let difference = max_abs_difference(&got, &expected);
        assert!(difference < 0.01 * peak, "{}: textures and factors differ by {difference} (peak {peak})", pipeline.name());
    }
}

#[test]
fn a_clearcoat_normal_map_tilts_the_coat_as_tilted_geometry_does() {
    // Only the coat reflects (black base, no specular): its normal from a one-texel normal map on a
    // flat wall shades as the wall whose vertex normals are that normal, without the map.
    let coated = |normal_texture| coat_only(Clearcoat { normal_texture, ..Clearcoat::untextured(1.0, 0.3) });
    let light = point_light(Vec3::new(0.2, 0.1, 1.0), 3.0, 6.0);
    let texel = [200u8, 128, 230, 255];
    let (mut mapped, camera) = wall(coated(Some(TextureRef::new(0, Wrap::Repeat, Wrap::Repeat))), vec![light]);
    mapped.textures = vec![Texture { name: "normal".into(), width: 1, height: 1, rgba8: texel.to_vec() }];
    // The wall's tangent frame is (+X, +Y, +Z) in the world; its vertex normals go through the
    // inverse transpose of its scale, so the world's tilted normal is scaled by it into the mesh.
    let tilted = Vec3::new(f32::from(texel[0]), f32::from(texel[1]), f32::from(texel[2])) / 255.0 * 2.0 - Vec3::ONE;
    let (mut geometry, _) = wall(coated(None), vec![light]);
    let scale = geometry.instances[0].world_from_local.to_scale_rotation_translation().0;
    for v in &mut geometry.meshes[0].primitives[0].vertices {
        v.normal = (tilted * scale).normalize().to_array();
    }
    let (flat, _) = wall(coated(None), vec![light]);
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        let (got, expected) = (frame(&mapped, &camera, pipeline), frame(&geometry, &camera, pipeline));
        let peak = expected.pixels.iter().map(|&p| luminance(p)).fold(0.0, f32::max);
        let difference = max_abs_difference(&got, &expected);
        assert!(difference < 0.01 * peak, "{}: the mapped coat differs from the tilted one by {difference} (peak {peak})", pipeline.name());
        assert!(max_abs_difference(&got, &frame(&flat, &camera, pipeline)) > 0.1 * peak, "{}: the map tilts nothing", pipeline.name());
    }
}

#[test]
fn a_clear_coat_reflects_the_environment_by_its_fresnel_and_the_split_sum() {
    // Only the coat reflects a uniform white environment: at normal incidence it sends 4 % of the
    // split-sum's directional albedo for its roughness (scale + bias at F0 = 1), in every pipeline.
    let roughness = 0.5;
    let (mut scene, camera) = wall(coat_only(Clearcoat::untextured(1.0, roughness)), vec![]);
    scene.ambient = Vec3::ONE;
    // The table's texels at n·v → 1 (its last column, where the lookup clamps) and the two rows
    // either side of roughness 0.5, which a bilinear lookup averages.
    let size = manylights::scene::ibl::BRDF_TABLE_SIZE as usize;
    let table = manylights::scene::ibl::brdf_table();
    let albedo = |row: usize| table[row * size + size - 1][0] + table[row * size + size - 1][1];
    let expected = 0.04 * 0.5 * (albedo(size / 2 - 1) + albedo(size / 2));
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        let got = pixel(&frame(&scene, &camera, pipeline), WIDTH / 2, HEIGHT / 2)[1];
        assert!((got - expected).abs() < 0.02 * expected, "{}: coat reflects {got}, the split sum says {expected}", pipeline.name());
    }
}

#[test]
fn the_core_material_shades_alike_on_the_core_and_the_extended_path() {
    // A scene whose materials use no extension compiles the core path alone
    // (`ShadingMethods::material_extensions`); an unused coated material switches the extended path
    // on, and the core material must look the same through it.
    let light = point_light(Vec3::new(0.6, -0.3, 1.2), 3.0, 6.0);
    let plain =
        Material { base_color_factor: Vec4::new(0.6, 0.3, 0.2, 1.0), metallic_factor: 0.3, roughness_factor: 0.4, ..Default::default() };
    let (core, camera) = wall(plain, vec![light]);
    let mut extended = core.clone();
    extended.materials.push(Material { clearcoat: Some(Clearcoat::untextured(1.0, 0.1)), ..Default::default() });
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        let (a, b) = (frame(&core, &camera, pipeline), frame(&extended, &camera, pipeline));
        let difference = max_abs_difference(&a, &b);
        assert!(difference < 1e-5, "{}: the paths differ by {difference}", pipeline.name());
    }
}

#[test]
fn unlit_materials_show_their_base_colour_whatever_lights_them() {
    let color = Vec3::new(0.2, 0.5, 0.8);
    let unlit = Material { base_color_factor: color.extend(1.0), unlit: true, ..Default::default() };
    let (mut scene, camera) = wall(unlit, vec![point_light(Vec3::new(0.0, 0.0, 1.0), 5.0, 6.0)]);
    scene.ambient = Vec3::splat(0.7);
    scene.sun = Some(manylights::scene::Sun { direction: Vec3::new(0.0, -0.5, -1.0), color: Vec3::ONE, illuminance: 4.0 });
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        let image = frame(&scene, &camera, pipeline);
        for p in &image.pixels {
            let got = Vec4::from(*p).truncate();
            // The deferred G-buffer keeps the base colour in 8-bit sRGB.
            assert!((got - color).abs().max_element() < 5e-3, "{}: {got}, not {color}", pipeline.name());
        }
    }
}

/// A uniform occlusion texture: R = 64/255 everywhere (G and B differ, as packed textures' do).
fn occlusion_texture() -> Texture {
    Texture { name: "occlusion".into(), width: 1, height: 1, rgba8: vec![64, 200, 10, 255] }
}

fn occluded(scene: &mut Scene, material: usize, strength: f32) {
    scene.textures = vec![occlusion_texture()];
    scene.materials[material].occlusion_texture = Some(TextureRef::new(0, Wrap::Repeat, Wrap::Repeat));
    scene.materials[material].occlusion_strength = strength;
}

#[test]
fn occlusion_darkens_the_environments_light_and_not_the_lights_in_every_pipeline() {
    // A wall in a uniform environment with a point light: the environment's part of its radiance
    // scales by 1 + strength × (R − 1); the light's stays.
    let light = point_light(Vec3::new(0.5, 0.3, 1.0), 2.0, 5.0);
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        let config = RenderConfig { pipeline, ..config(WIDTH, HEIGHT, LightMethod::Brute) };
        let (ambient_only, camera) = ambient_wall();
        let environment = render_with(&ambient_only, &camera, config.clone()).1;
        let mut light_only = ambient_only.clone();
        light_only.ambient = Vec3::ZERO;
        light_only.lights = vec![light];
        let direct = render_with(&light_only, &camera, config.clone()).1;
        for strength in [1.0, 0.6] {
            let mut scene = ambient_only.clone();
            scene.lights = vec![light];
            occluded(&mut scene, 0, strength);
            let image = render_with(&scene, &camera, config.clone()).1;
            let k = 1.0 + strength * (64.0 / 255.0 - 1.0);
            for (i, p) in image.pixels.iter().enumerate() {
                let expected = Vec4::from(environment.pixels[i]).truncate() * k + Vec4::from(direct.pixels[i]).truncate();
                let got = Vec4::from(*p).truncate();
                assert!(
                    (got - expected).abs().max_element() < 2e-3,
                    "{} strength {strength}, pixel {i}: {got}, expected {expected}",
                    pipeline.name()
                );
            }
        }
    }
}

#[test]
fn deferred_decals_keep_the_g_buffers_occlusion() {
    // A half-transparent decal over the occluded wall: blended into the G-buffer, it must leave the
    // occlusion in the albedo's alpha as decals applied at shading do.
    let (mut scene, camera) = ambient_wall();
    occluded(&mut scene, 0, 1.0);
    scene.materials.push(Material { base_color_factor: Vec4::new(0.9, 0.1, 0.1, 0.5), metallic_factor: 0.0, ..Default::default() });
    let world_from_decal = glam::Affine3A::from_scale_rotation_translation(Vec3::new(3.0, 3.0, 1.0), glam::Quat::IDENTITY, Vec3::ZERO);
    scene.decals.push(manylights::scene::Decal { world_from_decal, material: 1, layer: 0, weight: 1.0 });
    let frame = |decal_method| {
        let config = RenderConfig { pipeline: PipelineKind::Deferred, decal_method, ..config(WIDTH, HEIGHT, LightMethod::Off) };
        render_with(&scene, &camera, config).1
    };
    let (bvh, deferred) = (frame(manylights::settings::DecalMethod::Bvh), frame(manylights::settings::DecalMethod::DeferredDecals));
    let centre = Vec4::from(pixel(&bvh, WIDTH / 2, HEIGHT / 2));
    assert!(centre.x > 2.0 * centre.y, "the decal does not tint the wall: {centre}");
    let difference = max_abs_difference(&bvh, &deferred);
    assert!(difference <= 0.01, "deferred decals differ from bvh decals by {difference} over an occluded wall");
}

#[test]
fn a_traced_reflection_is_not_darkened_by_occlusion() {
    // A mirror under a uniform sky: without traced reflections occlusion darkens the prefiltered
    // sky it reflects; traced, the mirror shows the sky its rays reach, occluded or not.
    let (mut plain, camera) = ambient_wall();
    plain.materials[0].metallic_factor = 1.0;
    plain.materials[0].roughness_factor = 0.0;
    plain.materials[0].base_color_factor = Vec4::ONE;
    let mut scene = plain.clone();
    occluded(&mut scene, 0, 1.0);
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        let frame = |scene: &Scene, bounces: u32| {
            let rays = manylights::settings::RaySettings { reflection_bounces: bounces, ..Default::default() };
            render_with(scene, &camera, RenderConfig { pipeline, rays, ..config(WIDTH, HEIGHT, LightMethod::Off) }).1
        };
        let name = pipeline.name();
        let (prefiltered, prefiltered_occluded) = (frame(&plain, 0), frame(&scene, 0));
        let centre = |image: &manylights::renderer::Image<[f32; 4]>| luminance(pixel(image, WIDTH / 2, HEIGHT / 2));
        let ratio = centre(&prefiltered_occluded) / centre(&prefiltered);
        assert!((ratio - 64.0 / 255.0).abs() < 0.01, "{name}: occlusion scaled the prefiltered sky by {ratio}");
        let difference = max_abs_difference(&frame(&plain, 1), &frame(&scene, 1));
        assert!(difference < 2e-3, "{name}: occlusion changed the traced reflection by {difference}");
    }
}

#[test]
fn the_importer_reads_occlusion_on_the_first_two_coordinates_and_refuses_a_bad_strength() {
    let gltf = |materials: &str| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_texture_transform"], "materials": [{materials}], "textures": [{{"source": 0}}],
            "images": [{{"uri": "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg=="}}]}}"#
        )
    };
    let import = |json: String| import_gltf_json(&json);
    let scene = import(gltf(
        r#"{"occlusionTexture": {"index": 0, "strength": 0.3}}, {"occlusionTexture": {"index": 0, "texCoord": 1}},
           {"occlusionTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"texCoord": 1}}}},
           {"occlusionTexture": {"index": 0, "texCoord": 2}}"#,
    ))
    .unwrap();
    let occlusion: Vec<_> = scene.materials.iter().map(|m| (m.occlusion_texture.map(|t| t.tex_coord), m.occlusion_strength)).collect();
    // TEXCOORD_1 by texCoord or by the transform's override; past it the texture is left out.
    assert_eq!(occlusion, vec![(Some(0), 0.3), (Some(1), 1.0), (Some(1), 1.0), (None, 1.0)]);
    let error = import(gltf(r#"{"occlusionTexture": {"index": 0, "strength": 1.5}}"#)).unwrap_err().to_string();
    assert!(error.contains("occlusion strength 1.5"), "{error}");
}

#[test]
fn the_importer_reads_the_material_extensions() {
    let json = r#"{"asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_materials_ior", "KHR_materials_specular", "KHR_materials_clearcoat", "KHR_materials_unlit"],
        "materials": [
            {"extensions": {"KHR_materials_ior": {"ior": 1.7},
                            "KHR_materials_specular": {"specularFactor": 0.3, "specularColorFactor": [1.0, 0.8, 0.6]},
                            "KHR_materials_clearcoat": {"clearcoatFactor": 0.9, "clearcoatRoughnessFactor": 0.25}}},
            {"extensions": {"KHR_materials_unlit": {}}}
        ]}"#;
    let scene = import_gltf_json(json).unwrap();
    let (coated, unlit) = (&scene.materials[0], &scene.materials[1]);
    assert_eq!((coated.specular.ior, coated.specular.factor), (1.7, 0.3));
    assert_eq!(coated.specular.color_factor, Vec3::new(1.0, 0.8, 0.6));
    let coat = coated.clearcoat.expect("a clear coat");
    assert_eq!((coat.factor, coat.roughness_factor), (0.9, 0.25));
    assert!(!coated.unlit && unlit.unlit && unlit.clearcoat.is_none());
}

#[test]
fn the_importer_reads_transmission_its_medium_and_dispersion() {
    let gltf = |materials: &str| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_volume", "KHR_materials_dispersion"],
            "materials": [{materials}], "textures": [{{"source": 0}}],
            "images": [{{"uri": "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg=="}}]}}"#
        )
    };
    let scene = import_gltf_json(&gltf(
        r#"{"extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.8, "transmissionTexture": {"index": 0}},
                           "KHR_materials_volume": {"thicknessFactor": 0.2, "thicknessTexture": {"index": 0, "texCoord": 1},
                                                    "attenuationDistance": 0.5, "attenuationColor": [0.9, 0.6, 0.3]},
                           "KHR_materials_dispersion": {"dispersion": 0.4}}},
           {"extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}},
           {"extensions": {"KHR_materials_transmission": {}}}"#,
    ))
    .unwrap();
    let glass = scene.materials[0].transmission.expect("transmission");
    assert_eq!((glass.factor, glass.thickness_factor, glass.attenuation_distance), (0.8, 0.2, 0.5));
    assert_eq!((glass.attenuation_color, glass.dispersion), (Vec3::new(0.9, 0.6, 0.3), 0.4));
    assert_eq!((glass.texture.map(|t| t.tex_coord), glass.thickness_texture.map(|t| t.tex_coord)), (Some(0), Some(1)));
    // Without KHR_materials_volume a surface is thin-walled and clear; a factor of 0 lets nothing through.
    assert_eq!(scene.materials[1].transmission, Some(Transmission::thin(1.0)));
    assert!(scene.materials[2].transmission.is_none() && scene.materials.iter().all(|m| m.alpha_mode == AlphaMode::Opaque));
    for (bad, named) in [
        (r#""KHR_materials_transmission": {"transmissionFactor": 1.5}"#, "transmission factor 1.5"),
        (
            r#""KHR_materials_transmission": {"transmissionFactor": 1}, "KHR_materials_volume": {"attenuationDistance": 0}"#,
            "attenuation distance 0",
        ),
        (r#""KHR_materials_transmission": {"transmissionFactor": 1}, "KHR_materials_volume": {"thicknessFactor": -1}"#, "thickness -1"),
        (r#""KHR_materials_transmission": {"transmissionFactor": 1}, "KHR_materials_dispersion": {"dispersion": -2}"#, "dispersion -2"),
    ] {
        let error = import_gltf_json(&gltf(&format!(r#"{{"extensions": {{{bad}}}}}"#))).unwrap_err().to_string();
        assert!(error.contains(named), "{error}");
    }
}

/// A sheen whose colour and roughness the deferred G-buffer keeps exactly (√ colour and roughness in
/// 8 bits): 0.64 = (204/255)², 0.36 = (153/255)², 0.6 = 153/255.
const SHEEN: Sheen =
    Sheen { color_factor: Vec3::new(0.64, 0.36, 1.0), color_texture: None, roughness_factor: 0.6, roughness_texture: None };

/// KHR_materials_sheen over `below` (the BRDF times the light's irradiance, and n·l, n·v, n·h at the
/// point): the Charlie lobe added, the rest scaled by what the sheen leaves.
fn sheened(below: Vec3, sheen: &Sheen, (n_l, n_v, n_h): (f32, f32, f32), irradiance: f32) -> Vec3 {
    let r = sheen.roughness_factor;
    let leaves = 1.0 - sheen.color_factor.max_element() * ibl::sheen_albedo(n_v, r).max(ibl::sheen_albedo(n_l, r));
    below * leaves + sheen.color_factor * ibl::d_charlie(n_h, r) * ibl::v_sheen(n_v, n_l, r) * n_l * irradiance
}

#[test]
fn a_sheen_shades_as_its_specification_says_under_lights_and_the_environment_in_every_pipeline() {
    // A light low over the wall, where the sheen shows most.
    let light = point_light(Vec3::new(0.4, -0.2, 0.35), 1.0, 6.0);
    let plain = Params {
        base: Vec3::new(0.3, 0.5, 0.2),
        metallic: 0.0,
        roughness: 0.7,
        ior: 1.5,
        specular: 1.0,
        specular_color: Vec3::ONE,
        clearcoat: 0.0,
        clearcoat_roughness: 0.0,
    };
    let coated = Params { clearcoat: 0.6, clearcoat_roughness: 0.2, ..plain };
    let pixels = [(WIDTH / 2, HEIGHT / 2), (150, 60), (170, 85), (60, 110)];
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        let name = pipeline.name();
        // The deferred G-buffer keeps the surface in 8 and 16 bits.
        let tolerance = if pipeline == PipelineKind::Deferred { 0.02 } else { 0.005 };
        for params in [&plain, &coated] {
            let (bare, camera) = wall(params.material(), vec![light]);
            let (scene, _) = wall(Material { sheen: Some(SHEEN), ..params.material() }, vec![light]);
            let (image, bare_image) = (frame(&scene, &camera, pipeline), frame(&bare, &camera, pipeline));
            for (x, y) in pixels {
                let point = wall_point(x, y);
                let (l, v) = ((light.position - point).normalize(), (camera.position() - point).normalize());
                let cosines = (l.z, v.z, (l + v).normalize().z);
                let d2 = (light.position - point).length_squared();
                let irradiance = light.intensity * (1.0 - (d2 / (light.range * light.range)).powi(2)).clamp(0.0, 1.0).powi(2) / d2;
                let uncoated = Params { clearcoat: 0.0, ..*params };
                let under_coat = sheened(reference(&uncoated, &light, point, camera.position()), &SHEEN, cosines, irradiance);
                let coat = params.clearcoat * (0.04 + 0.96 * (1.0 - v.z).powi(5));
                let coat_lobe = reference(&Params { base: Vec3::ZERO, specular: 0.0, ..*params }, &light, point, camera.position());
                // The coat lies over the sheen: its share is taken from the sheen's result.
                let expected = under_coat * (1.0 - coat) + coat_lobe;
                let got = Vec4::from(pixel(&image, x, y)).truncate();
                let error = (got - expected).abs().max_element() / expected.max_element();
                let coated = params.clearcoat > 0.0;
                assert!(error < tolerance, "{name}, coated {coated}, ({x}, {y}): GPU {got}, reference {expected}");
                let bare = Vec4::from(pixel(&bare_image, x, y)).truncate();
                assert!((got - bare).abs().max_element() > 0.05 * expected.max_element(), "{name} ({x}, {y}): no sheen to see");
            }
        }

        // A glossy sheen in a uniform environment, facing a black panel behind the eye: traced
        // reflections see black where the prefiltered environment held white, so they take away
        // exactly the specular albedo below the sheen (F0 × scale + F90 × bias × what it leaves).
        let glossy = Material { sheen: Some(SHEEN), roughness_factor: 0.2, ..plain.material() };
        let (mut scene, camera) = wall(glossy, vec![]);
        scene.ambient = Vec3::ONE;
        scene.materials.push(Material { base_color_factor: Vec4::new(0.0, 0.0, 0.0, 1.0), unlit: true, ..Default::default() });
        let mut panel = scene.meshes[0].clone();
        panel.primitives[0].material = 1;
        scene.meshes.push(panel);
        let facing_the_wall = glam::Mat4::from_translation(Vec3::new(0.0, 0.0, 5.0)) * glam::Mat4::from_rotation_y(PI);
        scene
            .instances
            .push(manylights::scene::Instance { mesh: 1, world_from_local: facing_the_wall * glam::Mat4::from_scale(Vec3::splat(20.0)) });
        let rays = manylights::settings::RaySettings { reflection_bounces: 1, reflection_roughness: 1.0, ..Default::default() };
        let traced = render_with(&scene, &camera, RenderConfig { pipeline, rays, ..config(WIDTH, HEIGHT, LightMethod::Brute) }).1;
        let untraced = frame(&scene, &camera, pipeline);
        let (x, y) = (WIDTH / 2, HEIGHT / 2);
        let n_v = (camera.position() - wall_point(x, y)).normalize().z;
        // The split-sum table bilinear at roughness 0.2, in its last column (n·v → 1, where it clamps).
        let size = ibl::BRDF_TABLE_SIZE as usize;
        let row = 0.2 * size as f32 - 0.5;
        let (j, t) = (row.floor() as usize, row.fract());
        let albedo = |j: usize| 0.04 * ibl::brdf_table()[j * size + size - 1][0] + ibl::brdf_table()[j * size + size - 1][1];
        let specular = (albedo(j) * (1.0 - t) + albedo(j + 1) * t) * (1.0 - SHEEN.color_factor.max_element() * ibl::sheen_albedo(n_v, 0.6));
        let taken = Vec4::from(pixel(&untraced, x, y)).truncate() - Vec4::from(pixel(&traced, x, y)).truncate();
        assert!(
            (taken - Vec3::splat(specular)).abs().max_element() < 0.03 * specular,
            "{name}: traced reflections take {taken}, expected {specular}"
        );

        // A uniform white environment alone: the sheen reflects its albedo, the base colour what it leaves.
        let matte = Material { sheen: Some(SHEEN), specular: Specular { factor: 0.0, ..Default::default() }, ..plain.material() };
        let (mut scene, camera) = wall(matte, vec![]);
        scene.ambient = Vec3::ONE;
        let image = frame(&scene, &camera, pipeline);
        for (x, y) in pixels {
            let n_v = (camera.position() - wall_point(x, y)).normalize().z;
            let albedo = ibl::sheen_albedo(n_v, SHEEN.roughness_factor);
            let expected = plain.base * (1.0 - SHEEN.color_factor.max_element() * albedo) + SHEEN.color_factor * albedo;
            let got = Vec4::from(pixel(&image, x, y)).truncate();
            let error = (got - expected).abs().max_element() / expected.max_element();
            assert!(error < tolerance, "{name} in the environment at ({x}, {y}): GPU {got}, reference {expected}");
        }
    }
}

#[test]
fn the_importer_reads_sheen() {
    let gltf = |materials: &str| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_materials_sheen"],
            "materials": [{materials}], "textures": [{{"source": 0}}],
            "images": [{{"uri": "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg=="}}]}}"#
        )
    };
    let scene = import_gltf_json(&gltf(
        r#"{"extensions": {"KHR_materials_sheen": {"sheenColorFactor": [0.9, 0.5, 0.1], "sheenColorTexture": {"index": 0},
                                                   "sheenRoughnessFactor": 0.4, "sheenRoughnessTexture": {"index": 0, "texCoord": 1}}}},
           {"extensions": {"KHR_materials_sheen": {"sheenRoughnessFactor": 0.4}}}"#,
    ))
    .unwrap();
    let sheen = scene.materials[0].sheen.expect("a sheen");
    assert_eq!((sheen.color_factor, sheen.roughness_factor), (Vec3::new(0.9, 0.5, 0.1), 0.4));
    assert_eq!((sheen.color_texture.map(|t| t.tex_coord), sheen.roughness_texture.map(|t| t.tex_coord)), (Some(0), Some(1)));
    // The colour texture is sRGB colour, the roughness texture linear data.
    let uses: Vec<bool> = scene.materials[0].textures().map(|(_, srgb)| srgb).collect();
    assert_eq!(uses, [true, false]);
    // A black sheen (the default colour) is none.
    assert!(scene.materials[1].sheen.is_none());
    let error =
        import_gltf_json(&gltf(r#"{"extensions": {"KHR_materials_sheen": {"sheenColorFactor": [1.5, 0, 0]}}}"#)).unwrap_err().to_string();
    assert!(error.contains("sheen colour [1.5, 0.0, 0.0]"), "{error}");
}
