//! Seeded generators that add content to a loaded scene: many point lights and decals scattered over
//! its surfaces, for scenes (like Sponza) that come without them, and the grouping of lights and
//! decals into spinning groups for animated benchmarks.

use std::ops::Range;

use glam::{Affine3A, Mat3, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use super::{decal_textures, sky::DaylightSky, Aabb, Decal, GroupInstance, Groups, Light, LightKind, Scene, Spin, DECAL_LAYERS};
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
    /// Light range, uniform in [min, max]. `None`: [0.5, 1.5] × a typical range, 4 % of the scene's
    /// bounding-box diagonal, or less where many lights would crowd: at most the range at which about
    /// [`DEFAULT_LIGHT_OVERLAP`] lights reach each surface point ([`typical_light_range`]).
    pub range: Option<(f32, f32)>,
    /// Intensity in candela, uniform in [min, max]. `None`: (range / 2)² for each light, so that the
    /// illuminance at half its range is about 1, times the scene's [`light_level`].
    pub intensity: Option<(f32, f32)>,
}

impl Default for ScatterLights {
    fn default() -> Self {
        Self { count: 256, seed: 1, offset: None, range: None, intensity: None }
    }
}

/// How bright the scene's daylight is against the default sky's: its sun's illuminance over the
/// default daylight sky's sun's, or 1 without a sun. Generated lights and particles are as much
/// brighter, so they show as much against a glTF sun in lux (2,049 to 100,000) as under the default
/// sky, whether they are generated before the sky is given (scene files) or after (the CLI).
pub fn light_level(scene: &Scene) -> f32 {
    let default_sun = DaylightSky::for_scene(&Scene::default()).sun().illuminance;
    scene.sun.map(|sun| sun.illuminance).filter(|&e| e > 0.0 && e.is_finite()).map_or(1.0, |e| e / default_sun)
}

/// How many scattered lights of the default range reach a surface point, on average, at most: a few
/// overlapping pools of light, whatever the count and the scene's size.
pub const DEFAULT_LIGHT_OVERLAP: f32 = 2.0;

/// The middle of the default range of `count` lights scattered over `area` m² of surfaces in bounds
/// of diagonal `diagonal`: 4 % of the diagonal, or less where that many would crowd. A light just above
/// a surface reaches a disc of about π r² of it, and ranges uniform in [0.5, 1.5] × r have a mean
/// square of 13/12 r², so `count` of them reach N·π·13/12·r² / area lights a point.
pub fn typical_light_range(diagonal: f32, area: f32, count: usize) -> f32 {
    let crowded = (DEFAULT_LIGHT_OVERLAP * area / (count.max(1) as f32 * std::f32::consts::PI * 13.0 / 12.0)).sqrt();
    (diagonal * 0.04).min(crowded).max(1e-3)
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
        let typical = typical_light_range(scene.bounds().diagonal(), area as f32, params.count);
        (typical * 0.5, typical * 1.5)
    });
    let offset = params.offset.unwrap_or((range.0 + range.1) * 0.05);

    let level = light_level(scene);
    let mut rng = Pcg64::seed_from_u64(params.seed);
    let lights = (0..params.count)
        .map(|_| {
            let (point, normal) = surfaces.sample(&mut rng);
            let light_range = uniform(&mut rng, range);
            let intensity = match params.intensity {
                Some(interval) => uniform(&mut rng, interval),
                None => (light_range * 0.5).powi(2) * level,
            };
            Light {
                kind: LightKind::Point,
                position: point + normal * offset,
                direction: Vec3::NEG_Y,
                color: saturated_color(rng.random()),
                intensity,
                range: light_range,
                // Thousands of small lights: no shadow rays.
                cast_shadows: false,
            }
        })
        .collect();
    Ok(lights)
}

/// Appends [`scatter_lights`] to the scene's lights, which must not be grouped yet.
pub fn add_scattered_lights(scene: &mut Scene, params: &ScatterLights) -> Result<()> {
    check_ungrouped(&scene.light_groups, "lights")?;
    check_total("lights", scene.lights.len(), params.count, MAX_SCATTERED_LIGHTS)?;
    let lights = scatter_lights(scene, params)?;
    scene.lights.extend(lights);
    Ok(())
}

