//! Seeded generators that add content to a loaded scene: many point lights scattered over its
//! surfaces, for scenes (like Sponza) that come without lights.

use glam::{Mat3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use super::{Light, LightKind, Scene};
use crate::{Error, Result};

/// Most lights one generator call may create (2²⁴): far beyond real-time use, and a guard against
/// typos that would allocate gigabytes.
pub const MAX_SCATTERED_LIGHTS: usize = 1 << 24;

/// Point lights scattered uniformly by area over a scene's surfaces, just above them.
#[derive(Clone, Debug, PartialEq)]
pub struct ScatterLights {
    pub count: usize,
    pub seed: u64,
    /// Distance above the surface, along its normal. `None`: a tenth of the mean range.
    pub offset: Option<f32>,
    /// Light range, uniform in [min, max]. `None`: around 4 % of the scene's bounding-box diagonal.
    pub range: Option<(f32, f32)>,
    /// Intensity in candela, uniform in [min, max]. `None`: (range / 2)² for each light, so that the
    /// illuminance at half its range is about 1.
    pub intensity: Option<(f32, f32)>,
}

impl Default for ScatterLights {
    fn default() -> Self {
        Self { count: 256, seed: 1, offset: None, range: None, intensity: None }
    }
}

/// Generates `params.count` point lights over the surfaces of `scene`'s instances. Deterministic: the
/// same scene and parameters give the same lights.
pub fn scatter_lights(scene: &Scene, params: &ScatterLights) -> Result<Vec<Light>> {
    check(params)?;
    // Sampling indexes meshes, vertices and indices directly.
    scene.validate()?;
    if params.count == 0 {
        return Ok(Vec::new());
    }
    let surfaces = Surfaces::new(scene);
    let area = surfaces.total_area();
    if !(area.is_finite() && area > 0.0) {
        return Err(Error::InvalidConfig(format!("cannot scatter {} lights: the scene has no triangles with any area", params.count)));
    }
    let range = params.range.unwrap_or_else(|| {
        let typical = (scene.bounds().diagonal() * 0.04).max(1e-3);
        (typical * 0.5, typical * 1.5)
    });
    let offset = params.offset.unwrap_or((range.0 + range.1) * 0.05);

    let mut rng = Pcg64::seed_from_u64(params.seed);
    let lights = (0..params.count)
        .map(|_| {
            let (point, normal) = surfaces.sample(&mut rng);
            let light_range = uniform(&mut rng, range);
            let intensity = match params.intensity {
                Some(interval) => uniform(&mut rng, interval),
                None => (light_range * 0.5).powi(2),
            };
            Light {
                kind: LightKind::Point,
                position: point + normal * offset,
                direction: Vec3::NEG_Y,
                color: saturated_color(rng.random()),
                intensity,
                range: light_range,
            }
        })
        .collect();
    Ok(lights)
}

/// Appends [`scatter_lights`] to the scene's lights.
pub fn add_scattered_lights(scene: &mut Scene, params: &ScatterLights) -> Result<()> {
    let lights = scatter_lights(scene, params)?;
    scene.lights.extend(lights);
    Ok(())
}

fn check(params: &ScatterLights) -> Result<()> {
    let invalid = |m: String| Err(Error::InvalidConfig(format!("scattered lights: {m}")));
    if params.count > MAX_SCATTERED_LIGHTS {
        return invalid(format!("count {} exceeds the maximum of {MAX_SCATTERED_LIGHTS}", params.count));
    }
    if let Some(offset) = params.offset {
        if !(offset.is_finite() && offset >= 0.0) {
            return invalid(format!("offset {offset} must be finite and ≥ 0"));
        }
    }
    if let Some((min, max)) = params.range {
        if !(min.is_finite() && max.is_finite() && min > 0.0 && min <= max) {
            return invalid(format!("range [{min}, {max}] must be finite with 0 < min ≤ max"));
        }
    }
    if let Some((min, max)) = params.intensity {
        if !(min.is_finite() && max.is_finite() && min >= 0.0 && min <= max) {
            return invalid(format!("intensity [{min}, {max}] must be finite with 0 ≤ min ≤ max"));
        }
    }
    Ok(())
}

/// Every world-space triangle of the scene, for sampling by area.
struct Surfaces<'a> {
    scene: &'a Scene,
    /// Per instance: the matrix that takes normals to world space.
    world_from_local_normal: Vec<Mat3>,
    /// (instance, primitive, first index) of each triangle.
    triangles: Vec<(u32, u32, u32)>,
    /// Running sum of triangle areas, in f64 so millions of small triangles add up exactly enough.
    cumulative_area: Vec<f64>,
}

