//! The built-in procedural scene, the default of `manylights render`: needs no files and loads
//! instantly.
//!
//! A corner of a room about 10 m across: a tiled floor (procedural colour and normal maps), a back
//! and a side wall, boxes and spheres of varied materials (rough dielectric, gold, red plastic, a
//! glowing sphere, a striped metal/dielectric block), a perforated alpha-masked panel and a crate
//! mesh placed twice. A low warm sun, coloured point lights and two spot lights make pools of light
//! on the walls and floor; one camera frames it all at 16:9.

use std::f32::consts::PI;

use glam::{Mat4, Quat, Vec3, Vec4};

use super::{
    tangents, AlphaMode, Camera, Instance, Light, LightKind, Material, Mesh, Primitive, Scene, Sun, Texture, TextureRef, Vertex, Wrap,
};

/// Builds the demo scene. Deterministic: every call returns the same scene.
pub fn demo_scene() -> Scene {
    let textures = vec![tile_colour(), tile_normal(), metal_stripes(), perforated_paint()];
    let materials = materials();
    let meshes = vec![
        mesh("floor", plane(10.0, 10.0, 5.0), FLOOR),
        mesh("wall", plane(10.0, 5.0, 1.0), PLASTER),
        mesh("crate", cuboid(Vec3::ONE), CRATE),
        mesh("gold sphere", sphere(0.8), GOLD),
        mesh("plastic sphere", sphere(0.6), RED_PLASTIC),
        mesh("glowing sphere", sphere(0.25), GLOW),
        mesh("striped block", cuboid(Vec3::new(1.4, 0.8, 0.8)), STRIPES),
        mesh("perforated panel", plane(2.0, 2.0, 1.0), PANEL),
    ];
    let place = |mesh: usize, world_from_local: Mat4| Instance { mesh, world_from_local };
    let turn = |degrees: f32| Quat::from_rotation_y(degrees.to_radians());
    let instances = vec![
        place(0, Mat4::IDENTITY),
        place(1, upright(Vec3::Z, Vec3::new(0.0, 2.5, -5.0))),
        place(1, upright(Vec3::X, Vec3::new(-5.0, 2.5, 0.0))),
        // The crate mesh twice: a second, smaller crate stacked on the first.
        place(2, Mat4::from_rotation_translation(turn(20.0), Vec3::new(-3.3, 0.5, -3.3))),
        place(2, Mat4::from_scale_rotation_translation(Vec3::splat(0.7), turn(55.0), Vec3::new(-3.3, 1.35, -3.3))),
        place(3, Mat4::from_translation(Vec3::new(-0.6, 0.8, -2.2))),
        place(4, Mat4::from_translation(Vec3::new(1.9, 0.6, -0.2))),
        place(5, Mat4::from_translation(Vec3::new(-1.4, 0.25, 1.4))),
        place(6, Mat4::from_rotation_translation(turn(-15.0), Vec3::new(1.6, 0.4, -3.4))),
        place(7, upright(Vec3::new(-0.6, 0.0, 1.0).normalize(), Vec3::new(3.4, 1.0, -1.4))),
    ];
    let lights = lights();
    Scene {
        meshes,
        materials,
        textures,
        instances,
        authored_lights: lights.len(),
        lights,
        cameras: vec![Camera::look_at("demo", Vec3::new(4.6, 3.1, 7.2), Vec3::new(-0.6, 0.9, -1.4), 52f32.to_radians(), 0.05)],
        sun: Some(Sun { direction: Vec3::new(-0.45, -0.35, -0.82).normalize(), color: Vec3::new(1.0, 0.82, 0.62), illuminance: 2.5 }),
        ambient: Vec3::new(0.025, 0.03, 0.04),
        ..Scene::default()
    }
}

// Material indices, in the order `materials()` returns them.
const FLOOR: usize = 0;
const PLASTER: usize = 1;
const CRATE: usize = 2;
const GOLD: usize = 3;
const RED_PLASTIC: usize = 4;
const GLOW: usize = 5;
const STRIPES: usize = 6;
const PANEL: usize = 7;