/// Many scatterers (a scene file's entries, then the command line's) may not add up past what one
/// call may make: the structures hold no more, and generating them would take minutes.
fn check_total(what: &str, existing: usize, count: usize, max: usize) -> Result<()> {
    if existing.saturating_add(count) > max {
        return Err(Error::InvalidConfig(format!(
            "{count} more {what} would make {}, over the {max} a scene may have; scatter fewer",
            existing.saturating_add(count)
        )));
    }
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

/// Most decals one generator call may create (2²⁴), a guard like [`MAX_SCATTERED_LIGHTS`].
pub const MAX_SCATTERED_DECALS: usize = 1 << 24;

/// Decals scattered uniformly by area over a scene's surfaces, after Hansen & Peters (2021): each box
/// centred on a surface point, its +Z along the surface normal, turned randomly about it.
#[derive(Clone, Debug, PartialEq)]
pub struct ScatterDecals {
    pub count: usize,
    pub seed: u64,
    /// Mean edge of the box's square face; each decal's is uniform in [0.75, 1.25] × size and its depth
    /// half that. `None`: 2.5 % of the scene's bounding-box diagonal, or less where many decals would
    /// crowd: at most the edge at which about [`DEFAULT_DECAL_OVERLAP`] decals cover each surface point.
    pub size: Option<f32>,
}

impl Default for ScatterDecals {
    fn default() -> Self {
        Self { count: 256, seed: 1, size: None }
    }
}

/// How many scattered decals of the default size cover a surface point, on average, at most.
pub const DEFAULT_DECAL_OVERLAP: f32 = 1.0;

/// The default mean edge of `count` decals scattered over `area` m² of surfaces in bounds of diagonal
/// `diagonal`: 2.5 % of the diagonal, or less where that many would crowd (a decal covers about its
/// square face, edges uniform in [0.75, 1.25] × s having a mean square of 49/48 s²).
pub fn typical_decal_size(diagonal: f32, area: f32, count: usize) -> f32 {
    let crowded = (DEFAULT_DECAL_OVERLAP * area / (count.max(1) as f32 * 49.0 / 48.0)).sqrt();
    (diagonal * 0.025).min(crowded)
}

/// Generates `params.count` decals over the surfaces of `scene`'s instances, each with a material
/// drawn from `materials`, a random layer and a weight in [0.5, 2]. Deterministic.
pub fn scatter_decals(scene: &Scene, params: &ScatterDecals, materials: Range<usize>) -> Result<Vec<Decal>> {
    check_decals(params)?;
    if materials.is_empty() || materials.end > scene.materials.len() {
        return Err(Error::InvalidConfig(format!(
            "scattered decals: materials {materials:?} must be a non-empty range of the scene's {} materials",
            scene.materials.len()
        )));
    }
    scene.validate()?;
    if params.count == 0 {
        return Ok(Vec::new());
    }
    let surfaces = Surfaces::new(scene);
    let area = surfaces.total_area();
    if !(area.is_finite() && area > 0.0) {
        return Err(Error::InvalidConfig(format!("cannot scatter {} decals: the scene has no triangles with any area", params.count)));
    }
    let size = params
        .size
        .unwrap_or_else(|| typical_decal_size(scene.bounds().diagonal(), Surfaces::new(scene).total_area() as f32, params.count));
    if !(size.is_finite() && size > 0.0) {
        return Err(Error::InvalidConfig(format!(
            "scattered decals: the scene's bounds give no usable size ({size}); give one explicitly"
        )));
    }

    let mut rng = Pcg64::seed_from_u64(params.seed);
    let decals = (0..params.count)
        .map(|_| {
            let (point, normal) = surfaces.sample(&mut rng);
            let (a, b) = normal.any_orthonormal_pair();
            let (sin, cos) = (std::f32::consts::TAU * rng.random::<f32>()).sin_cos();
            let x = a * cos + b * sin;
            let edge = size * uniform(&mut rng, (0.75, 1.25));
            Decal {
                // Right-handed: x × (n × x) = n.
                world_from_decal: Affine3A::from_cols(
                    (x * edge).into(),
                    (normal.cross(x) * edge).into(),
                    (normal * (edge * 0.5)).into(),
                    point.into(),
                ),
                material: rng.random_range(materials.clone()),
                layer: rng.random_range(0..DECAL_LAYERS),
                weight: uniform(&mut rng, (0.5, 2.0)),
            }
        })
        .collect();
    Ok(decals)
}

/// `count` points distributed uniformly by area over the scene's surfaces (seeded): where shading
/// happens, for statistics such as [`crate::accel::overlap`]. Empty for a scene without area.
pub fn surface_points(scene: &Scene, count: usize, seed: u64) -> Vec<Vec3> {
    let surfaces = Surfaces::new(scene);
    let area = surfaces.total_area();
    if !(area.is_finite() && area > 0.0) {
        return Vec::new();
    }
    let mut rng = Pcg64::seed_from_u64(seed);
    (0..count).map(|_| surfaces.sample(&mut rng).0).collect()
}

/// Appends [`scatter_decals`] to the scene's decals, which must not be grouped yet, with the
/// procedural decal materials ([`decal_textures`]), which are added the first time only.
pub fn add_scattered_decals(scene: &mut Scene, params: &ScatterDecals) -> Result<()> {
    check_decals(params)?;
    check_total("decals", scene.decals.len(), params.count, MAX_SCATTERED_DECALS)?;
    add_decals_with_builtin_materials(scene, params.count, |scene, materials| scatter_decals(scene, params, materials))
}

/// Most decals [`large_decals`] places: one per flat surface, and scenes have few large ones.
pub const MAX_LARGE_DECALS: usize = 256;

/// Decals covering the largest flat surfaces of a scene — its floors and walls — as in the paper's
/// "large decals" scene: coplanar triangles are pooled by plane, the planes with the most area are
/// taken, and each gets one decal whose box spans all of that plane's triangles, thin along its normal.
#[derive(Clone, Debug, PartialEq)]
pub struct LargeDecals {
    pub count: usize,
    pub seed: u64,
}

/// Generates up to `params.count` large decals (fewer when the scene has fewer distinct planes), each
/// with a material drawn from `materials`, layer 0 and weight 1. Deterministic.
pub fn large_decals(scene: &Scene, params: &LargeDecals, materials: Range<usize>) -> Result<Vec<Decal>> {
    if params.count > MAX_LARGE_DECALS {
        return Err(Error::InvalidConfig(format!("large decals: count {} exceeds the maximum of {MAX_LARGE_DECALS}", params.count)));
    }
    if materials.is_empty() || materials.end > scene.materials.len() {
        return Err(Error::InvalidConfig(format!(
            "large decals: materials {materials:?} must be a non-empty range of the scene's {} materials",
            scene.materials.len()
        )));
    }
    scene.validate()?;
    if params.count == 0 {
        return Ok(Vec::new());
    }
    let diagonal = scene.bounds().diagonal();
    if !(diagonal.is_finite() && diagonal > 0.0) {
        return Err(Error::InvalidConfig(format!("cannot place {} large decals: the scene has no extent", params.count)));
    }
    let planes = flat_surfaces(&Surfaces::new(scene), diagonal);
    let mut rng = Pcg64::seed_from_u64(params.seed);
    Ok(planes
        .into_iter()
        .take(params.count)
        .map(|plane| Decal { world_from_decal: plane.world_from_box, material: rng.random_range(materials.clone()), layer: 0, weight: 1.0 })
        .collect())
}

/// Appends [`large_decals`] to the scene's decals, which must not be grouped yet, with the procedural
/// decal materials, added the first time only.
pub fn add_large_decals(scene: &mut Scene, params: &LargeDecals) -> Result<()> {
    add_decals_with_builtin_materials(scene, params.count, |scene, materials| large_decals(scene, params, materials))
}

/// Runs a decal generator with the built-in decal materials, adding them to the scene the first time;
/// on error the scene is left as it was.
fn add_decals_with_builtin_materials(
    scene: &mut Scene,
    count: usize,
    generate: impl FnOnce(&Scene, Range<usize>) -> Result<Vec<Decal>>,
) -> Result<()> {
    check_ungrouped(&scene.decal_groups, "decals")?;
    if count == 0 {
        return Ok(());
    }
    let (material_count, texture_count) = (scene.materials.len(), scene.textures.len());
    let materials = decal_textures::find_decal_materials(scene).unwrap_or_else(|| decal_textures::add_decal_materials(scene));
    match generate(scene, materials) {
        Ok(decals) => {
            scene.decals.extend(decals);
            Ok(())
        }
        Err(e) => {
            scene.materials.truncate(material_count);
            scene.textures.truncate(texture_count);
            Err(e)
        }
    }
}

/// One flat surface: the triangles of one plane (one side of it), pooled.
struct FlatSurface {
    normal: Vec3,
    offset: f32,
    /// The decal box covering every triangle of the plane: x and y span it, z is its thickness.
    world_from_box: Affine3A,
}

/// The scene's planes, largest area first. Triangles are pooled by their normal (to about 3°) and
/// their distance from the origin (to 0.5 % of the scene's diagonal); a plane within that of a larger
/// one already taken is the same surface split across pooling cells and is dropped.
fn flat_surfaces(surfaces: &Surfaces, diagonal: f32) -> Vec<FlatSurface> {
    const NORMAL_CELLS: f32 = 20.0;
    let offset_cell = diagonal * 0.005;
    struct Pool {
        area: f64,
        normal_sum: Vec3,
        corners: Vec<Vec3>,
    }
    let mut pools: std::collections::HashMap<[i32; 4], Pool> = std::collections::HashMap::new();
    for &(ii, pi, first) in &surfaces.triangles {
        let [(a, na), (b, nb), (c, nc)] = surfaces.corners(ii as usize, pi as usize, first as usize);
        let cross = (b - a).cross(c - a);
        let area = cross.length() * 0.5;
        if !(area.is_finite() && area > 0.0) {
            continue;
        }
        let geometric = cross / (2.0 * area);
        let normal = if geometric.dot(na + nb + nc) < 0.0 { -geometric } else { geometric };
        let q = (normal * NORMAL_CELLS).round();
        let key = [q.x as i32, q.y as i32, q.z as i32, (normal.dot(a) / offset_cell).round() as i32];
        let pool = pools.entry(key).or_insert_with(|| Pool { area: 0.0, normal_sum: Vec3::ZERO, corners: Vec::new() });
        pool.area += f64::from(area);
        pool.normal_sum += normal * area;
        pool.corners.extend([a, b, c]);
    }
    let mut pools: Vec<([i32; 4], Pool)> = pools.into_iter().collect();
    // Largest first; the key breaks ties so the order never depends on the hash map's.
    pools.sort_by(|(ka, a), (kb, b)| b.area.total_cmp(&a.area).then(ka.cmp(kb)));

    let mut planes: Vec<FlatSurface> = Vec::new();
    for (_, pool) in pools {
        let normal = pool.normal_sum.normalize_or_zero();
        if normal == Vec3::ZERO {
            continue;
        }
        let offset = normal.dot(pool.corners[0]);
        let same_surface = |p: &FlatSurface| p.normal.dot(normal) > 0.99 && (p.offset - offset).abs() < 2.0 * offset_cell;
        if planes.iter().any(same_surface) {
            continue;
        }
        // The decal's image is upright: its y is world up, or -Z on floors and ceilings (as scene files place decals).
        let up = if normal.y.abs() > 0.99 { Vec3::NEG_Z } else { Vec3::Y };
        let x = up.cross(normal).normalize();
        let y = normal.cross(x);
        let (mut min, mut max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for p in &pool.corners {
            let local = Vec3::new(x.dot(*p), y.dot(*p), normal.dot(*p));
            min = min.min(local);
            max = max.max(local);
        }
        // Thick enough for the surface's relief: a hundredth of the scene's diagonal either side.
        let thickness = (max.z - min.z) + 0.02 * diagonal;
        let centre = (min + max) * 0.5;
        planes.push(FlatSurface {
            normal,
            offset,
            world_from_box: Affine3A::from_cols(
                (x * (max.x - min.x)).into(),
                (y * (max.y - min.y)).into(),
                (normal * thickness).into(),
                (x * centre.x + y * centre.y + normal * centre.z).into(),
            ),
        });
    }
    planes
}

/// Most particle emitters one generator call places.
pub const MAX_PARTICLE_EMITTERS: usize = 4096;

/// Particle lights launched from emitters on the scene's upward-facing surfaces
/// (`particles::ParticleSettings` with its defaults otherwise).
#[derive(Clone, Debug, PartialEq)]
pub struct ScatterParticles {
    pub count: u32,
    pub seed: u64,
    pub emitters: usize,
    /// Light radius (range) in metres, uniform in [min, max] per launch; emitters float the largest
    /// above their surfaces. `None`: [0.5, 1.5] × 2.7 % of the scene's bounding-box diagonal (about
    /// [0.5, 1.5] m in a courtyard like Sponza's).
    pub radius: Option<(f32, f32)>,
    /// Candela of a particle's brightest channel. `None`: [`DEFAULT_PARTICLE_INTENSITY`] for a
    /// radius of 1 m, scaled by the square of the mean radius (so the light they shed does not
    /// depend on the scene's units) and by the scene's [`light_level`], and shared out beyond
    /// [`BRIGHT_PARTICLES`] particles (so a million light a room as brightly as that many do).
    pub intensity: Option<f32>,
}

/// The intensity of a particle of 1 m mean radius, among at most [`BRIGHT_PARTICLES`].
pub const DEFAULT_PARTICLE_INTENSITY: f32 = 0.2;
pub const BRIGHT_PARTICLES: u32 = 65_536;

impl ScatterParticles {
    /// `count` particles from `emitters` emitters, with the default radius and intensity.
    pub fn new(count: u32, seed: u64, emitters: usize) -> Self {
        Self { count, seed, emitters, radius: None, intensity: None }
    }
}

/// Sets the scene's particles: `params.count` particle lights from `params.emitters` emitters a
/// particle's reach above seeded surface points facing up (or any surface points when none faces
/// up), launched fast enough to rise about a sixth of the scene's height. Deterministic.
pub fn add_particles(scene: &mut Scene, params: &ScatterParticles) -> Result<()> {
    if params.emitters == 0 || params.emitters > MAX_PARTICLE_EMITTERS {
        return Err(Error::InvalidConfig(format!("particles: {} emitters; give 1 to {MAX_PARTICLE_EMITTERS}", params.emitters)));
    }
    scene.validate()?;
    let bounds = scene.bounds();
    let typical = (bounds.diagonal() * 0.027).max(1e-3);
    let (low, high) = params.radius.unwrap_or((typical * 0.5, typical * 1.5));
    if !(low.is_finite() && high.is_finite() && low > 0.0 && low <= high) {
        return Err(Error::InvalidConfig(format!("particles: radius [{low}, {high}] must be finite with 0 < min ≤ max")));
    }
    let mean_radius = (low + high) * 0.5;
    let shared_out = (BRIGHT_PARTICLES as f32 / params.count.max(1) as f32).min(1.0);
    let intensity = params.intensity.unwrap_or(DEFAULT_PARTICLE_INTENSITY * mean_radius * mean_radius * shared_out * light_level(scene));
    let surfaces = Surfaces::new(scene);
    let area = surfaces.total_area();
    if !(area.is_finite() && area > 0.0) {
        return Err(Error::InvalidConfig(format!(
            "cannot place {} particle emitters: the scene has no triangles with any area",
            params.emitters
        )));
    }
    let mut settings = super::ParticleSettings {
        count: params.count,
        seed: params.seed as u32 ^ (params.seed >> 32) as u32,
        radius: (low, high),
        intensity,
        ..Default::default()
    };
    let height = (bounds.max.y - bounds.min.y).max(1e-3);
    let speed = (2.0 * settings.gravity * height / 6.0).sqrt();
    let mut rng = Pcg64::seed_from_u64(params.seed);
    // Upward-facing points, drawn among at most 64 tries each; any surface point after that. Each
    // emitter floats a particle's reach above its point: a light touching a surface is a singular
    // hot spot as a point light, which no grid voxel can hold.
    let lift = settings.radius.1;
    settings.emitters = (0..params.emitters)
        .map(|_| {
            let mut point = surfaces.sample(&mut rng);
            for _ in 0..64 {
                if point.1.y > 0.7 {
                    break;
                }
                point = surfaces.sample(&mut rng);
            }
            (point.0 + point.1 * lift, speed)
        })
        .collect();
    settings.validate()?;
    scene.particles = Some(settings);
    Ok(())
}

/// World-space items appended to grouped ones would land in the wrong space and break the grouping.
fn check_ungrouped(groups: &Groups, what: &str) -> Result<()> {
    if *groups != Groups::default() {
        return Err(Error::InvalidConfig(format!(
            "cannot scatter {what} into a scene whose {what} are grouped; scatter them before grouping \
             (use `--animate` rather than a scene file's `[animate]` with `--lights`/`--decals`)"
        )));
    }
    Ok(())
}

fn check_decals(params: &ScatterDecals) -> Result<()> {
    if params.count > MAX_SCATTERED_DECALS {
        return Err(Error::InvalidConfig(format!(
            "scattered decals: count {} exceeds the maximum of {MAX_SCATTERED_DECALS}",
            params.count
        )));
    }
    if let Some(size) = params.size {
        if !SCATTERED_DECAL_SIZES.contains(&size) {
            return Err(Error::InvalidConfig(format!(
                "scattered decals: size {size} m is outside {} to {} m (their boxes' matrices would lose their volume to rounding)",
                SCATTERED_DECAL_SIZES.start(),
                SCATTERED_DECAL_SIZES.end()
            )));
        }
    }
    Ok(())
}

/// Mean decal edges, in metres, the scatter accepts: from a tenth of a millimetre to a hundred
/// kilometres, where a box's f32 matrix and its inverse stay well conditioned.
pub const SCATTERED_DECAL_SIZES: std::ops::RangeInclusive<f32> = 1e-4..=1e5;

/// Group count of [`group_for_animation`] when none is given.
pub const DEFAULT_ANIMATION_GROUPS: usize = 16;

/// Splits the scene's lights, and its decals, into up to `groups` spatially coherent groups that spin
/// about their own vertical axes, for benchmarks of moving content: items are sorted along a Morton
/// curve over their bounds and cut into equal runs (fewer groups when there are fewer items). Each
/// group's items are stored relative to their centre and placed there by one instance spinning at
/// ±[0.3, 1] rad/s (seeded). At time 0 everything is where it was. The scene must not be grouped yet.
pub fn group_for_animation(scene: &mut Scene, groups: usize, seed: u64) -> Result<()> {
    if groups == 0 {
        return Err(Error::InvalidConfig("animation groups: the group count must be at least 1".into()));
    }
    for (what, existing) in [("lights", &scene.light_groups), ("decals", &scene.decal_groups)] {
        if *existing != Groups::default() {
            return Err(Error::InvalidConfig(format!(
                "animation groups: the scene's {what} are grouped already; group them once (not both `[animate]` in a scene file and `--animate`)"
            )));
        }
    }
    let mut rng = Pcg64::seed_from_u64(seed);
    scene.light_groups = group_items(&mut scene.lights, groups, &mut rng, |l| l.position, |l, centre| l.position -= centre);
    scene.decal_groups = group_items(
        &mut scene.decals,
        groups,
        &mut rng,
        |d| d.world_from_decal.translation.into(),
        |d, centre| d.world_from_decal = Affine3A::from_translation(-centre) * d.world_from_decal,
    );
    Ok(())
}

/// Sorts `items` by position along a Morton curve, cuts them into up to `groups` runs and moves each
/// run into its own space, centred on its bounds; returns the groups with one spinning instance each.
fn group_items<T>(
    items: &mut [T],
    groups: usize,
    rng: &mut Pcg64,
    position: impl Fn(&T) -> Vec3,
    recentre: impl Fn(&mut T, Vec3),
) -> Groups {
    if items.is_empty() {
        return Groups::default();
    }
    let mut bounds = Aabb::EMPTY;
    items.iter().for_each(|item| bounds.grow_point(position(item)));
    items.sort_by_cached_key(|item| morton_code(position(item), &bounds));

    let (n, k) = (items.len(), groups.min(items.len()));
    let mut result = Groups::default();
    for g in 0..k {
        let run = &mut items[g * n / k..(g + 1) * n / k];
        let mut run_bounds = Aabb::EMPTY;
        run.iter().for_each(|item| run_bounds.grow_point(position(item)));
        let centre = run_bounds.center();
        run.iter_mut().for_each(|item| recentre(item, centre));
        let speed = uniform(rng, (0.3, 1.0));
        let radians_per_second = if rng.random() { speed } else { -speed };
        result.sizes.push(run.len());
        result.instances.push(GroupInstance {
            group: g,
            world_from_group: Affine3A::from_translation(centre),
            spin: Some(Spin { pivot: centre, radians_per_second }),
        });
    }
    result
}

/// 30-bit Morton code of `p` quantised to 1024 steps per axis of `bounds`.
fn morton_code(p: Vec3, bounds: &Aabb) -> u32 {
    // A flat axis divides 0 by a tiny number; NaN saturates to 0.
    let unit = ((p - bounds.min) / (bounds.max - bounds.min).max(Vec3::splat(f32::MIN_POSITIVE))).clamp(Vec3::ZERO, Vec3::ONE);
    let q = (unit * 1023.0).as_uvec3();
    spread_bits(q.x) << 2 | spread_bits(q.y) << 1 | spread_bits(q.z)
}

/// Moves bit i of a 10-bit value to bit 3i.
fn spread_bits(v: u32) -> u32 {
    let mut x = v & 0x3ff;
    x = (x | x << 16) & 0x0300_00ff;
    x = (x | x << 8) & 0x0300_f00f;
    x = (x | x << 4) & 0x030c_30c3;
    (x | x << 2) & 0x0924_9249
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
    use crate::scene::{Instance, Material, Mesh, Primitive, Sun, Vertex};
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

    /// Under a sun in lux (a glTF file's) generated lights and particles are as much brighter than
    /// under the default sky's sun, and as bright without a sun as under it.
    #[test]
    fn default_intensities_follow_the_scenes_sun() {
        let default_sun = DaylightSky::for_scene(&Scene::default()).sun();
        let with_sun = |illuminance| {
            let mut scene = two_floors();
            scene.sun = Some(Sun { illuminance, ..default_sun });
            scene
        };
        let intensities = |scene: &Scene| {
            let lights = scatter_lights(scene, &ScatterLights::default()).unwrap();
            let mut with_particles = scene.clone();
            add_particles(&mut with_particles, &ScatterParticles::new(1000, 1, 4)).unwrap();
            (lights.iter().map(|l| l.intensity).collect::<Vec<_>>(), with_particles.particles.unwrap().intensity)
        };
        let (sky, lux, none) =
            (intensities(&with_sun(default_sun.illuminance)), intensities(&with_sun(68_300.0)), intensities(&two_floors()));
        assert_eq!(sky, none, "the default sky's sun and no sun alike");
        let ratio = 68_300.0 / default_sun.illuminance;
        assert!((lux.1 / sky.1 / ratio - 1.0).abs() < 1e-4, "particles: {} against {}", lux.1, sky.1);
        for (a, b) in sky.0.iter().zip(&lux.0) {
            assert!((b / a / ratio - 1.0).abs() < 1e-4, "lights: {b} against {a}");
        }
    }

    #[test]
    fn default_sizes_scale_with_the_scene_and_shrink_for_crowds() {
        let small = two_floors();
        let mut large = two_floors();
        for instance in &mut large.instances {
            instance.world_from_local = Mat4::from_scale(Vec3::splat(100.0)) * instance.world_from_local;
        }
        // The same lights, decals and particles on a scene a hundred times larger are a hundred times
        // larger, and ten thousand times brighter: the same picture.
        for count in [16, 20_000] {
            let (a, b) = (
                scatter_lights(&small, &ScatterLights { count, ..Default::default() }).unwrap(),
                scatter_lights(&large, &ScatterLights { count, ..Default::default() }).unwrap(),
            );
            for (a, b) in a.iter().zip(&b) {
                assert!((b.range / a.range - 100.0).abs() < 1e-2 && (b.intensity / a.intensity - 1e4).abs() < 2.0, "{a:?} {b:?}");
            }
        }
        let mut particles = (small.clone(), large.clone());
        add_particles(&mut particles.0, &ScatterParticles::new(1000, 1, 4)).unwrap();
        add_particles(&mut particles.1, &ScatterParticles::new(1000, 1, 4)).unwrap();
        let (a, b) = (particles.0.particles.unwrap(), particles.1.particles.unwrap());
        assert!((b.radius.1 / a.radius.1 - 100.0).abs() < 1e-2 && (b.intensity / a.intensity - 1e4).abs() < 2.0);
        // Beyond BRIGHT_PARTICLES, the particles share out the light of that many.
        let mut many = small.clone();
        add_particles(&mut many, &ScatterParticles::new(4 * BRIGHT_PARTICLES, 1, 4)).unwrap();
        assert!((many.particles.unwrap().intensity * 4.0 - a.intensity).abs() < 1e-6);
        // Many lights shrink to about DEFAULT_LIGHT_OVERLAP reaching a point: N π r² 13/12 over the area.
        let area = 2.0 * 16.0;
        let crowded = typical_light_range(small.bounds().diagonal(), area, 20_000);
        assert!(crowded < small.bounds().diagonal() * 0.04);
        let overlap = 20_000.0 * std::f32::consts::PI * crowded * crowded * 13.0 / 12.0 / area;
        assert!((overlap - DEFAULT_LIGHT_OVERLAP).abs() < 1e-3, "{overlap}");
        let size = typical_decal_size(small.bounds().diagonal(), area, 20_000);
        assert!((20_000.0 * size * size * 49.0 / 48.0 / area - DEFAULT_DECAL_OVERLAP).abs() < 1e-3);
        assert_eq!(typical_decal_size(small.bounds().diagonal(), area, 4), small.bounds().diagonal() * 0.025);
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

    fn decal_axes(d: &Decal) -> [Vec3; 4] {
        let m = d.world_from_decal;
        [m.matrix3.x_axis.into(), m.matrix3.y_axis.into(), m.matrix3.z_axis.into(), m.translation.into()]
    }

    #[test]
    fn decals_sit_on_surfaces_facing_out_along_the_normal() {
        let mut scene = two_floors();
        let materials = decal_textures::add_decal_materials(&mut scene);
        let params = ScatterDecals { count: 500, size: Some(0.4), ..Default::default() };
        let decals = scatter_decals(&scene, &params, materials.clone()).unwrap();
        assert_eq!(decals.len(), 500);
        for d in &decals {
            let [x, y, z, centre] = decal_axes(d);
            assert!(centre.x.abs() <= 2.0 && centre.z.abs() <= 2.0, "{centre}");
            // Facing up from the lower floor, down from the upside-down upper one.
            let on_lower = centre.y.abs() < 1e-5 && z.normalize().abs_diff_eq(Vec3::Y, 1e-5);
            let on_upper = (centre.y - 2.0).abs() < 1e-5 && z.normalize().abs_diff_eq(Vec3::NEG_Y, 1e-5);
            assert!(on_lower || on_upper, "{centre} {z}");
            let edge = x.length();
            assert!((0.3 - 1e-5..=0.5 + 1e-5).contains(&edge), "{edge}");
            assert!((y.length() - edge).abs() < 1e-5 && (z.length() - edge * 0.5).abs() < 1e-5);
            assert!(x.dot(y).abs() < 1e-5 && x.dot(z).abs() < 1e-5 && x.cross(y).dot(z) > 0.0);
            assert!(materials.contains(&d.material) && d.layer < DECAL_LAYERS && (0.5..=2.0).contains(&d.weight));
            crate::scene::validate_decal(d, scene.materials.len()).unwrap();
        }
        let lower = decals.iter().filter(|d| d.world_from_decal.translation.y < 1.0).count();
        assert!((200..300).contains(&lower), "equal areas get about equal shares: {lower} of 500");
        for layer in 0..DECAL_LAYERS {
            assert!(decals.iter().any(|d| d.layer == layer), "layer {layer} unused");
        }
        assert!(materials.clone().all(|m| decals.iter().any(|d| d.material == m)), "a material is unused");
        // Turned randomly about the normal.
        let lower_x: Vec<Vec3> =
            decals.iter().filter(|d| d.world_from_decal.translation.y < 1.0).map(|d| decal_axes(d)[0].normalize()).collect();
        assert!(lower_x.iter().any(|x| x.x > 0.9) && lower_x.iter().any(|x| x.x < -0.9) && lower_x.iter().any(|x| x.z > 0.9));
    }

    #[test]
    fn decals_are_seeded_and_sized_by_the_scene() {
        let mut scene = two_floors();
        let materials = decal_textures::add_decal_materials(&mut scene);
        let params = ScatterDecals { count: 64, ..Default::default() };
        let a = scatter_decals(&scene, &params, materials.clone()).unwrap();
        assert_eq!(a, scatter_decals(&scene, &params, materials.clone()).unwrap());
        assert_ne!(a, scatter_decals(&scene, &ScatterDecals { seed: 2, ..params }, materials).unwrap());
        let size = scene.bounds().diagonal() * 0.025;
        for d in &a {
            let edge = decal_axes(d)[0].length();
            assert!(edge >= size * 0.75 - 1e-5 && edge <= size * 1.25 + 1e-5, "{edge} for size {size}");
        }
    }

    #[test]
    fn add_scattered_decals_adds_the_materials_once() {
        let mut scene = two_floors();
        add_scattered_decals(&mut scene, &ScatterDecals { count: 0, ..Default::default() }).unwrap();
        assert_eq!((scene.materials.len(), scene.textures.len()), (1, 0), "no decals, no materials");
        add_scattered_decals(&mut scene, &ScatterDecals { count: 10, ..Default::default() }).unwrap();
        let materials = scene.materials.len();
        add_scattered_decals(&mut scene, &ScatterDecals { count: 5, seed: 9, ..Default::default() }).unwrap();
        assert_eq!(scene.materials.len(), materials);
        assert_eq!(scene.decals.len(), 15);
        assert!(scene.decals.iter().all(|d| d.material >= 1));
        scene.validate().unwrap();

        // A failed call leaves the scene as it was.
        let mut empty = Scene::default();
        let err = add_scattered_decals(&mut empty, &ScatterDecals::default()).unwrap_err();
        assert!(err.to_string().contains("no triangles"), "{err}");
        assert!(empty.materials.is_empty() && empty.textures.is_empty() && empty.decals.is_empty());
    }

    #[test]
    fn impossible_decal_requests_are_errors() {
        let mut scene = two_floors();
        let materials = decal_textures::add_decal_materials(&mut scene);
        for size in [0.0, -1.0, f32::NAN, f32::INFINITY, 1e-30, 1e30] {
            let err = scatter_decals(&scene, &ScatterDecals { size: Some(size), ..Default::default() }, materials.clone()).unwrap_err();
            assert!(matches!(err, Error::InvalidConfig(_)) && err.to_string().contains(&format!("size {size} m is outside")), "{err}");
        }
        let too_many = ScatterDecals { count: MAX_SCATTERED_DECALS + 1, ..Default::default() };
        let err = scatter_decals(&scene, &too_many, materials).unwrap_err();
        assert!(err.to_string().contains("16777216"), "{err}");
        for bad in [1..1, 0..100] {
            let err = scatter_decals(&scene, &ScatterDecals::default(), bad).unwrap_err();
            assert!(err.to_string().contains("non-empty range"), "{err}");
        }
        let err = scatter_decals(&Scene { materials: vec![Material::default()], ..Scene::default() }, &ScatterDecals::default(), 0..1);
        assert!(err.unwrap_err().to_string().contains("no triangles"));
    }

    /// Two floors with 100 lights and 60 decals scattered over them.
    fn populated() -> Scene {
        let mut scene = two_floors();
        add_scattered_lights(&mut scene, &ScatterLights { count: 100, ..Default::default() }).unwrap();
        add_scattered_decals(&mut scene, &ScatterDecals { count: 60, ..Default::default() }).unwrap();
        // A spot light, whose direction must survive grouping.
        scene.lights[7].kind = LightKind::Spot { inner_cone_angle: 0.2, outer_cone_angle: 0.4 };
        scene.lights[7].direction = Vec3::new(0.6, -0.8, 0.0);
        scene
    }

    /// Each grouped item's world transform at `time`, with the item.
    fn placed<T: Copy>(items: &[T], groups: &Groups, time: f32) -> Vec<(Affine3A, T)> {
        let (ranges, instances) = groups.resolve(items.len());
        instances.iter().flat_map(|i| ranges[i.group].clone().map(move |r| (i.world_from_group_at(time), items[r]))).collect()
    }

    #[test]
    fn grouping_keeps_everything_in_place_at_time_zero() {
        let original = populated();
        let mut scene = original.clone();
        group_for_animation(&mut scene, 7, 3).unwrap();
        scene.validate().unwrap();
        for groups in [&scene.light_groups, &scene.decal_groups] {
            assert_eq!(groups.sizes.len(), 7);
            assert_eq!(groups.instances.len(), 7);
            assert!(groups.is_animated());
        }
        assert_eq!(scene.light_groups.sizes.iter().sum::<usize>(), 100);
        assert_eq!(scene.decal_groups.sizes.iter().sum::<usize>(), 60);
        assert!(scene.light_groups.sizes.iter().all(|&n| n == 14 || n == 15));

        let mut unmatched = original.lights.clone();
        for (world_from_group, light) in placed(&scene.lights, &scene.light_groups, 0.0) {
            let world = Light { position: world_from_group.transform_point3(light.position), ..light };
            let i = unmatched
                .iter()
                .position(|l| l.position.abs_diff_eq(world.position, 1e-5) && Light { position: l.position, ..world } == *l);
            unmatched.swap_remove(i.unwrap_or_else(|| panic!("{world:?} was not in the scene")));
        }
        let mut unmatched = original.decals.clone();
        for (world_from_group, decal) in placed(&scene.decals, &scene.decal_groups, 0.0) {
            let world = world_from_group * decal.world_from_decal;
            let i = unmatched.iter().position(|d| {
                d.world_from_decal.abs_diff_eq(world, 1e-5)
                    && (d.material, d.layer, d.weight) == (decal.material, decal.layer, decal.weight)
            });
            unmatched.swap_remove(i.unwrap_or_else(|| panic!("{world:?} was not in the scene")));
        }
    }

    #[test]
    fn groups_move_rigidly_and_are_spatially_coherent() {
        let mut scene = populated();
        let all = scene.bounds().diagonal();
        group_for_animation(&mut scene, 8, 3).unwrap();
        let mut moved = false;
        let (t0, t1) = (placed(&scene.lights, &scene.light_groups, 0.0), placed(&scene.lights, &scene.light_groups, 2.3));
        let (ranges, _) = scene.light_groups.resolve(scene.lights.len());
        let mut diagonals = 0.0;
        for range in ranges {
            let mut bounds = Aabb::EMPTY;
            for i in range.clone() {
                let p = |placed: &[(Affine3A, Light)], i: usize| placed[i].0.transform_point3(placed[i].1.position);
                bounds.grow_point(p(&t0, i));
                moved |= p(&t0, i).distance(p(&t1, i)) > 1e-3;
                for j in range.clone() {
                    assert!((p(&t0, i).distance(p(&t0, j)) - p(&t1, i).distance(p(&t1, j))).abs() < 1e-4);
                }
                // Spot directions turn with their group.
                let direction = |placed: &[(Affine3A, Light)]| placed[i].0.transform_vector3(placed[i].1.direction);
                assert!((direction(&t1).length() - 1.0).abs() < 1e-5 && (direction(&t0).y - direction(&t1).y).abs() < 1e-5);
            }
            diagonals += bounds.diagonal();
        }
        assert!(moved, "nothing moved");
        assert!(diagonals / 8.0 < 0.75 * all, "groups are not compact: mean diagonal {} of {all}", diagonals / 8.0);
        let speeds: Vec<f32> = scene.light_groups.instances.iter().map(|i| i.spin.unwrap().radians_per_second).collect();
        assert!(speeds.iter().all(|s| (0.3..=1.0).contains(&s.abs())), "{speeds:?}");
        assert!(speeds.iter().any(|&s| s > 0.0) && speeds.iter().any(|&s| s < 0.0), "{speeds:?}");
    }

    #[test]
    fn grouping_is_seeded_and_adapts_to_few_items() {
        let (mut a, mut b, mut c) = (populated(), populated(), populated());
        group_for_animation(&mut a, 5, 1).unwrap();
        group_for_animation(&mut b, 5, 1).unwrap();
        group_for_animation(&mut c, 5, 2).unwrap();
        assert_eq!((&a.lights, &a.light_groups, &a.decal_groups), (&b.lights, &b.light_groups, &b.decal_groups));
        assert_ne!(a.light_groups, c.light_groups);

        let mut few = two_floors();
        few.lights = populated().lights[..3].to_vec();
        group_for_animation(&mut few, DEFAULT_ANIMATION_GROUPS, 1).unwrap();
        assert_eq!(few.light_groups.sizes, [1, 1, 1]);
        assert_eq!(few.decal_groups, Groups::default(), "no decals, no decal groups");
        few.validate().unwrap();
    }

    #[test]
    fn grouping_twice_or_into_no_groups_is_an_error() {
        let mut scene = populated();
        let err = group_for_animation(&mut scene, 0, 1).unwrap_err();
        assert!(matches!(err, Error::InvalidConfig(_)) && err.to_string().contains("at least 1"), "{err}");
        group_for_animation(&mut scene, 4, 1).unwrap();
        let err = group_for_animation(&mut scene, 4, 1).unwrap_err();
        assert!(err.to_string().contains("lights are grouped already"), "{err}");
        // Nor can world-space items join grouped ones.
        let err = add_scattered_lights(&mut scene, &ScatterLights::default()).unwrap_err();
        assert!(err.to_string().contains("scene whose lights are grouped"), "{err}");
        let err = add_scattered_decals(&mut scene, &ScatterDecals::default()).unwrap_err();
        assert!(err.to_string().contains("scene whose decals are grouped"), "{err}");
    }

    #[test]
    fn morton_codes_interleave_axes() {
        let bounds = Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert_eq!(morton_code(Vec3::ZERO, &bounds), 0);
        assert_eq!(morton_code(Vec3::ONE, &bounds), (1 << 30) - 1);
        assert_eq!(morton_code(Vec3::X, &bounds), 0x2492_4924);
        assert_eq!(morton_code(Vec3::Z, &bounds), 0x0924_9249);
        // Flat bounds and NaN do not panic.
        assert_eq!(morton_code(Vec3::NAN, &Aabb::new(Vec3::ONE, Vec3::ONE)), 0);
    }

    #[test]
    fn add_scattered_lights_appends() {
        let mut scene = two_floors();
        add_scattered_lights(&mut scene, &ScatterLights { count: 10, ..Default::default() }).unwrap();
        add_scattered_lights(&mut scene, &ScatterLights { count: 5, ..Default::default() }).unwrap();
        assert_eq!(scene.lights.len(), 15);
        scene.validate().unwrap();
    }

    #[test]
    fn large_decals_cover_whole_floors_largest_first() {
        let mut scene = two_floors();
        // The upper floor, flipped at y = 2, is made twice as wide: four times the area, so it comes first.
        scene.instances[1].world_from_local *= Mat4::from_scale(Vec3::new(2.0, 1.0, 2.0));
        add_large_decals(&mut scene, &LargeDecals { count: 5, seed: 1 }).unwrap();
        // Two planes, so two decals however many were asked for.
        assert_eq!(scene.decals.len(), 2);
        scene.validate().unwrap();
        let [upper, lower] = [&scene.decals[0], &scene.decals[1]];
        let inside = |d: &Decal, p: Vec3| crate::accel::decal_contains(d, p);
        for (x, z) in [(0.0, 0.0), (3.99, 3.99), (-3.99, 1.0)] {
            assert!(inside(upper, Vec3::new(x, 2.0, z)), "upper floor at ({x}, {z})");
        }
        for (x, z) in [(0.0, 0.0), (1.99, -1.99), (-1.99, 1.99)] {
            assert!(inside(lower, Vec3::new(x, 0.0, z)), "lower floor at ({x}, {z})");
            assert!(!inside(lower, Vec3::new(x, 1.0, z)), "a metre above the lower floor");
        }
        assert!(!inside(lower, Vec3::new(3.0, 0.0, 0.0)), "beyond the lower floor's edge");
        // Projecting along the floors' normals: the box's z faces out of each floor.
        let z = |d: &Decal| Vec3::from(d.world_from_decal.matrix3.z_axis).normalize();
        assert!(z(upper).abs_diff_eq(Vec3::NEG_Y, 1e-5) && z(lower).abs_diff_eq(Vec3::Y, 1e-5));
        assert!(scene.decals.iter().all(|d| d.layer == 0 && d.weight == 1.0));
        // Deterministic, and a count of 1 keeps the largest.
        let mut again = two_floors();
        again.instances[1].world_from_local *= Mat4::from_scale(Vec3::new(2.0, 1.0, 2.0));
        add_large_decals(&mut again, &LargeDecals { count: 1, seed: 1 }).unwrap();
        assert_eq!(again.decals, scene.decals[..1]);
        let err = add_large_decals(&mut again, &LargeDecals { count: MAX_LARGE_DECALS + 1, seed: 1 }).unwrap_err();
        assert!(err.to_string().contains("exceeds the maximum"), "{err}");
    }
}