impl<'a> Surfaces<'a> {
    fn new(scene: &'a Scene) -> Self {
        let mut triangles = Vec::new();
        let mut cumulative_area = Vec::new();
        let mut total = 0.0;
        for (ii, instance) in scene.instances.iter().enumerate() {
            for (pi, primitive) in scene.meshes[instance.mesh].primitives.iter().enumerate() {
                for (t, triangle) in primitive.indices.chunks_exact(3).enumerate() {
                    let [a, b, c] = [0, 1, 2].map(|k| {
                        let local = Vec3::from(primitive.vertices[triangle[k] as usize].position);
                        instance.world_from_local.transform_point3(local)
                    });
                    total += f64::from((b - a).cross(c - a).length() * 0.5);
                    triangles.push((ii as u32, pi as u32, (t * 3) as u32));
                    cumulative_area.push(total);
                }
            }
        }
        let world_from_local_normal = scene.instances.iter().map(|i| Mat3::from_mat4(i.world_from_local).inverse().transpose()).collect();
        Self { scene, world_from_local_normal, triangles, cumulative_area }
    }

    fn total_area(&self) -> f64 {
        self.cumulative_area.last().copied().unwrap_or(0.0)
    }

    /// World-space positions and normals of one triangle's corners.
    fn corners(&self, instance: usize, primitive: usize, first: usize) -> [(Vec3, Vec3); 3] {
        let world_from_local = self.scene.instances[instance].world_from_local;
        let primitive = &self.scene.meshes[self.scene.instances[instance].mesh].primitives[primitive];
        [0, 1, 2].map(|k| {
            let v = &primitive.vertices[primitive.indices[first + k] as usize];
            (world_from_local.transform_point3(Vec3::from(v.position)), self.world_from_local_normal[instance] * Vec3::from(v.normal))
        })
    }

    /// A uniformly distributed surface point and its geometric normal, turned to the side the
    /// shading normals face.
    fn sample(&self, rng: &mut Pcg64) -> (Vec3, Vec3) {
        let target = rng.random::<f64>() * self.total_area();
        // Zero-area triangles have no width in the table, so they are never picked.
        let t = self.cumulative_area.partition_point(|&a| a <= target).min(self.triangles.len() - 1);
        let (ii, pi, first) = self.triangles[t];
        let [(a, na), (b, nb), (c, nc)] = self.corners(ii as usize, pi as usize, first as usize);

        let (r1, r2): (f32, f32) = (rng.random(), rng.random());
        let s = r1.sqrt();
        let (wa, wb, wc) = (1.0 - s, s * (1.0 - r2), s * r2);
        let point = a * wa + b * wb + c * wc;
        let geometric = (b - a).cross(c - a).normalize_or_zero();
        let shading = na * wa + nb * wb + nc * wc;
        let normal = if geometric.dot(shading) < 0.0 { -geometric } else { geometric };
        (point, normal)
    }
}

fn uniform(rng: &mut Pcg64, (min, max): (f32, f32)) -> f32 {
    min + (max - min) * rng.random::<f32>()
}

