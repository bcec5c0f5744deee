//! Procedural decal materials: a fixed set of stamps (splat, ring, star, hazard stripes, cross, checker
//! disc, rivet plate, arrow) whose textures are generated in code, so scattered decals need no files.
//!
//! Shapes are signed distance fields in texture space ([-1, 1]² across the image, +y up the image),
//! their alpha ramping over a pixel or more so edges stay smooth. Normal maps are derived from height
//! fields (glTF convention: green = +Y, up the image); metallic-roughness maps hold G = roughness and
//! B = metallic. Shapes keep clear of the border, so filtering at the box's edges sees transparent
//! texels. The textures are clamped to their edges, as decals sample every texture
//! (`shading/decals.wgsl`); the decals' texture arrays have the stamps' own size, so lavapipe, which
//! samples clamped layers of large arrays about 200× slower, is not slowed.

use std::f32::consts::{PI, SQRT_2, TAU};
use std::ops::Range;

use glam::{Vec2, Vec3, Vec4};

use super::demo::{texture, unorm8};
use super::{Material, Scene, TextureRef, Wrap};

/// Side of every procedural decal texture, in texels.
pub const DECAL_TEXTURE_SIZE: u32 = 128;

/// One texel's width in texture space.
const PIXEL: f32 = 2.0 / DECAL_TEXTURE_SIZE as f32;

/// One decal material: factors as in glTF, and the functions its textures are sampled from.
struct Stamp {
    name: &'static str,
    color: Vec4,
    roughness: f32,
    metallic: f32,
    /// sRGB-coded colour and alpha.
    albedo: fn(Vec2) -> Vec4,
    /// Height above the surface in texture-space units; `None`: no normal map.
    height: Option<fn(Vec2) -> f32>,
    /// (roughness, metallic); `None`: the factors alone.
    roughness_metallic: Option<fn(Vec2) -> (f32, f32)>,
}

const STAMPS: [Stamp; 8] = [
    Stamp {
        name: "splat",
        color: Vec4::new(0.5, 0.06, 0.05, 1.0),
        roughness: 0.35,
        metallic: 0.0,
        albedo: splat_albedo,
        height: None,
        roughness_metallic: None,
    },
    Stamp {
        name: "ring",
        color: Vec4::new(1.0, 0.78, 0.34, 1.0),
        roughness: 1.0,
        metallic: 1.0,
        albedo: ring_albedo,
        height: Some(ring_height),
        roughness_metallic: Some(ring_roughness_metallic),
    },
    Stamp {
        name: "star",
        color: Vec4::new(1.0, 0.8, 0.1, 1.0),
        roughness: 0.5,
        metallic: 0.0,
        albedo: star_albedo,
        height: None,
        roughness_metallic: None,
    },
    Stamp {
        name: "hazard stripes",
        color: Vec4::ONE,
        roughness: 1.0,
        metallic: 1.0,
        albedo: hazard_albedo,
        height: Some(hazard_height),
        roughness_metallic: Some(hazard_roughness_metallic),
    },
    Stamp {
        name: "cross",
        color: Vec4::new(0.1, 0.65, 0.2, 1.0),
        roughness: 0.6,
        metallic: 0.0,
        albedo: cross_albedo,
        height: None,
        roughness_metallic: None,
    },
    Stamp {
        name: "checker disc",
        color: Vec4::new(0.7, 0.85, 1.0, 1.0),
        roughness: 1.0,
        metallic: 1.0,
        albedo: checker_albedo,
        height: None,
        roughness_metallic: Some(checker_roughness_metallic),
    },
    Stamp {
        name: "rivet plate",
        color: Vec4::new(0.9, 0.9, 0.95, 1.0),
        roughness: 1.0,
        metallic: 1.0,
        albedo: rivet_albedo,
        height: Some(rivet_height),
        roughness_metallic: Some(rivet_roughness_metallic),
    },
    Stamp {
        name: "arrow",
        color: Vec4::new(0.1, 0.55, 0.95, 1.0),
        roughness: 0.45,
        metallic: 0.0,
        albedo: arrow_albedo,
        height: Some(arrow_height),
        roughness_metallic: None,
    },
];

fn material_name(stamp: &Stamp) -> String {
    format!("decal {}", stamp.name)
}