// Texture indices, in the order `demo_scene()` lists them.
const TILE_COLOUR: usize = 0;
const TILE_NORMAL: usize = 1;
const METAL_STRIPES: usize = 2;
const PERFORATED_PAINT: usize = 3;

fn materials() -> Vec<Material> {
    let repeat = |texture| Some(TextureRef::new(texture, Wrap::Repeat, Wrap::Repeat));
    let dielectric = |name: &str, rgb: [f32; 3], roughness_factor| Material {
        name: name.into(),
        base_color_factor: Vec3::from(rgb).extend(1.0),
        metallic_factor: 0.0,
        roughness_factor,
        ..Material::default()
    };
    vec![
        Material {
            base_color_texture: repeat(TILE_COLOUR),
            normal_texture: repeat(TILE_NORMAL),
            ..dielectric("floor tiles", [1.0; 3], 0.55)
        },
        dielectric("plaster", [0.8, 0.78, 0.74], 0.9),
        dielectric("crate", [0.55, 0.42, 0.3], 0.85),
        Material { metallic_factor: 1.0, ..dielectric("gold", [1.0, 0.78, 0.34], 0.3) },
        dielectric("red plastic", [0.8, 0.08, 0.06], 0.35),
        Material { emissive_factor: Vec3::new(4.0, 1.6, 0.4), ..dielectric("glow", [0.1; 3], 0.5) },
        Material {
            name: "striped metal".into(),
            base_color_factor: Vec4::new(0.75, 0.75, 0.78, 1.0),
            metallic_roughness_texture: repeat(METAL_STRIPES),
            // Factors of 1 let the texture alone decide metallic and roughness.
            ..Material::default()
        },
        Material {
            base_color_texture: repeat(PERFORATED_PAINT),
            alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
            double_sided: true,
            ..dielectric("perforated paint", [1.0; 3], 0.6)
        },
    ]
}

fn lights() -> Vec<Light> {
    let point = |position: [f32; 3], color: [f32; 3], intensity, range| Light {
        kind: LightKind::Point,
        position: Vec3::from(position),
        direction: Vec3::NEG_Y,
        color: Vec3::from(color),
        intensity,
        range,
        cast_shadows: true,
    };
    let spot = |position: Vec3, target: Vec3, cone_degrees: (f32, f32), color: [f32; 3], intensity, range| Light {
        kind: LightKind::Spot { inner_cone_angle: cone_degrees.0.to_radians(), outer_cone_angle: cone_degrees.1.to_radians() },
        position,
        direction: (target - position).normalize(),
        color: Vec3::from(color),
        intensity,
        range,
        cast_shadows: true,
    };
    vec![
        point([-2.0, 1.6, -4.4], [1.0, 0.55, 0.2], 3.5, 7.0),
        point([2.6, 2.2, -4.4], [0.2, 0.7, 1.0], 3.5, 7.0),
        point([-4.4, 1.2, 0.8], [0.3, 1.0, 0.35], 3.0, 6.0),
        point([0.6, 0.5, 2.6], [1.0, 0.25, 0.8], 2.0, 5.0),
        // Just above the glowing sphere, so that it appears to light its surroundings.
        point([-1.4, 0.75, 1.4], [1.0, 0.5, 0.15], 2.0, 5.0),
        // Pools on the floor, around the red sphere and in front of the crates.
        spot(Vec3::new(1.9, 4.2, 1.2), Vec3::new(2.1, 0.0, 0.4), (14.0, 24.0), [1.0, 0.95, 0.85], 80.0, 9.0),
        spot(Vec3::new(-3.0, 4.0, 1.0), Vec3::new(-2.6, 0.0, -1.8), (12.0, 22.0), [0.75, 0.85, 1.0], 70.0, 10.0),
    ]
}