/// Fully saturated colour of the given hue (0..1: red, yellow, green, cyan, blue, magenta), brightest
/// channel 1 (HSV with S = V = 1).
fn saturated_color(hue: f32) -> Vec3 {
    let channel = |n: f32| {
        let k = (n + hue * 6.0).rem_euclid(6.0);
        1.0 - k.min(4.0 - k).clamp(0.0, 1.0)
    };
    Vec3::new(channel(5.0), channel(3.0), channel(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Instance, Material, Mesh, Primitive, Vertex};
    use glam::Mat4;

    /// A 4 × 4 floor at y = 0 facing up, placed twice: as is and flipped upside down at y = 2.
    fn two_floors() -> Scene {
        let corner = |x: f32, z: f32| Vertex { position: [x, 0.0, z], normal: [0.0, 1.0, 0.0], ..Vertex::default() };
        let floor = Primitive {
            vertices: vec![corner(-2.0, -2.0), corner(-2.0, 2.0), corner(2.0, 2.0), corner(2.0, -2.0)],
            indices: vec![0, 1, 2, 0, 2, 3],
            material: 0,
        };
        Scene {
            meshes: vec![Mesh { name: "floor".into(), primitives: vec![floor] }],
            materials: vec![Material::default()],
            instances: vec![
                Instance { mesh: 0, world_from_local: Mat4::IDENTITY },
                Instance { mesh: 0, world_from_local: Mat4::from_translation(Vec3::Y * 2.0) * Mat4::from_rotation_x(std::f32::consts::PI) },
            ],
            ..Scene::default()
        }
    }

    #[test]
    fn same_seed_same_lights_different_seed_different_lights() {
        let scene = two_floors();
        let params = ScatterLights { count: 100, ..Default::default() };
        let a = scatter_lights(&scene, &params).unwrap();
        assert_eq!(a, scatter_lights(&scene, &params).unwrap());
        let b = scatter_lights(&scene, &ScatterLights { seed: 2, ..params }).unwrap();
        assert_eq!(b.len(), 100);
        assert_ne!(a, b);
    }

    #[test]
    fn lights_sit_at_the_offset_on_the_normal_side_of_a_surface() {
        let scene = two_floors();
        let params = ScatterLights { count: 500, offset: Some(0.25), ..Default::default() };
        let lights = scatter_lights(&scene, &params).unwrap();
        for l in &lights {
            let p = l.position;
            assert!(p.x.abs() <= 2.0 && p.z.abs() <= 2.0, "{p}");
            // Above the lower floor, or below the upside-down upper one.
            let on_lower = (p.y - 0.25).abs() < 1e-4;
            let on_upper = (p.y - 1.75).abs() < 1e-4;
            assert!(on_lower || on_upper, "{p}");
            assert!(crate::scene::validate_light(l).is_ok());
        }
        let lower = lights.iter().filter(|l| l.position.y < 1.0).count();
        assert!((200..300).contains(&lower), "equal areas get about equal shares: {lower} of 500");
    }

    #[test]
    fn defaults_follow_the_scene_size() {
        let scene = two_floors();
        let lights = scatter_lights(&scene, &ScatterLights::default()).unwrap();
        assert_eq!(lights.len(), 256);
        let diagonal = scene.bounds().diagonal();
        for l in &lights {
            assert!(l.range >= diagonal * 0.02 - 1e-6 && l.range <= diagonal * 0.06 + 1e-6, "{}", l.range);
            assert!((l.intensity - (l.range * 0.5).powi(2)).abs() < 1e-5);
            assert!((l.color.max_element() - 1.0).abs() < 1e-6, "saturated: {}", l.color);
        }
    }

    #[test]
    fn intervals_are_honoured() {
        let params = ScatterLights { count: 64, range: Some((0.5, 2.0)), intensity: Some((3.0, 3.0)), ..Default::default() };
        for l in scatter_lights(&two_floors(), &params).unwrap() {
            assert!((0.5..=2.0).contains(&l.range));
            assert_eq!(l.intensity, 3.0);
        }
    }

    #[test]
    fn lights_lie_on_the_surface_of_a_real_mesh() {
        let scene = crate::scene::gltf::import(&crate::scene::test_support::assets_dir().join("box/Box.glb")).unwrap();
        let params = ScatterLights { count: 200, offset: Some(0.1), ..Default::default() };
        let lights = scatter_lights(&scene, &params).unwrap();
        let surfaces = Surfaces::new(&scene);
        for l in &lights {
            let near_a_face = surfaces.triangles.iter().any(|&(ii, pi, first)| {
                let [(a, na), (b, _), (c, _)] = surfaces.corners(ii as usize, pi as usize, first as usize);
                let n = (b - a).cross(c - a).normalize();
                let n = if n.dot(na) < 0.0 { -n } else { n };
                let height = (l.position - a).dot(n);
                let foot = l.position - n * height;
                (height - 0.1).abs() < 1e-4 && inside(foot, [a, b, c], n)
            });
            assert!(near_a_face, "{}", l.position);
        }
    }

    fn inside(p: Vec3, [a, b, c]: [Vec3; 3], n: Vec3) -> bool {
        let eps = -1e-4;
        (b - a).cross(p - a).dot(n) >= eps && (c - b).cross(p - b).dot(n) >= eps && (a - c).cross(p - c).dot(n) >= eps
    }

    #[test]
    fn zero_lights_are_fine_but_impossible_requests_are_errors() {
        assert!(scatter_lights(&Scene::default(), &ScatterLights { count: 0, ..Default::default() }).unwrap().is_empty());
        let empty = scatter_lights(&Scene::default(), &ScatterLights::default()).unwrap_err();
        assert!(empty.to_string().contains("no triangles"), "{empty}");
        let too_many = ScatterLights { count: MAX_SCATTERED_LIGHTS + 1, ..Default::default() };
        let err = scatter_lights(&two_floors(), &too_many).unwrap_err();
        assert!(matches!(err, Error::InvalidConfig(_)) && err.to_string().contains("16777216"), "{err}");
        let bad_range = ScatterLights { range: Some((2.0, 1.0)), ..Default::default() };
        assert!(matches!(scatter_lights(&two_floors(), &bad_range), Err(Error::InvalidConfig(_))));
    }

    #[test]
    fn hues_map_to_saturated_colours() {
        for (hue, rgb) in [(0.0, Vec3::X), (1.0 / 3.0, Vec3::Y), (2.0 / 3.0, Vec3::Z), (0.5, Vec3::new(0.0, 1.0, 1.0))] {
            assert!(saturated_color(hue).abs_diff_eq(rgb, 1e-5), "{hue}: {}", saturated_color(hue));
        }
    }

    #[test]
    fn add_scattered_lights_appends() {
        let mut scene = two_floors();
        add_scattered_lights(&mut scene, &ScatterLights { count: 10, ..Default::default() }).unwrap();
        add_scattered_lights(&mut scene, &ScatterLights { count: 5, ..Default::default() }).unwrap();
        assert_eq!(scene.lights.len(), 15);
        scene.validate().unwrap();
    }
}