/// Appends the procedural decal materials and their textures to `scene`; returns the new materials'
/// indices. Deterministic. Their textures are clamped to the edges, as decals sample them.
pub fn add_decal_materials(scene: &mut Scene) -> Range<usize> {
    let first = scene.materials.len();
    for stamp in &STAMPS {
        let mut add = |kind: &str, texel: &dyn Fn(Vec2) -> [u8; 4]| {
            let name = format!("{} {kind}", material_name(stamp));
            scene.textures.push(texture(&name, DECAL_TEXTURE_SIZE, |x, y| texel(texture_point(x, y))));
            Some(TextureRef::new(scene.textures.len() - 1, Wrap::ClampToEdge, Wrap::ClampToEdge))
        };
        let base_color_texture = add("albedo", &|p| (stamp.albedo)(p).to_array().map(unorm8));
        let normal_texture = stamp.height.and_then(|height| add("normal", &|p| normal_texel(height, p)));
        let metallic_roughness_texture = stamp.roughness_metallic.and_then(|f| {
            add("metallic-roughness", &|p| {
                let (roughness, metallic) = f(p);
                [255, unorm8(roughness), unorm8(metallic), 255]
            })
        });
        scene.materials.push(Material {
            name: material_name(stamp),
            base_color_factor: stamp.color,
            base_color_texture,
            metallic_factor: stamp.metallic,
            roughness_factor: stamp.roughness,
            metallic_roughness_texture,
            normal_texture,
            ..Material::default()
        });
    }
    first..scene.materials.len()
}

/// The materials [`add_decal_materials`] added to `scene`, found by name, if it did.
pub fn find_decal_materials(scene: &Scene) -> Option<Range<usize>> {
    let first = scene.materials.iter().position(|m| m.name == material_name(&STAMPS[0]))?;
    let range = first..first + STAMPS.len();
    let materials = scene.materials.get(range.clone())?;
    materials.iter().zip(&STAMPS).all(|(m, stamp)| m.name == material_name(stamp)).then_some(range)
}

/// The texture-space point at the centre of texel (x, y); rows run down the image.
fn texture_point(x: u32, y: u32) -> Vec2 {
    Vec2::new((x as f32 + 0.5) * PIXEL - 1.0, 1.0 - (y as f32 + 0.5) * PIXEL)
}

/// Tangent-space normal of a height field, from central differences one texel wide.
fn normal_texel(height: fn(Vec2) -> f32, p: Vec2) -> [u8; 4] {
    let slope = |axis: Vec2| (height(p + axis * (0.5 * PIXEL)) - height(p - axis * (0.5 * PIXEL))) / PIXEL;
    let normal = Vec3::new(-slope(Vec2::X), -slope(Vec2::Y), 1.0).normalize();
    (normal * 0.5 + 0.5).extend(1.0).to_array().map(unorm8)
}

fn smoothstep(edge0: f32, edge1: f32, x: f32) -> f32 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Coverage of a shape at signed distance `sd` (negative inside), ramping over `texels` across its edge.
fn fill(sd: f32, texels: f32) -> f32 {
    smoothstep(0.5 * texels * PIXEL, -0.5 * texels * PIXEL, sd)
}

/// 0 outside a shape, rising to 1 over `width` inside its edge: a bevel.
fn bevel(sd: f32, width: f32) -> f32 {
    smoothstep(0.0, -width, sd)
}

/// A dome of `height` and `radius`, flat where it meets the surface: (1 − t²)².
fn dome(distance: f32, radius: f32, height: f32) -> f32 {
    let t = (distance / radius).min(1.0);
    height * (1.0 - t * t).powi(2)
}

fn white(alpha: f32) -> Vec4 {
    Vec4::new(1.0, 1.0, 1.0, alpha)
}

fn rounded_box(p: Vec2, half: Vec2, radius: f32) -> f32 {
    let d = p.abs() - (half - radius);
    d.max(Vec2::ZERO).length() + d.x.max(d.y).min(0.0) - radius
}