/// Places a plane made by [`plane`] upright, facing `normal` (horizontal), centred at `center`.
fn upright(normal: Vec3, center: Vec3) -> Mat4 {
    let x = Vec3::Y.cross(normal).normalize();
    // Local z (the plane's depth) becomes -Y, so the frame stays right-handed.
    Mat4::from_cols(x.extend(0.0), normal.extend(0.0), x.cross(normal).extend(0.0), center.extend(1.0))
}

fn mesh(name: &str, (mut vertices, mut indices): (Vec<Vertex>, Vec<u32>), material: usize) -> Mesh {
    tangents::generate(&mut vertices, &mut indices, 0);
    Mesh { name: name.into(), primitives: vec![Primitive { vertices, indices, material }] }
}

fn vertex(position: Vec3, normal: Vec3, u: f32, v: f32) -> Vertex {
    Vertex { position: position.to_array(), u, normal: normal.to_array(), v, ..Vertex::default() }
}

/// A `width` × `depth` rectangle in the XZ plane facing +Y, its texture repeated `repeat` times
/// along each side.
fn plane(width: f32, depth: f32, repeat: f32) -> (Vec<Vertex>, Vec<u32>) {
    let corner = |s: f32, t: f32| {
        let position = Vec3::new(s * width * 0.5, 0.0, t * depth * 0.5);
        vertex(position, Vec3::Y, (s + 1.0) * 0.5 * repeat, (t + 1.0) * 0.5 * repeat)
    };
    let vertices = vec![corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
    (vertices, vec![0, 3, 1, 1, 3, 2])
}

/// An axis-aligned box of the given size centred at the origin, each face showing the whole texture
/// upright.
fn cuboid(size: Vec3) -> (Vec<Vertex>, Vec<u32>) {
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    for normal in [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z] {
        // u × v = normal, so corners in (s, t) order are counter-clockwise seen from outside.
        let u = if normal.y.abs() > 0.5 { Vec3::X } else { Vec3::Y.cross(normal) };
        let v = normal.cross(u);
        let first = vertices.len() as u32;
        for (s, t) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let position = (normal + u * s + v * t) * size * 0.5;
            vertices.push(vertex(position, normal, (s + 1.0) * 0.5, (1.0 - t) * 0.5));
        }
        indices.extend([0, 1, 2, 0, 2, 3].map(|i| first + i));
    }
    (vertices, indices)
}

/// A UV sphere centred at the origin: u around the equator, v from the north pole down.
fn sphere(radius: f32) -> (Vec<Vertex>, Vec<u32>) {
    const SLICES: u32 = 48;
    const STACKS: u32 = 24;
    let mut vertices = Vec::new();
    for i in 0..=STACKS {
        let theta = PI * i as f32 / STACKS as f32;
        for j in 0..=SLICES {
            let phi = 2.0 * PI * j as f32 / SLICES as f32;
            let normal = Vec3::new(theta.sin() * phi.sin(), theta.cos(), theta.sin() * phi.cos());
            vertices.push(vertex(normal * radius, normal, j as f32 / SLICES as f32, i as f32 / STACKS as f32));
        }
    }
    let at = |i: u32, j: u32| i * (SLICES + 1) + j;
    let mut indices = Vec::new();
    for i in 0..STACKS {
        for j in 0..SLICES {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            // The triangle touching a pole would be degenerate.
            if i + 1 < STACKS {
                indices.extend([a, b, c]);
            }
            if i > 0 {
                indices.extend([a, c, d]);
            }
        }
    }
    (vertices, indices)
}

const TILE_TEXTURE_SIZE: u32 = 256;
/// 4 × 4 tiles per texture; the floor repeats it 5 times over 10 m, so a tile is 0.5 m.
const TILE_PIXELS: u32 = 64;