/// Five-pointed star pointing up, tips at `radius`, inner corners at `radius × inner` (after Quílez).
fn star5(p: Vec2, radius: f32, inner: f32) -> f32 {
    let k1 = Vec2::new((0.1 * TAU).cos(), -(0.1 * TAU).sin());
    let k2 = Vec2::new(-k1.x, k1.y);
    let mut p = Vec2::new(p.x.abs(), p.y);
    p -= 2.0 * k1.dot(p).max(0.0) * k1;
    p -= 2.0 * k2.dot(p).max(0.0) * k2;
    p.x = p.x.abs();
    p.y -= radius;
    let ba = inner * Vec2::new(-k1.y, k1.x) - Vec2::Y;
    let h = (p.dot(ba) / ba.dot(ba)).clamp(0.0, radius);
    (p - ba * h).length() * (p.y * ba.x - p.x * ba.y).signum()
}

/// Exact signed distance to a triangle (after Quílez).
fn triangle(p: Vec2, [a, b, c]: [Vec2; 3]) -> f32 {
    let edges = [(a, b - a), (b, c - b), (c, a - c)];
    let orientation = (b - a).perp_dot(a - c).signum();
    let (distance_squared, side) = edges.iter().fold((f32::INFINITY, f32::INFINITY), |(d, s), &(start, edge)| {
        let v = p - start;
        let closest = v - edge * (v.dot(edge) / edge.dot(edge)).clamp(0.0, 1.0);
        (d.min(closest.length_squared()), s.min(orientation * v.perp_dot(edge)))
    });
    -distance_squared.sqrt() * side.signum()
}

// Splat: a blob with wavy rim and a few droplets, with a soft edge.

const DROPLETS: [(Vec2, f32); 5] = [
    (Vec2::new(0.72, 0.2), 0.07),
    (Vec2::new(-0.6, -0.55), 0.06),
    (Vec2::new(0.15, -0.8), 0.05),
    (Vec2::new(-0.78, 0.35), 0.045),
    (Vec2::new(0.5, 0.62), 0.05),
];

fn splat_albedo(p: Vec2) -> Vec4 {
    let angle = p.y.atan2(p.x);
    let radius = 0.55 + 0.08 * (5.0 * angle).sin() + 0.05 * (9.0 * angle + 1.3).sin() + 0.03 * (17.0 * angle + 0.4).sin();
    let sd = DROPLETS.iter().fold(p.length() - radius, |d, &(centre, r)| d.min(p.distance(centre) - r));
    white(0.9 * fill(sd, 4.0))
}

// Ring: a raised metal torus.

const RING_RADIUS: f32 = 0.6;
const RING_HALF_WIDTH: f32 = 0.16;

fn ring_albedo(p: Vec2) -> Vec4 {
    white(fill((p.length() - RING_RADIUS).abs() - RING_HALF_WIDTH, 1.5))
}

fn ring_height(p: Vec2) -> f32 {
    dome((p.length() - RING_RADIUS).abs(), RING_HALF_WIDTH, 0.1)
}

fn ring_roughness_metallic(p: Vec2) -> (f32, f32) {
    let t = ((p.length() - RING_RADIUS) / RING_HALF_WIDTH).clamp(-1.0, 1.0);
    // Polished on the crest, duller towards the edges.
    (0.2 + 0.25 * t * t, 1.0)
}

fn star_albedo(p: Vec2) -> Vec4 {
    white(fill(star5(p, 0.8, 0.45), 1.5))
}

// Hazard stripes: yellow and black chevrons on a plate with a black frame; the black is sunk.

fn hazard_plate(p: Vec2) -> f32 {
    rounded_box(p, Vec2::splat(0.78), 0.12)
}

/// Approximate signed distance to the nearest chevron edge, positive on black stripes.
fn chevrons(p: Vec2) -> f32 {
    const PERIOD: f32 = 0.36;
    // |∇(|x| + y)| = √2, so this is a distance near the edges, where it matters.
    (TAU * (p.x.abs() + p.y) / PERIOD).sin() * PERIOD / (TAU * SQRT_2)
}

/// Weight of yellow: the stripes inside the frame, edges ramping over `texels`.
fn hazard_yellow(p: Vec2, texels: f32) -> f32 {
    fill(chevrons(p), texels) * fill(hazard_plate(p) + 0.07, texels)
}

fn hazard_albedo(p: Vec2) -> Vec4 {
    let color = Vec3::splat(0.05).lerp(Vec3::new(0.95, 0.75, 0.05), hazard_yellow(p, 1.5));
    color.extend(fill(hazard_plate(p), 1.5))
}

fn hazard_height(p: Vec2) -> f32 {
    0.02 * hazard_yellow(p, 4.0)
}