/// Signed distance in pixels from a tile's grout line (negative inside the grout).
fn tile_edge_distance(x: u32, y: u32) -> f32 {
    const GROUT_HALF_WIDTH: f32 = 2.0;
    let edge = |c: u32| {
        let local = (c % TILE_PIXELS) as f32 + 0.5;
        local.min(TILE_PIXELS as f32 - local)
    };
    edge(x).min(edge(y)) - GROUT_HALF_WIDTH
}

/// Integer hash to [0, 1), for per-tile and per-pixel variation without a random generator.
fn hash(x: u32, y: u32) -> f32 {
    let mut h = x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841);
    h ^= h >> 13;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 16;
    (h & 0xffff) as f32 / 65536.0
}

pub(super) fn texture(name: &str, size: u32, texel: impl Fn(u32, u32) -> [u8; 4]) -> Texture {
    let rgba8 = (0..size).flat_map(|y| (0..size).map(move |x| (x, y))).flat_map(|(x, y)| texel(x, y)).collect();
    Texture { name: name.into(), width: size, height: size, rgba8 }
}

pub(super) fn unorm8(value: f32) -> u8 {
    (value.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// Checkerboard of cream and terracotta tiles with dark grout and slight per-tile variation.
fn tile_colour() -> Texture {
    texture("demo tiles", TILE_TEXTURE_SIZE, |x, y| {
        let (tx, ty) = (x / TILE_PIXELS, y / TILE_PIXELS);
        let base = if tile_edge_distance(x, y) < 0.0 {
            Vec3::new(0.35, 0.34, 0.33)
        } else if (tx + ty) % 2 == 0 {
            Vec3::new(0.89, 0.83, 0.73)
        } else {
            Vec3::new(0.69, 0.38, 0.27)
        };
        let shade = 0.92 + 0.12 * hash(tx, ty) + 0.04 * hash(x, y);
        (base * shade).extend(1.0).to_array().map(unorm8)
    })
}

/// Tangent-space normals of bevelled tiles sunk between grooves (glTF: +Y up the image).
fn tile_normal() -> Texture {
    const BEVEL_PIXELS: f32 = 5.0;
    const STRENGTH: f32 = 2.5;
    let n = TILE_TEXTURE_SIZE;
    let height = |x: u32, y: u32| {
        let t = (tile_edge_distance(x % n, y % n) / BEVEL_PIXELS).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    texture("demo tile normals", n, |x, y| {
        let (left, right) = (height(x + n - 1, y), height(x + 1, y));
        let (up, down) = (height(x, y + n - 1), height(x, y + 1));
        // Rows run down the image and green points up it, hence the sign of the y slope.
        let normal = Vec3::new((left - right) * 0.5 * STRENGTH, (down - up) * 0.5 * STRENGTH, 1.0).normalize();
        (normal * 0.5 + 0.5).extend(1.0).to_array().map(unorm8)
    })
}

/// glTF metallic-roughness layout (G = roughness, B = metallic): polished metal stripes alternating
/// with rough dielectric ones.
fn metal_stripes() -> Texture {
    texture("demo metal stripes", 64, |x, _| if (x / 8) % 2 == 0 { [255, unorm8(0.2), 255, 255] } else { [255, unorm8(0.8), 0, 255] })
}

/// Painted sheet metal with a grid of round holes (alpha 0) inside a solid rim.
fn perforated_paint() -> Texture {
    const SIZE: u32 = 128;
    const CELL: f32 = 16.0;
    const HOLE_RADIUS: f32 = 5.0;
    const RIM: u32 = 6;
    texture("demo perforated paint", SIZE, |x, y| {
        let centre_offset = |c: u32| (c as f32 + 0.5) % CELL - CELL * 0.5;
        let in_rim = x.min(y) < RIM || x.max(y) >= SIZE - RIM;
        let in_hole = centre_offset(x).hypot(centre_offset(y)) < HOLE_RADIUS;
        let alpha = if in_hole && !in_rim { 0 } else { 255 };
        [70, 130, 120, alpha]
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demo_scene_is_valid_and_complete() {
        let scene = demo_scene();
        scene.validate().unwrap();
        assert!(!scene.cameras.is_empty());
        assert!(scene.materials.iter().any(|m| matches!(m.alpha_mode, AlphaMode::Mask { .. }) && m.double_sided));
        assert!(scene.materials.iter().any(|m| m.emissive_factor.max_element() > 1.0));
        assert!(scene.materials.iter().any(|m| m.metallic_roughness_texture.is_some()));
        assert!(scene.materials.iter().any(|m| m.normal_texture.is_some()));
        let uses = |mesh| scene.instances.iter().filter(|i| i.mesh == mesh).count();
        assert!((0..scene.meshes.len()).any(|m| uses(m) >= 2), "a mesh is instanced");
        let spots = scene.lights.iter().filter(|l| matches!(l.kind, LightKind::Spot { .. })).count();
        assert!((3..=6).contains(&(scene.lights.len() - spots)) && (1..=2).contains(&spots));
        assert!(scene.sun.is_some());
        assert!(scene.textures.iter().all(|t| t.width <= 256 && t.height <= 256));
    }

    #[test]
    fn demo_scene_is_deterministic() {
        let (a, b) = (demo_scene(), demo_scene());
        assert_eq!(a.lights, b.lights);
        assert!(a.textures.iter().zip(&b.textures).all(|(x, y)| x.rgba8 == y.rgba8));
        assert!(a.meshes.iter().zip(&b.meshes).all(|(x, y)| x.primitives[0].vertices == y.primitives[0].vertices));
    }

    #[test]
    fn triangles_face_their_normals_and_tangents_are_orthonormal() {
        for mesh in demo_scene().meshes {
            let p = &mesh.primitives[0];
            for t in p.indices.chunks_exact(3) {
                let [a, b, c] = [t[0], t[1], t[2]].map(|i| p.vertices[i as usize]);
                let [pa, pb, pc] = [a, b, c].map(|v| Vec3::from(v.position));
                let geometric = (pb - pa).cross(pc - pa);
                let shading = Vec3::from(a.normal) + Vec3::from(b.normal) + Vec3::from(c.normal);
                assert!(geometric.dot(shading) > 0.0, "{}: clockwise triangle", mesh.name);
            }
            for v in &p.vertices {
                let t = Vec4::from(v.tangent);
                assert!((t.truncate().length() - 1.0).abs() < 1e-3 && t.truncate().dot(Vec3::from(v.normal)).abs() < 1e-3);
                // Every layout is an upright, unmirrored image.
                assert_eq!(t.w, 1.0, "{}", mesh.name);
            }
        }
    }

    #[test]
    fn camera_sees_every_object_and_light_at_16_by_9() {
        let scene = demo_scene();
        let camera = &scene.cameras[0];
        let clip_from_world = camera.clip_from_view(16.0 / 9.0) * camera.world_from_view.inverse();
        let in_view = |p: Vec3| {
            let clip = clip_from_world * p.extend(1.0);
            let ndc = clip.truncate() / clip.w;
            clip.w > 0.0 && ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0
        };
        // Floor and walls (the first three instances) extend beyond the frame by design.
        for instance in &scene.instances[3..] {
            for v in &scene.meshes[instance.mesh].primitives[0].vertices {
                let p = instance.world_from_local.transform_point3(Vec3::from(v.position));
                assert!(in_view(p), "{} at {p}", scene.meshes[instance.mesh].name);
            }
        }
        for light in &scene.lights {
            assert!(in_view(light.position), "light at {}", light.position);
        }
    }

    #[test]
    fn panel_has_holes_and_a_solid_rim() {
        let panel = perforated_paint();
        let alpha: Vec<u8> = panel.rgba8.chunks_exact(4).map(|p| p[3]).collect();
        let holes = alpha.iter().filter(|&&a| a == 0).count();
        assert!(holes > alpha.len() / 10 && holes < alpha.len() / 2, "{holes}");
        assert_eq!(alpha[0], 255);
    }
}