fn hazard_roughness_metallic(p: Vec2) -> (f32, f32) {
    (0.75 - 0.3 * hazard_yellow(p, 1.5), 0.0)
}

fn cross_albedo(p: Vec2) -> Vec4 {
    let sd = rounded_box(p, Vec2::new(0.7, 0.2), 0.04).min(rounded_box(p, Vec2::new(0.2, 0.7), 0.04));
    white(fill(sd, 1.5))
}

// Checker disc: polished metal and rough black squares in a circle.

/// Approximate signed distance to the nearest grid line of a 6 × 6 checkerboard, positive on black.
fn checker(p: Vec2) -> f32 {
    const CELL: f32 = 2.0 / 6.0;
    let d = (p * (PI / CELL)).map(f32::sin) * (CELL / PI);
    (d.x * d.y).signum() * d.x.abs().min(d.y.abs())
}

fn checker_albedo(p: Vec2) -> Vec4 {
    let color = Vec3::splat(0.08).lerp(Vec3::splat(0.95), fill(checker(p), 1.5));
    color.extend(fill(p.length() - 0.8, 1.5))
}

fn checker_roughness_metallic(p: Vec2) -> (f32, f32) {
    let metal = fill(checker(p), 1.5);
    (0.7 - 0.5 * metal, metal)
}

// Rivet plate: a bevelled metal plate with a 4 × 4 grid of domed rivets.

const RIVET_RADIUS: f32 = 0.07;

fn rivet_plate(p: Vec2) -> f32 {
    rounded_box(p, Vec2::splat(0.75), 0.15)
}

/// Distance to the nearest rivet's centre.
fn rivet_distance(p: Vec2) -> f32 {
    const SPACING: f32 = 0.34;
    let centre = ((p / SPACING + 1.5).round().clamp(Vec2::ZERO, Vec2::splat(3.0)) - 1.5) * SPACING;
    p.distance(centre)
}

fn rivet_albedo(p: Vec2) -> Vec4 {
    let color = Vec3::splat(0.62).lerp(Vec3::splat(0.85), fill(rivet_distance(p) - RIVET_RADIUS, 1.5));
    color.extend(fill(rivet_plate(p), 1.5))
}

fn rivet_height(p: Vec2) -> f32 {
    0.03 * bevel(rivet_plate(p), 0.12) + dome(rivet_distance(p), RIVET_RADIUS, 0.05)
}

fn rivet_roughness_metallic(p: Vec2) -> (f32, f32) {
    (0.45 - 0.25 * fill(rivet_distance(p) - RIVET_RADIUS, 1.5), 1.0)
}

// Arrow: an embossed arrow pointing up the image.

fn arrow(p: Vec2) -> f32 {
    let shaft = rounded_box(p - Vec2::new(0.0, -0.25), Vec2::new(0.14, 0.45), 0.03);
    shaft.min(triangle(p, [Vec2::new(0.0, 0.8), Vec2::new(-0.5, 0.1), Vec2::new(0.5, 0.1)]))
}

fn arrow_albedo(p: Vec2) -> Vec4 {
    white(fill(arrow(p), 1.5))
}

fn arrow_height(p: Vec2) -> f32 {
    0.03 * bevel(arrow(p), 0.12)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texels(scene: &Scene, t: Option<TextureRef>) -> impl Iterator<Item = [u8; 4]> + '_ {
        scene.textures[t.unwrap().texture].rgba8.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]])
    }

    fn texel(scene: &Scene, t: Option<TextureRef>, x: u32, y: u32) -> [u8; 4] {
        texels(scene, t).nth((y * DECAL_TEXTURE_SIZE + x) as usize).unwrap()
    }

    fn on_border(i: usize) -> bool {
        let n = DECAL_TEXTURE_SIZE as usize;
        let (x, y) = (i % n, i / n);
        x == 0 || y == 0 || x == n - 1 || y == n - 1
    }

    #[test]
    fn materials_are_appended_and_found_again() {
        let mut scene = Scene { materials: vec![Material::default()], ..Scene::default() };
        assert_eq!(find_decal_materials(&scene), None);
        let range = add_decal_materials(&mut scene);
        assert_eq!(range, 1..1 + STAMPS.len());
        assert_eq!(find_decal_materials(&scene), Some(range.clone()));
        scene.validate().unwrap();
        for m in &scene.materials[range] {
            let refs = [m.base_color_texture, m.normal_texture, m.metallic_roughness_texture];
            for t in refs.into_iter().flatten() {
                assert_eq!((t.wrap_u, t.wrap_v), (Wrap::ClampToEdge, Wrap::ClampToEdge), "{}", m.name);
                let image = &scene.textures[t.texture];
                assert_eq!((image.width, image.height), (DECAL_TEXTURE_SIZE, DECAL_TEXTURE_SIZE));
            }
        }
    }

    #[test]
    fn materials_are_deterministic() {
        let (mut a, mut b) = (Scene::default(), Scene::default());
        add_decal_materials(&mut a);
        add_decal_materials(&mut b);
        assert!(a.textures.iter().zip(&b.textures).all(|(x, y)| x.rgba8 == y.rgba8));
    }

    #[test]
    fn shapes_have_soft_edges_and_clear_borders() {
        let mut scene = Scene::default();
        let range = add_decal_materials(&mut scene);
        for m in &scene.materials[range] {
            let alpha: Vec<u8> = texels(&scene, m.base_color_texture).map(|t| t[3]).collect();
            assert!(alpha.iter().enumerate().all(|(i, &a)| a == 0 || !on_border(i)), "{}: opaque border", m.name);
            assert!(alpha.contains(&0) && alpha.iter().any(|&a| a >= 229), "{}: no shape", m.name);
            let edge = alpha.iter().filter(|&&a| a > 0 && a < 229).count();
            assert!(edge > 100, "{}: {edge} edge texels", m.name);
            if m.normal_texture.is_some() {
                for (i, [r, g, b, _]) in texels(&scene, m.normal_texture).enumerate() {
                    let n = Vec3::new(r as f32, g as f32, b as f32) / 127.5 - 1.0;
                    assert!((n.length() - 1.0).abs() < 0.03 && n.z > 0.0, "{}: {n}", m.name);
                    assert!(!on_border(i) || [r, g, b] == [128, 128, 255], "{}: tilted border", m.name);
                }
            }
        }
    }

    #[test]
    fn normal_maps_point_green_up_the_image() {
        let mut scene = Scene::default();
        let ring = add_decal_materials(&mut scene).start + 1;
        let ring = scene.materials[ring].clone();
        // Column 64 runs up the image's centre; rows 20 and 30 lie on the upper part of the ring,
        // outside and inside its crest: the outer slope faces up the image, the inner one down.
        let [r, g, ..] = texel(&scene, ring.normal_texture, 64, 20);
        assert!(g > 150 && r.abs_diff(128) < 8, "outer slope: {r} {g}");
        let [r, g, ..] = texel(&scene, ring.normal_texture, 64, 30);
        assert!(g < 106 && r.abs_diff(128) < 8, "inner slope: {r} {g}");
    }

    #[test]
    fn the_set_is_varied() {
        let mut scene = Scene::default();
        let range = add_decal_materials(&mut scene);
        let materials = &scene.materials[range];
        let complete = materials.iter().filter(|m| m.normal_texture.is_some() && m.metallic_roughness_texture.is_some()).count();
        let albedo_only = materials.iter().filter(|m| m.normal_texture.is_none() && m.metallic_roughness_texture.is_none()).count();
        assert!(complete >= 2 && albedo_only >= 2, "{complete} complete, {albedo_only} albedo only");
        let metallic = materials
            .iter()
            .filter(|m| m.metallic_factor > 0.0)
            .filter(|m| m.metallic_roughness_texture.is_none_or(|_| texels(&scene, m.metallic_roughness_texture).any(|t| t[2] == 255)))
            .count();
        assert!(metallic >= 2, "{metallic} metallic");
        let mut colours: Vec<[u32; 4]> = materials.iter().map(|m| m.base_color_factor.to_array().map(f32::to_bits)).collect();
        colours.sort_unstable();
        colours.dedup();
        assert!(colours.len() >= 6);
        // The star's centre is inside, its tips reach up.
        let star = &materials[2];
        assert_eq!(texel(&scene, star.base_color_texture, 64, 64)[3], 255);
        assert_eq!(texel(&scene, star.base_color_texture, 64, 24)[3], 255);
        assert_eq!(texel(&scene, star.base_color_texture, 64, 112)[3], 0);
    }
}
