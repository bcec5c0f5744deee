//! TOML scene files: a glTF scene plus what it lacks for benchmarking (a camera, a sun, exposure,
//! explicit lights and decals, seeded scattered lights and decals, and animation).
//!
//! Every key is optional except where noted; unknown keys are errors. Relative paths are relative to
//! the TOML file. Angles are in degrees, directions need not be normalized.
//!
//! ```toml
//! gltf = "../shared/assets/sponza/Sponza.gltf"   # absent: an empty scene
//! exposure = 1.0                  # fixed linear scale before tonemapping; absent: exposed automatically
//! ambient = [0.03, 0.03, 0.03]    # uniform ambient radiance, where there is no sky or environment
//! sky = "auto"            # the daylight sky (settings::Sky), unless the command line says: "auto"
//!                         # (where the scene has no lights of its own but perhaps a sun, which places
//!                         # the sky and sets its brightness), "daylight" or "off"
//! environment = "sky.hdr" # an equirectangular Radiance HDR or OpenEXR image lighting the scene
//!                         # instead of the sky (centre column −Z, top row +Y)
//!
//! [camera]                # becomes camera 0; either `index = N` (move glTF camera N to the front) …
//! position = [-9.0, 1.5, 0.0]     # … or a look-at camera: position and target required
//! target = [0.0, 2.0, 0.0]
//! yfov_degrees = 60.0     # default 60
//! near = 0.05             # default 0.05; the far plane is at infinity
//!
//! [sun]                   # replaces the glTF's directional light
//! direction = [0.3, -1.0, 0.2]    # required: the direction the light travels
//! color = [1.0, 0.95, 0.9]        # default white
//! illuminance = 3.0               # required
//!
//! [[lights]]              # explicit lights, added to the glTF's
//! type = "point"          # required: "point" or "spot"
//! position = [0.0, 1.0, 0.0]      # required
//! color = [1.0, 0.8, 0.6]         # default white
//! intensity = 10.0        # required, candela
//! range = 5.0             # default: where intensity / d² falls to DEFAULT_LIGHT_CUTOFF
//!
//! [[lights]]
//! type = "spot"
//! position = [2.0, 4.0, 0.0]
//! intensity = 40.0
//! direction = [0.0, -1.0, 0.0]    # spot only, required
//! inner_cone_degrees = 20.0       # spot only, default 0
//! outer_cone_degrees = 30.0       # spot only, default 45
//! cast_shadows = true     # traces shadow rays towards it (within [rays] light_shadow_rays); default true
//!
//! [[scatter_lights]]      # point lights scattered over the surfaces (generators::ScatterLights)
//! count = 256             # required
//! seed = 1                # default 1
//! offset = 0.2            # distance along the surface normal; default a tenth of the mean range
//! range = [0.5, 2.0]      # uniform in [min, max]; default [0.5, 1.5] × 4 % of the scene's diagonal, less
//!                         # where many would crowd (about 2 lights reaching each surface point)
//! intensity = [0.5, 3.0]  # uniform in [min, max]; default (range / 2)² per light × the light level
//!                         # (the sun's illuminance over the default sky's sun's, 1 without a sun)
//!
//! [[decals]]              # explicit decals: a box centred on `position` projecting an image
//! position = [0.0, 0.0, -4.99]    # required
//! normal = [0.0, 0.0, 1.0]        # required: the direction the decal faces out of the surface
//! size = [1.0, 0.5, 0.2]  # required: width (image u), height (image v), depth (along the normal)
//! rotation_degrees = 0.0  # about the normal, counter-clockwise as seen facing the decal; default 0:
//!                         # the image's up is world +Y, or -Z where the normal is vertical
//! layer = 0               # 0 to 3, higher layers cover lower ones; default 0
//! weight = 1.0            # weight in its layer's blend, > 0; default 1
//! albedo = "decals/logo.png"      # required: colour and alpha (sRGB PNG, JPEG or EXR)
//! normal_map = "decals/logo_normal.png"   # tangent-space normals (glTF: green up); absent: normals
//!                                         # are left alone
//! roughness_metallic = "decals/logo_rm.png"   # G = roughness, B = metallic
//! color = [1.0, 1.0, 1.0, 1.0]    # factor on the albedo and alpha, 0 to 1; default 1
//! roughness = 0.5         # 0 to 1; default 1 (the texture's value, or fully rough)
//! metallic = 0.0          # 0 to 1; default 1 with `roughness_metallic` (the texture's value), else 0
//!
//! [[scatter_decals]]      # decals with built-in materials scattered over the surfaces (generators::ScatterDecals)
//! count = 256             # required
//! seed = 1                # default 1
//! size = 0.5              # mean edge; default 2.5 % of the scene's diagonal, less where many would
//!                         # crowd (about 1 decal covering each surface point)
//!
//! [[large_decals]]        # decals covering the largest flat surfaces, floors and walls (generators::LargeDecals)
//! count = 6               # required: one per plane, largest first
//! seed = 1                # default 1: picks their built-in materials
//!
//! [particles]             # moving particle lights (scene::ParticleSettings, generators::add_particles)
//! count = 262144          # required
//! seed = 1                # default 1
//! emitters = 16           # default 16: on seeded upward-facing surface points
//! radius = [0.5, 1.5]     # light range in metres, uniform per launch; default [0.5, 1.5] × 2.7 % of the scene's diagonal
//! intensity = 0.2         # candela of the brightest channel; default 0.2 × (mean radius in m)² × the light level,
//!                         # × 65536 / count beyond 65536 particles
//! lifetime = [2.0, 4.0]   # seconds between launches; default [2, 4]
//! method = "grid"         # how to render them, unless the command line says: "off", "grid" or "bvh"
//! voxel_size = 0.5        # the grid's voxel edge in metres, likewise
//! filter = "tricubic"     # "nearest", "trilinear" or "tricubic", likewise
//! samples = 4             # jittered samples per shading point, likewise
//! cascades = 4            # camera-centred clipmap cascades (0: one grid over the scene), likewise
//! cascade_resolution = 64 # voxels per axis of each cascade, likewise
//!
//! [methods]               # how lights and decals are found, unless the command line says
//! lights = "auto"         # "auto" (default: the fastest for the scene), "off", "brute", "bvh", "clustered"
//! decals = "auto"         # the same, or "deferred-decals" (deferred pipeline only)
//!
//! [rays]                  # ray-traced effects (settings::RaySettings), unless the command line says
//! shadows = "soft"        # the sun's: "off", "hard" (one ray per pixel) or "soft"; default "off"
//! sun_angle = 0.53        # the sun's angular diameter in degrees (soft shadows); default 0.53
//! shadow_rays = 4         # rays per pixel towards the sun's disc (soft shadows), 1 to 64; default 4
//! reflections = 1         # reflection bounces on glossy surfaces, 0 (none) to 8; default 0
//! reflection_roughness = 0.3      # surfaces below this perceptual roughness reflect; default 0.3
//! light_shadow_rays = 4   # shadow rays per shading point towards lights that cast shadows; default 0
//! direct_lighting = "restir"  # local lights: "exact" (default), "reference" (a shadow ray each) or "restir"
//! restir_shadow_rays = 1  # samples, each with its shadow ray, per point with "restir", 1 to 4; default 1
//! restir_reuse = "temporal"  # what "restir" reuses: "off", "temporal" (default) or "spatiotemporal"
//! restir_candidates = "auto"  # where "restir" finds candidates: "auto" (default), "enumeration" or "tree"
//! denoise = "svgf"        # how "restir"'s lighting is denoised: "svgf" (default) or "off"
//! backend = "auto"        # what traces: "auto" (default: ray queries where the GPU has them), "hardware" or "software"
//!
//! [[deform]]              # a travelling wave deforming every mesh of a name (scene::deform::Wave)
//! mesh = "Curtain"        # required: the glTF mesh name
//! amplitude = 0.05        # required: metres along the vertex normals
//! wavelength = 1.0        # required: metres
//! speed = 0.5             # metres per second the crests travel; default 0
//! direction = [1.0, 0.0, 0.0]     # in the mesh's space; default [1, 0, 0]
//!
//! [animate]               # group all lights and decals into spinning groups (generators::group_for_animation)
//! groups = 16             # default 16
//! seed = 1                # default 1
//! ```
//!
//! Images are loaded once per path however many decals use them, and decals with the same images and
//! factors share one material.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Affine3A, Vec3, Vec4};
use serde::Deserialize;

use super::generators::{self, LargeDecals, ScatterDecals, ScatterLights, ScatterParticles};
use super::{
    validate_decal, validate_light, Camera, Decal, Environment, Light, LightKind, Material, Scene, Sun, Texture, TextureRef, Wrap,
    DECAL_LAYERS, DEFAULT_LIGHT_CUTOFF,
};
use crate::files::{self, guard, InputKind, LoadBudget};
use crate::settings::{DecalMethod, LightMethod, MethodOverlay, ParticleOverlay, RayOverlay, SettingsOverlay, Sky, Spelling};
use crate::{Error, Result};

/// Loads a TOML scene file and the glTF it references, with the file's choices of how to render it.
pub fn load(path: &Path) -> Result<(Scene, SettingsOverlay)> {
    let budget = LoadBudget::new();
    let invalid = |reason: String| Error::SceneFile { path: path.to_owned(), reason: crate::error::one_line(&reason) };
    let bytes = files::read_input(path, InputKind::SceneFile, None, &budget)?;
    let text = String::from_utf8(bytes)
        .map_err(|e| invalid(format!("the file is not UTF-8 text (byte {} is not); save it as UTF-8", e.utf8_error().valid_up_to())))?;
    let file: SceneFile = guard::contain_panics(|| toml::from_str(&text))
        .map_err(|message| Error::ParserPanic { path: path.to_owned(), parser: "TOML reader", message })?
        .map_err(|e| invalid(toml_reason(&e, &text)))?;
    if file.is_empty() {
        return Err(invalid(
            "the file sets nothing to render; give it `gltf = \"model.gltf\"`, or [[lights]], [[decals]] and a [camera] (see scenes/)"
                .into(),
        ));
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut scene = match &file.gltf {
        Some(gltf) => super::gltf::import_within(&dir.join(gltf), &budget)?,
        None => Scene::default(),
    };
    let overlay = file.apply(&mut scene, dir, &budget).map_err(invalid)?;
    scene.source_files = budget.files();
    Ok((scene, overlay))
}

/// A TOML error on one line: where, what, and the offending line.
fn toml_reason(error: &toml::de::Error, text: &str) -> String {
    let message = error.message().trim_end().replace('\n', "; ");
    let Some(span) = error.span() else { return message };
    let start = span.start.min(text.len());
    let line = text[..start].matches('\n').count() + 1;
    let column = start - text[..start].rfind('\n').map_or(0, |i| i + 1) + 1;
    let source = text.lines().nth(line - 1).unwrap_or("").trim();
    let source: String = source.chars().take(60).collect();
    format!("line {line}, column {column}: {message} (in `{source}`)")
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    gltf: Option<PathBuf>,
    exposure: Option<f32>,
    ambient: Option<[f32; 3]>,
    sky: Option<Sky>,
    environment: Option<PathBuf>,
    camera: Option<CameraSpec>,
    sun: Option<SunSpec>,
    #[serde(default)]
    lights: Vec<LightSpec>,
    #[serde(default)]
    scatter_lights: Vec<ScatterSpec>,
    #[serde(default)]
    decals: Vec<DecalSpec>,
    #[serde(default)]
    scatter_decals: Vec<ScatterDecalsSpec>,
    #[serde(default)]
    large_decals: Vec<LargeDecalsSpec>,
    particles: Option<ParticlesSpec>,
    methods: Option<MethodsSpec>,
    rays: Option<RaysSpec>,
    #[serde(default)]
    deform: Vec<DeformSpec>,
    animate: Option<AnimateSpec>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DeformSpec {
    mesh: String,
    amplitude: f32,
    wavelength: f32,
    #[serde(default)]
    speed: f32,
    direction: Option<[f32; 3]>,
}

impl DeformSpec {
    fn apply(&self, scene: &mut Scene) -> Result<(), String> {
        let direction = Vec3::from(self.direction.unwrap_or([1.0, 0.0, 0.0]));
        if !(direction.is_finite() && direction.length() > 0.0) {
            return Err(format!("direction {direction} must be finite and non-zero"));
        }
        let wave = super::deform::Wave {
            amplitude: self.amplitude,
            wavelength: self.wavelength,
            speed: self.speed,
            direction: direction.normalize(),
        };
        wave.validate()?;
        let meshes: Vec<usize> = (0..scene.meshes.len()).filter(|&m| scene.meshes[m].name == self.mesh).collect();
        if meshes.is_empty() {
            return Err(format!("no mesh is named \"{}\"", self.mesh));
        }
        scene.deformers.extend(meshes.into_iter().map(|mesh| super::deform::Deformer::wave(mesh, wave)));
        Ok(())
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MethodsSpec {
    lights: Option<LightMethod>,
    decals: Option<DecalMethod>,
}

impl MethodsSpec {
    fn overlay(&self) -> MethodOverlay {
        MethodOverlay { lights: self.lights, decals: self.decals }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RaysSpec {
    shadows: Option<String>,
    sun_angle: Option<f32>,
    shadow_rays: Option<u32>,
    reflections: Option<u32>,
    reflection_roughness: Option<f32>,
    light_shadow_rays: Option<u32>,
    direct_lighting: Option<String>,
    restir_shadow_rays: Option<u32>,
    restir_reuse: Option<String>,
    restir_candidates: Option<String>,
    denoise: Option<String>,
    backend: Option<String>,
}

impl RaysSpec {
    fn overlay(&self) -> Result<RayOverlay, String> {
        let sun_shadows = self.shadows.as_deref().map(str::parse).transpose().map_err(|e| format!("shadows {e}"))?;
        let direct_lighting = self.direct_lighting.as_deref().map(str::parse).transpose().map_err(|e| format!("direct_lighting {e}"))?;
        let restir_reuse = self.restir_reuse.as_deref().map(str::parse).transpose().map_err(|e| format!("restir_reuse {e}"))?;
        let restir_candidates =
            self.restir_candidates.as_deref().map(str::parse).transpose().map_err(|e| format!("restir_candidates {e}"))?;
        let denoise = self.denoise.as_deref().map(str::parse).transpose().map_err(|e| format!("denoise {e}"))?;
        let backend = self.backend.as_deref().map(str::parse).transpose().map_err(|e| format!("backend {e}"))?;
        let overlay = RayOverlay {
            sun_shadows,
            sun_angle_degrees: self.sun_angle,
            shadow_rays: self.shadow_rays,
            reflection_bounces: self.reflections,
            reflection_roughness: self.reflection_roughness,
            light_shadow_rays: self.light_shadow_rays,
            direct_lighting,
            restir_shadow_rays: self.restir_shadow_rays,
            restir_reuse,
            restir_candidates,
            denoise,
            backend,
        };
        overlay.settings().validate(Spelling::Key).map_err(inner_message)?;
        Ok(overlay)
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraSpec {
    index: Option<usize>,
    position: Option<[f32; 3]>,
    target: Option<[f32; 3]>,
    yfov_degrees: Option<f32>,
    near: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SunSpec {
    direction: [f32; 3],
    #[serde(default = "white")]
    color: [f32; 3],
    illuminance: f32,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "lowercase")]
enum LightType {
    Point,
    Spot,
}

/// One flat table for both types (rather than a tagged enum) keeps toml's line numbers in errors.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LightSpec {
    #[serde(rename = "type")]
    kind: LightType,
    position: [f32; 3],
    #[serde(default = "white")]
    color: [f32; 3],
    intensity: f32,
    range: Option<f32>,
    direction: Option<[f32; 3]>,
    inner_cone_degrees: Option<f32>,
    outer_cone_degrees: Option<f32>,
    cast_shadows: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScatterSpec {
    count: usize,
    seed: Option<u64>,
    offset: Option<f32>,
    range: Option<[f32; 2]>,
    intensity: Option<[f32; 2]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DecalSpec {
    position: [f32; 3],
    normal: [f32; 3],
    #[serde(default)]
    rotation_degrees: f32,
    size: [f32; 3],
    #[serde(default)]
    layer: u32,
    #[serde(default = "one")]
    weight: f32,
    albedo: PathBuf,
    normal_map: Option<PathBuf>,
    roughness_metallic: Option<PathBuf>,
    #[serde(default = "opaque_white")]
    color: [f32; 4],
    roughness: Option<f32>,
    metallic: Option<f32>,
}

fn one() -> f32 {
    1.0
}

fn opaque_white() -> [f32; 4] {
    [1.0; 4]
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScatterDecalsSpec {
    count: usize,
    seed: Option<u64>,
    size: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LargeDecalsSpec {
    count: usize,
    seed: Option<u64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ParticlesSpec {
    count: u32,
    seed: Option<u64>,
    emitters: Option<usize>,
    radius: Option<(f32, f32)>,
    intensity: Option<f32>,
    lifetime: Option<(f32, f32)>,
    method: Option<String>,
    voxel_size: Option<f32>,
    filter: Option<String>,
    samples: Option<u32>,
    cascades: Option<u32>,
    cascade_resolution: Option<u32>,
}

impl ParticlesSpec {
    /// Adds the particles to `scene`; returns the file's choices of how to render them.
    fn apply(&self, scene: &mut Scene) -> Result<ParticleOverlay, String> {
        let mut params = ScatterParticles::new(self.count, self.seed.unwrap_or(1), self.emitters.unwrap_or(16));
        params.radius = self.radius;
        params.intensity = self.intensity;
        generators::add_particles(scene, &params).map_err(inner_message)?;
        let settings = scene.particles.as_mut().expect("set by add_particles");
        settings.lifetime = self.lifetime.unwrap_or(settings.lifetime);
        let overlay = ParticleOverlay {
            method: self.method.as_deref().map(str::parse).transpose().map_err(|e| format!("method {e}"))?,
            filter: self.filter.as_deref().map(str::parse).transpose().map_err(|e| format!("filter {e}"))?,
            voxel_size: self.voxel_size,
            samples: self.samples,
            cascades: self.cascades,
            cascade_resolution: self.cascade_resolution,
        };
        overlay.validate(Spelling::Key).map_err(inner_message)?;
        settings.validate().map_err(inner_message)?;
        Ok(overlay)
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AnimateSpec {
    groups: Option<usize>,
    seed: Option<u64>,
}

impl SceneFile {
    /// Whether the file gives nothing to see: no glTF, lights, decals or particles.
    fn is_empty(&self) -> bool {
        self.gltf.is_none()
            && self.lights.is_empty()
            && self.scatter_lights.is_empty()
            && self.decals.is_empty()
            && self.scatter_decals.is_empty()
            && self.large_decals.is_empty()
            && self.particles.is_none()
    }

    /// Applies the file's settings on top of the loaded glTF, resolving image paths against `dir`, and
    /// returns what it asks of the renderer; errors are reasons for `Error::SceneFile`.
    fn apply(&self, scene: &mut Scene, dir: &Path, budget: &LoadBudget) -> Result<SettingsOverlay, String> {
        let mut overlay = SettingsOverlay::default();
        if let Some(exposure) = self.exposure {
            if !(exposure.is_finite() && exposure > 0.0) {
                return Err(format!("exposure {exposure} must be a finite scale above 0 (or absent: exposed automatically)"));
            }
            overlay.exposure = Some(exposure);
        }
        if let Some(methods) = &self.methods {
            overlay.methods = methods.overlay();
        }
        if let Some(ambient) = self.ambient {
            scene.ambient = Vec3::from(ambient);
        }
        if let (Some(Sky::Daylight | Sky::Off), Some(_)) = (self.sky, &self.environment) {
            return Err("sky and environment: give one, the daylight sky or an environment image, not both".into());
        }
        overlay.sky = self.sky;
        if let Some(path) = &self.environment {
            scene.environment = Some(Environment::load(&dir.join(path), budget).map_err(|e| format!("environment: {e}"))?);
        }
        if let Some(camera) = &self.camera {
            camera.apply(&mut scene.cameras).map_err(|m| format!("camera: {m}"))?;
        }
        if let Some(sun) = &self.sun {
            scene.sun = Some(Sun {
                direction: Vec3::from(sun.direction).normalize_or_zero(),
                color: Vec3::from(sun.color),
                illuminance: sun.illuminance,
            });
        }
        for (i, spec) in self.lights.iter().enumerate() {
            let light = spec.to_light().and_then(|l| validate_light(&l).map(|()| l));
            scene.lights.push(light.map_err(|m| format!("light {i}: {m}"))?);
        }
        scene.authored_lights = scene.lights.len();
        for (i, spec) in self.scatter_lights.iter().enumerate() {
            generators::add_scattered_lights(scene, &spec.to_params()).map_err(|e| format!("scatter_lights {i}: {}", inner_message(e)))?;
        }
        let mut decal_materials = DecalMaterials::new(dir, budget);
        for (i, spec) in self.decals.iter().enumerate() {
            let decal = spec.to_decal(scene, &mut decal_materials).and_then(|d| validate_decal(&d, scene.materials.len()).map(|()| d));
            scene.decals.push(decal.map_err(|m| format!("decal {i}: {m}"))?);
        }
        for (i, spec) in self.large_decals.iter().enumerate() {
            let params = LargeDecals { count: spec.count, seed: spec.seed.unwrap_or(1) };
            generators::add_large_decals(scene, &params).map_err(|e| format!("large_decals {i}: {}", inner_message(e)))?;
        }
        for (i, spec) in self.scatter_decals.iter().enumerate() {
            let params = ScatterDecals { count: spec.count, seed: spec.seed.unwrap_or(ScatterDecals::default().seed), size: spec.size };
            generators::add_scattered_decals(scene, &params).map_err(|e| format!("scatter_decals {i}: {}", inner_message(e)))?;
        }
        if let Some(particles) = &self.particles {
            overlay.particles = particles.apply(scene).map_err(|m| format!("particles: {m}"))?;
        }
        if let Some(rays) = &self.rays {
            overlay.rays = rays.overlay().map_err(|m| format!("rays: {m}"))?;
        }
        for (i, spec) in self.deform.iter().enumerate() {
            spec.apply(scene).map_err(|m| format!("deform {i}: {m}"))?;
        }
        if let Some(animate) = &self.animate {
            let groups = animate.groups.unwrap_or(generators::DEFAULT_ANIMATION_GROUPS);
            generators::group_for_animation(scene, groups, animate.seed.unwrap_or(1))
                .map_err(|e| format!("animate: {}", inner_message(e)))?;
        }
        // Ambient and sun are checked here; the glTF part was checked on import.
        scene.validate().map_err(inner_message)?;
        Ok(overlay)
    }
}

/// The message of a scene or settings error without its generic prefix, for use in a
/// `SceneFile` error that already says where the problem is.
fn inner_message(e: Error) -> String {
    match e {
        Error::InvalidScene(m) | Error::InvalidConfig(m) => m,
        other => other.to_string(),
    }
}

impl CameraSpec {
    /// Puts the chosen camera at index 0.
    fn apply(&self, cameras: &mut Vec<Camera>) -> Result<(), String> {
        let look_at = [self.position.is_some(), self.target.is_some(), self.yfov_degrees.is_some(), self.near.is_some()];
        match (self.index, self.position, self.target) {
            (Some(_), ..) if look_at.contains(&true) => {
                Err("give either `index` or a look-at camera (`position`, `target`, …), not both".into())
            }
            (Some(index), ..) if index >= cameras.len() => {
                Err(format!("index {index} does not exist: the glTF has {} camera(s)", cameras.len()))
            }
            (Some(index), ..) => {
                let camera = cameras.remove(index);
                cameras.insert(0, camera);
                Ok(())
            }
            (None, Some(position), Some(target)) => {
                cameras.insert(0, self.look_at(Vec3::from(position), Vec3::from(target))?);
                Ok(())
            }
            (None, ..) => Err("a look-at camera needs both `position` and `target` (or give `index`)".into()),
        }
    }

    fn look_at(&self, position: Vec3, target: Vec3) -> Result<Camera, String> {
        let yfov_degrees = self.yfov_degrees.unwrap_or(60.0);
        let near = self.near.unwrap_or(0.05);
        if !(position.is_finite() && target.is_finite()) {
            return Err("position and target must be finite".into());
        }
        if position.abs().max(target.abs()).max_element() > MAX_CAMERA_COORDINATE {
            return Err(format!(
                "position {position} and target {target} must lie within {MAX_CAMERA_COORDINATE:e} m of the origin, where 32-bit \
                 floats still resolve a metre; move the camera (and the scene) nearer the origin"
            ));
        }
        if target == position {
            return Err("target equals position; give a target the camera looks towards".into());
        }
        // The camera's up is +Y, so it cannot look straight up or down.
        if (target - position).normalize_or_zero().cross(Vec3::Y).length() < 1e-4 {
            return Err("target lies straight above or below position, and the camera's up is +Y; move the target sideways".into());
        }
        if !(yfov_degrees > 0.0 && yfov_degrees < 180.0) {
            return Err(format!("yfov_degrees {yfov_degrees} must lie strictly between 0 and 180"));
        }
        if !(near.is_finite() && near >= super::camera::MIN_ZNEAR) {
            return Err(format!("near {near} must be finite and at least {} m", super::camera::MIN_ZNEAR));
        }
        Ok(Camera::look_at("scene file", position, target, yfov_degrees.to_radians(), near))
    }
}

/// How far from the origin a scene file's camera may stand, in metres.
const MAX_CAMERA_COORDINATE: f32 = 1e7;

impl LightSpec {
    fn to_light(&self) -> Result<Light, String> {
        let color = Vec3::from(self.color);
        let spot_only = [self.direction.is_some(), self.inner_cone_degrees.is_some(), self.outer_cone_degrees.is_some()];
        let (kind, direction) = match self.kind {
            LightType::Point if spot_only.contains(&true) => {
                return Err("`direction`, `inner_cone_degrees` and `outer_cone_degrees` apply to spot lights only".into())
            }
            LightType::Point => (LightKind::Point, Vec3::NEG_Y),
            LightType::Spot => {
                let direction = self.direction.ok_or("a spot light needs `direction`")?;
                let kind = LightKind::Spot {
                    inner_cone_angle: self.inner_cone_degrees.unwrap_or(0.0).to_radians(),
                    outer_cone_angle: self.outer_cone_degrees.unwrap_or(45.0).to_radians(),
                };
                (kind, Vec3::from(direction).normalize_or_zero())
            }
        };
        let range = match self.range {
            Some(range) => range,
            None => {
                let derived = Light::range_from_cutoff(self.intensity, color, DEFAULT_LIGHT_CUTOFF);
                if !(derived.is_finite() && derived > 0.0) {
                    return Err(format!(
                        "no range, and intensity {} with colour {:?} gives none to derive one from; give `range`, or an intensity and colour > 0",
                        self.intensity, self.color
                    ));
                }
                derived
            }
        };
        Ok(Light {
            kind,
            position: Vec3::from(self.position),
            direction,
            color,
            intensity: self.intensity,
            range,
            cast_shadows: self.cast_shadows.unwrap_or(true),
        })
    }
}

impl ScatterSpec {
    fn to_params(&self) -> ScatterLights {
        ScatterLights {
            count: self.count,
            seed: self.seed.unwrap_or(ScatterLights::default().seed),
            offset: self.offset,
            range: self.range.map(|[min, max]| (min, max)),
            intensity: self.intensity.map(|[min, max]| (min, max)),
        }
    }
}

impl DecalSpec {
    fn to_decal(&self, scene: &mut Scene, materials: &mut DecalMaterials) -> Result<Decal, String> {
        let (position, normal, size) = (Vec3::from(self.position), Vec3::from(self.normal), Vec3::from(self.size));
        if !position.is_finite() {
            return Err(format!("position {:?} is NaN or infinite", self.position));
        }
        if !(normal.is_finite() && normal.length() > 0.0) {
            return Err(format!("normal {:?} must be a finite, non-zero direction", self.normal));
        }
        if !(size.is_finite() && size.min_element() > 0.0) {
            return Err(format!("size {:?} must be finite and > 0 on every axis (width, height, depth)", self.size));
        }
        if !self.rotation_degrees.is_finite() {
            return Err(format!("rotation_degrees {} must be finite", self.rotation_degrees));
        }
        // Checked before the images are read, so that a typo is reported without waiting for them.
        if self.layer >= DECAL_LAYERS {
            return Err(format!("layer {} must be between 0 and {}", self.layer, DECAL_LAYERS - 1));
        }
        if !(self.weight.is_finite() && self.weight > 0.0) {
            return Err(format!("weight {} must be finite and > 0", self.weight));
        }
        let z = normal.normalize();
        // The image's up is world +Y projected onto the surface, or -Z where there is none.
        let up = if Vec3::Y.cross(z).length() > 1e-3 { Vec3::Y } else { Vec3::NEG_Z };
        let x0 = up.cross(z).normalize();
        let y0 = z.cross(x0);
        let (sin, cos) = self.rotation_degrees.to_radians().sin_cos();
        let (x, y) = (x0 * cos + y0 * sin, y0 * cos - x0 * sin);
        let world_from_decal = Affine3A::from_cols((x * size.x).into(), (y * size.y).into(), (z * size.z).into(), position.into());
        Ok(Decal { world_from_decal, material: materials.material(scene, self)?, layer: self.layer, weight: self.weight })
    }

    /// Factors as glTF defines them: without a metallic-roughness texture, a fully rough dielectric.
    fn factors(&self) -> Result<(Vec4, f32, f32), String> {
        let color = Vec4::from(self.color);
        if !(color.is_finite() && color.min_element() >= 0.0 && color.max_element() <= 1.0) {
            return Err(format!("color {:?} must lie between 0 and 1", self.color));
        }
        let textured = self.roughness_metallic.is_some();
        let roughness = self.roughness.unwrap_or(1.0);
        let metallic = self.metallic.unwrap_or(if textured { 1.0 } else { 0.0 });
        for (name, value) in [("roughness", roughness), ("metallic", metallic)] {
            if !(0.0..=1.0).contains(&value) {
                return Err(format!("{name} {value} must lie between 0 and 1"));
            }
        }
        Ok((color, roughness, metallic))
    }
}

/// What makes decal materials equal: albedo, normal and metallic-roughness texture, and the factors' bits.
type DecalMaterialKey = (usize, Option<usize>, Option<usize>, [u32; 6]);

/// The textures and materials of a file's decals, each image loaded once and each distinct
/// combination of images and factors made into one material.
struct DecalMaterials<'a> {
    dir: &'a Path,
    budget: &'a LoadBudget,
    textures: HashMap<PathBuf, usize>,
    materials: HashMap<DecalMaterialKey, usize>,
}

impl<'a> DecalMaterials<'a> {
    fn new(dir: &'a Path, budget: &'a LoadBudget) -> Self {
        Self { dir, budget, textures: HashMap::new(), materials: HashMap::new() }
    }

    fn material(&mut self, scene: &mut Scene, spec: &DecalSpec) -> Result<usize, String> {
        let (color, roughness, metallic) = spec.factors()?;
        let albedo = self.texture(scene, "albedo", &spec.albedo)?;
        let normal = spec.normal_map.as_ref().map(|path| self.texture(scene, "normal_map", path)).transpose()?;
        let roughness_metallic =
            spec.roughness_metallic.as_ref().map(|path| self.texture(scene, "roughness_metallic", path)).transpose()?;
        let factors = [color.x, color.y, color.z, color.w, roughness, metallic].map(f32::to_bits);
        let index = *self.materials.entry((albedo, normal, roughness_metallic, factors)).or_insert_with(|| {
            let clamped = |texture| TextureRef::new(texture, Wrap::ClampToEdge, Wrap::ClampToEdge);
            scene.materials.push(Material {
                name: format!("decal {}", spec.albedo.display()),
                base_color_factor: color,
                base_color_texture: Some(clamped(albedo)),
                metallic_factor: metallic,
                roughness_factor: roughness,
                metallic_roughness_texture: roughness_metallic.map(clamped),
                normal_texture: normal.map(clamped),
                ..Material::default()
            });
            scene.materials.len() - 1
        });
        Ok(index)
    }

    /// The texture index of the image at `path` (relative to the scene file), loading it the first time.
    fn texture(&mut self, scene: &mut Scene, key: &str, path: &Path) -> Result<usize, String> {
        let path = self.dir.join(path);
        if let Some(&index) = self.textures.get(&path) {
            return Ok(index);
        }
        scene.textures.push(load_image(&path, self.budget).map_err(|m| format!("{key} image {m}"))?);
        self.textures.insert(path, scene.textures.len() - 1);
        Ok(scene.textures.len() - 1)
    }
}

/// Decodes a PNG, JPEG or EXR file to RGBA8; the message starts with the path.
fn load_image(path: &Path, budget: &LoadBudget) -> Result<Texture, String> {
    let bytes = files::read_input(path, InputKind::Image, None, budget).map_err(|e| match e {
        Error::Io { error, .. } => format!("{}: cannot read it: {error} (check that the path exists and is readable)", path.display()),
        Error::Input { reason, .. } => format!("{}: {reason}", path.display()),
        e => e.to_string(),
    })?;
    let format = image::guess_format(&bytes)
        .ok()
        .filter(|f| matches!(f, image::ImageFormat::Png | image::ImageFormat::Jpeg | image::ImageFormat::OpenExr))
        .ok_or_else(|| {
            format!("{}: not a readable PNG, JPEG or EXR image (its bytes are none of these); convert it to one of those", path.display())
        })?;
    let decoded = guard::contain_panics(|| super::gltf::decode_limited(&bytes, format, budget))
        .unwrap_or_else(|message| Err(format!("the image decoder failed on it ({message}); re-save the image")))
        .map_err(|e| format!("{}: not a readable PNG, JPEG or EXR image: {e}", path.display()))?;
    let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    Ok(Texture { name, width: decoded.width, height: decoded.height, rgba8: super::gltf::to_rgba8(decoded) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::test_support::{assets_dir, temp_dir};
    use crate::scene::Projection;

    /// Writes `text` as `scene.toml` in a fresh directory and loads it.
    fn load_text(test: &str, text: &str) -> Result<Scene> {
        let dir = temp_dir(test);
        let path = dir.join("scene.toml");
        std::fs::write(&path, text).unwrap();
        load(&path)
    }

    /// The scene alone.
    fn load(path: &Path) -> Result<Scene> {
        super::load(path).map(|(scene, _)| scene)
    }

    #[test]
    fn sky_and_environment_keys() {
        let dir = temp_dir("scene_file_environment");
        let pixels = vec![image::Rgb([0.25f32, 0.5, 1.0]); 8];
        image::codecs::hdr::HdrEncoder::new(std::fs::File::create(dir.join("sky.hdr")).unwrap()).encode(&pixels, 4, 2).unwrap();
        let gltf = format!("gltf = {:?}\n", assets_dir().join("box/Box.glb"));
        let path = dir.join("scene.toml");
        std::fs::write(&path, format!("{gltf}sky = \"daylight\"\n")).unwrap();
        let (scene, overlay) = super::load(&path).unwrap();
        assert_eq!((overlay.sky, scene.environment), (Some(Sky::Daylight), None), "the scene file's sky is an overlay its caller applies");
        std::fs::write(&path, format!("{gltf}environment = \"sky.hdr\"\n")).unwrap();
        let environment = load(&path).unwrap().environment.expect("the environment image");
        assert_eq!((environment.width, environment.height, environment.radiance[0]), (4, 2, [0.25, 0.5, 1.0]));
        std::fs::write(&path, format!("{gltf}sky = \"off\"\nenvironment = \"sky.hdr\"\n")).unwrap();
        let both = reason(load(&path));
        assert!(both.contains("sky and environment: give one"), "{both}");
        std::fs::write(&path, format!("{gltf}environment = \"missing.hdr\"\n")).unwrap();
        let missing = reason(load(&path));
        assert!(missing.contains("environment: cannot read") && missing.contains("missing.hdr"), "{missing}");
    }

    fn reason(result: Result<Scene>) -> String {
        match result {
            Err(Error::SceneFile { reason, .. }) => reason,
            other => panic!("expected a scene-file error, got {other:?}"),
        }
    }

    #[test]
    fn deform_waves_every_mesh_of_its_name_and_bad_ones_are_named() {
        let gltf = assets_dir().join("box/Box.gltf");
        let file = |extra: &str| {
            format!("gltf = {:?}\n[[deform]]\nmesh = \"Mesh\"\namplitude = 0.1\nwavelength = 2.0\n{extra}", gltf.to_str().unwrap())
        };
        let scene = load_text("deform", &file("speed = 0.5\ndirection = [0.0, 2.0, 0.0]\n")).unwrap();
        let [deformer] = &scene.deformers[..] else { panic!("{:?}", scene.deformers) };
        assert_eq!(scene.meshes[deformer.mesh].name, "Mesh");
        let crate::scene::deform::Deformation::Wave(wave) = deformer.deformation else { panic!("{deformer:?}") };
        assert_eq!((wave.amplitude, wave.wavelength, wave.speed), (0.1, 2.0, 0.5));
        assert_eq!(wave.direction, Vec3::Y, "directions are normalised");
        let unknown = reason(load_text("deform_unknown", &file("").replace("\"Mesh\"", "\"Flag\"")));
        assert!(unknown.contains("deform 0") && unknown.contains("no mesh is named \"Flag\""), "{unknown}");
        let flat = reason(load_text("deform_wavelength", &file("").replace("wavelength = 2.0", "wavelength = 0.0")));
        assert!(flat.contains("deform 0") && flat.contains("wavelength 0"), "{flat}");
        let twice =
            reason(load_text("deform_twice", &format!("{}[[deform]]\nmesh = \"Mesh\"\namplitude = 0.1\nwavelength = 1.0\n", file(""))));
        assert!(twice.contains("has a deformer already"), "{twice}");
    }

    #[test]
    fn complete_file_with_a_relative_gltf() {
        let dir = temp_dir("complete");
        std::fs::create_dir(dir.join("models")).unwrap();
        for file in ["Box.gltf", "Box0.bin"] {
            std::fs::copy(assets_dir().join("box").join(file), dir.join("models").join(file)).unwrap();
        }
        let path = dir.join("scene.toml");
        std::fs::write(
            &path,
            r#"
gltf = "models/Box.gltf"
exposure = 2.0
ambient = [0.1, 0.2, 0.3]

[methods]
lights = "clustered"
decals = "bvh"

[camera]
position = [3.0, 2.0, 3.0]
target = [0.0, 0.0, 0.0]
yfov_degrees = 45.0

[sun]
direction = [0.0, -2.0, 0.0]
color = [1.0, 0.9, 0.8]
illuminance = 2.5

[[lights]]
type = "point"
position = [0.0, 1.0, 0.0]
color = [1.0, 0.5, 0.5]
intensity = 4.0

[[lights]]
type = "spot"
position = [0.0, 3.0, 0.0]
intensity = 20.0
range = 6.0
direction = [0.0, -3.0, 0.0]
inner_cone_degrees = 20.0
outer_cone_degrees = 30.0

[[scatter_lights]]
count = 16
seed = 7
offset = 0.05
range = [0.5, 1.0]
intensity = [1.0, 2.0]
"#,
        )
        .unwrap();
        let (scene, overlay) = super::load(&path).unwrap();
        assert_eq!(scene.drawn_triangle_count(), 12);
        assert_eq!(overlay.exposure, Some(2.0));
        assert_eq!(overlay.methods, MethodOverlay { lights: Some(LightMethod::Clustered), decals: Some(DecalMethod::Bvh) });
        assert_eq!(scene.ambient, Vec3::new(0.1, 0.2, 0.3));
        assert_eq!(scene.cameras.len(), 1);
        assert!(scene.cameras[0].position().abs_diff_eq(Vec3::new(3.0, 2.0, 3.0), 1e-5));
        assert!(matches!(scene.cameras[0].projection, Projection::Perspective { yfov, .. } if (yfov - 45f32.to_radians()).abs() < 1e-6));
        let sun = scene.sun.unwrap();
        assert_eq!((sun.direction, sun.illuminance), (Vec3::NEG_Y, 2.5));

        assert_eq!(scene.lights.len(), 2 + 16);
        let point = scene.lights[0];
        assert_eq!(point.range, Light::range_from_cutoff(4.0, Vec3::new(1.0, 0.5, 0.5), DEFAULT_LIGHT_CUTOFF));
        let spot = scene.lights[1];
        assert_eq!(spot.direction, Vec3::NEG_Y);
        assert_eq!(spot.range, 6.0);
        let LightKind::Spot { inner_cone_angle, outer_cone_angle } = spot.kind else { panic!("{spot:?}") };
        assert!((inner_cone_angle - 20f32.to_radians()).abs() < 1e-6 && (outer_cone_angle - 30f32.to_radians()).abs() < 1e-6);
        assert!(scene.lights[2..].iter().all(|l| (0.5..=1.0).contains(&l.range) && (1.0..=2.0).contains(&l.intensity)));

        let again = load(&path).unwrap();
        assert_eq!(scene.lights, again.lights, "scattering is seeded");
    }

    #[test]
    fn a_file_with_nothing_to_render_is_an_error() {
        for text in ["", "# nothing\n", "exposure = 2.0\n[sun]\ndirection = [0, -1, 0]\nilluminance = 3.0\n"] {
            let reason = reason(load_text("empty", text));
            assert!(reason.contains("sets nothing to render") && reason.contains("gltf ="), "{reason}");
        }
        let lights_only = load_text("lights_only", "[[lights]]\ntype = 'point'\nposition = [0, 1, 0]\nintensity = 1.0\n").unwrap();
        assert_eq!(lights_only.lights.len(), 1);
    }

    #[test]
    fn look_at_cameras_that_cannot_look_say_why() {
        let camera = |position: &str, target: &str| {
            let light = "[[lights]]\ntype = 'point'\nposition = [0, 1, 0]\nintensity = 1.0\n";
            reason(load_text("look_at", &format!("{light}[camera]\nposition = {position}\ntarget = {target}\n")))
        };
        let far = camera("[3e38, 0, 0]", "[-3e38, 0, 0]");
        assert!(far.contains("within 1e7 m of the origin") && !far.contains("equals"), "{far}");
        assert!(camera("[1, 2, 3]", "[1, 2, 3]").contains("target equals position"));
        assert!(camera("[1, 2, 3]", "[1, 5, 3]").contains("straight above or below"));
    }

    #[test]
    fn toml_errors_fit_one_line_and_text_must_be_utf8() {
        let syntax = reason(load_text("toml_syntax", "exposure = 1.0\n[sun\ndirection = [0, -1, 0]\n"));
        assert!(!syntax.contains('\n') && syntax.starts_with("line 2, column") && syntax.contains("`[sun`"), "{syntax}");
        let unknown = reason(load_text("toml_unknown", "exposur = 1.0\n"));
        assert!(!unknown.contains('\n') && unknown.contains("line 1") && unknown.contains("exposur"), "{unknown}");
        let dir = temp_dir("toml_latin1");
        let path = dir.join("scene.toml");
        std::fs::write(&path, b"# caf\xe9\ngltf = 'x.gltf'\n").unwrap();
        let latin1 = reason(load(&path));
        assert!(latin1.contains("not UTF-8 text (byte 5") && latin1.contains("save it as UTF-8"), "{latin1}");
    }

    #[test]
    fn camera_index_moves_a_gltf_camera_to_the_front() {
        let dir = temp_dir("camera_index");
        let gltf = r#"{
            "asset": {"version": "2.0"},
            "cameras": [
                {"name": "A", "type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.1}},
                {"name": "B", "type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}
            ],
            "nodes": [{"camera": 0}, {"camera": 1, "translation": [0, 0, 5]}],
            "scenes": [{"nodes": [0, 1]}]
        }"#;
        std::fs::write(dir.join("cameras.gltf"), gltf).unwrap();
        let path = dir.join("scene.toml");
        std::fs::write(&path, "gltf = 'cameras.gltf'\n[camera]\nindex = 1\n").unwrap();
        let names: Vec<String> = load(&path).unwrap().cameras.into_iter().map(|c| c.name).collect();
        assert_eq!(names, ["B", "A"]);

        std::fs::write(&path, "gltf = 'cameras.gltf'\n[camera]\nindex = 2\n").unwrap();
        assert!(reason(load(&path)).contains("index 2 does not exist"));
        std::fs::write(&path, "gltf = 'cameras.gltf'\n[camera]\nindex = 0\nnear = 1.0\n").unwrap();
        assert!(reason(load(&path)).contains("not both"));
    }

    #[test]
    fn bad_lights_are_reported_with_their_index() {
        let nan = reason(load_text("nan", "[[lights]]\ntype = 'point'\nposition = [nan, 0, 0]\nintensity = 1.0\n"));
        assert!(nan.starts_with("light 0: position [NaN, 0.0, 0.0] is NaN or infinite"), "{nan}");

        let negative = reason(load_text(
            "negative_range",
            "[[lights]]\ntype = 'point'\nposition = [0, 0, 0]\nintensity = 1.0\n\
             [[lights]]\ntype = 'point'\nposition = [0, 0, 0]\nintensity = 1.0\nrange = -2.0\n",
        ));
        assert!(negative.starts_with("light 1: range -2 must be finite and > 0"), "{negative}");

        let spot = reason(load_text("spot", "[[lights]]\ntype = 'spot'\nposition = [0, 0, 0]\nintensity = 1.0\n"));
        assert!(spot.contains("needs `direction`"), "{spot}");
    }

    #[test]
    fn unknown_keys_and_syntax_errors_carry_the_line() {
        let unknown = reason(load_text("unknown", "exposure = 1.0\n[sun]\ndirection = [0, -1, 0]\nilluminance = 1\nbrightness = 2\n"));
        assert!(unknown.contains("line 5") && unknown.contains("unknown field `brightness`"), "{unknown}");
        let syntax = reason(load_text("syntax", "exposure = 1.0\nambient = [0.1, 0.1\n"));
        assert!(syntax.contains("line 2"), "{syntax}");
    }

    #[test]
    fn invalid_globals_and_scatter_settings_are_scene_file_errors() {
        let light = "[[lights]]\ntype = 'point'\nposition = [0, 1, 0]\nintensity = 1.0\n";
        assert!(reason(load_text("exposure", &format!("exposure = 0.0\n{light}"))).contains("exposure 0 must be a finite scale above 0"));
        let method = reason(load_text("method", &format!("[methods]\nlights = \"fast\"\n{light}")));
        assert!(method.contains("fast") && method.contains("bvh"), "{method}");
        let scatter = reason(load_text("scatter", "[[scatter_lights]]\ncount = 4\n"));
        assert!(scatter.starts_with("scatter_lights 0:") && scatter.contains("no triangles"), "{scatter}");
    }

    /// Writes a `size`² RGBA PNG of one colour.
    fn write_png(path: &Path, size: u32, rgba: [u8; 4]) {
        image::RgbaImage::from_pixel(size, size, image::Rgba(rgba)).save(path).unwrap();
    }

    fn axes(d: &Decal) -> [Vec3; 4] {
        let m = d.world_from_decal;
        [m.matrix3.x_axis.into(), m.matrix3.y_axis.into(), m.matrix3.z_axis.into(), m.translation.into()]
    }

    #[test]
    fn explicit_decals_with_every_field_and_with_defaults() {
        let dir = temp_dir("decals");
        std::fs::create_dir(dir.join("decals")).unwrap();
        write_png(&dir.join("decals/logo.png"), 8, [200, 100, 50, 128]);
        write_png(&dir.join("decals/normal.png"), 4, [128, 128, 255, 255]);
        write_png(&dir.join("decals/rm.png"), 4, [255, 100, 200, 255]);
        let path = dir.join("scene.toml");
        std::fs::write(
            &path,
            r#"
[[decals]]
position = [1.0, 2.0, -4.9]
normal = [0.0, 0.0, 2.0]
rotation_degrees = 90.0
size = [2.0, 1.0, 0.5]
layer = 3
weight = 0.5
albedo = "decals/logo.png"
normal_map = "decals/normal.png"
roughness_metallic = "decals/rm.png"
color = [1.0, 0.5, 0.25, 0.8]
roughness = 0.5
metallic = 0.25

[[decals]]
position = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
size = [1.0, 1.0, 1.0]
albedo = "decals/logo.png"

[[decals]]
position = [3.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
size = [1.0, 2.0, 1.0]
albedo = "decals/logo.png"

[[decals]]
position = [0.0, 1.0, 0.0]
normal = [1.0, 0.0, 0.0]
size = [1.0, 1.0, 1.0]
albedo = "decals/logo.png"
roughness_metallic = "decals/rm.png"
"#,
        )
        .unwrap();
        let scene = load(&path).unwrap();
        assert_eq!(scene.decals.len(), 4);

        // Facing +Z, turned a quarter counter-clockwise: u runs up (+Y), v's opposite left (-X).
        let full = scene.decals[0];
        let [x, y, z, centre] = axes(&full);
        assert!(
            x.abs_diff_eq(Vec3::Y * 2.0, 1e-5) && y.abs_diff_eq(Vec3::NEG_X, 1e-5) && z.abs_diff_eq(Vec3::Z * 0.5, 1e-5),
            "{x} {y} {z}"
        );
        assert_eq!(centre, Vec3::new(1.0, 2.0, -4.9));
        assert_eq!((full.layer, full.weight), (3, 0.5));
        let m = &scene.materials[full.material];
        assert_eq!(m.base_color_factor, Vec4::new(1.0, 0.5, 0.25, 0.8));
        assert_eq!((m.roughness_factor, m.metallic_factor), (0.5, 0.25));
        let texture = |t: Option<TextureRef>| {
            let t = t.unwrap();
            assert_eq!((t.wrap_u, t.wrap_v), (Wrap::ClampToEdge, Wrap::ClampToEdge));
            &scene.textures[t.texture]
        };
        let albedo = texture(m.base_color_texture);
        assert_eq!((albedo.name.as_str(), albedo.width, &albedo.rgba8[..4]), ("logo.png", 8, &[200, 100, 50, 128][..]));
        assert_eq!(&texture(m.normal_texture).rgba8[..4], &[128, 128, 255, 255]);
        assert_eq!(&texture(m.metallic_roughness_texture).rgba8[..4], &[255, 100, 200, 255]);

        // Defaults: on a floor the image's up is -Z; layer 0, weight 1, white, fully rough dielectric.
        let plain = scene.decals[1];
        let [x, y, z, _] = axes(&plain);
        assert!(x.abs_diff_eq(Vec3::X, 1e-6) && y.abs_diff_eq(Vec3::NEG_Z, 1e-6) && z.abs_diff_eq(Vec3::Y, 1e-6), "{x} {y} {z}");
        assert_eq!((plain.layer, plain.weight), (0, 1.0));
        let m = &scene.materials[plain.material];
        assert_eq!((m.base_color_factor, m.roughness_factor, m.metallic_factor), (Vec4::ONE, 1.0, 0.0));
        assert!(m.normal_texture.is_none() && m.metallic_roughness_texture.is_none());
        // The same image and factors share one material; the image is loaded once.
        assert_eq!(scene.decals[2].material, plain.material);
        assert_eq!(scene.textures.iter().filter(|t| t.name == "logo.png").count(), 1);
        // On a wall the image's up is +Y; with a metallic-roughness texture both factors default to 1.
        let [x, y, ..] = axes(&scene.decals[3]);
        assert!(x.abs_diff_eq(Vec3::NEG_Z, 1e-6) && y.abs_diff_eq(Vec3::Y, 1e-6), "{x} {y}");
        let m = &scene.materials[scene.decals[3].material];
        assert_eq!((m.roughness_factor, m.metallic_factor), (1.0, 1.0));
        assert_eq!(scene.materials.len(), 3);
    }

    /// A decal table with `extra` lines, in a directory holding `logo.png`.
    fn decal_reason(test: &str, extra: &str) -> String {
        let dir = temp_dir(test);
        write_png(&dir.join("logo.png"), 4, [255; 4]);
        let path = dir.join("scene.toml");
        let mut text = "[[decals]]\nalbedo = 'logo.png'\n".to_string();
        for (key, value) in [("position", "[0, 0, 0]"), ("normal", "[0, 1, 0]"), ("size", "[1, 1, 1]")] {
            if !extra.contains(&format!("{key} =")) {
                text += &format!("{key} = {value}\n");
            }
        }
        std::fs::write(&path, text + extra).unwrap();
        reason(load(&path))
    }

    #[test]
    fn bad_decals_are_reported_with_their_index_and_field() {
        let cases = [
            ("position = [nan, 0, 0]", "decal 0: position [NaN, 0.0, 0.0] is NaN or infinite"),
            ("normal = [0, 0, 0]", "decal 0: normal [0.0, 0.0, 0.0] must be a finite, non-zero direction"),
            ("size = [1, 0, 1]", "decal 0: size [1.0, 0.0, 1.0] must be finite and > 0 on every axis"),
            ("size = [1, 1, inf]", "decal 0: size [1.0, 1.0, inf] must be finite"),
            ("rotation_degrees = nan", "decal 0: rotation_degrees NaN must be finite"),
            ("layer = 4", "decal 0: layer 4 must be between 0 and 3"),
            ("weight = 0.0", "decal 0: weight 0 must be finite and > 0"),
            ("color = [1, 1, 2, 1]", "decal 0: color [1.0, 1.0, 2.0, 1.0] must lie between 0 and 1"),
            ("roughness = -0.5", "decal 0: roughness -0.5 must lie between 0 and 1"),
            ("metallic = nan", "decal 0: metallic NaN must lie between 0 and 1"),
        ];
        for (i, (extra, expected)) in cases.iter().enumerate() {
            let reason = decal_reason(&format!("bad_decal_{i}"), extra);
            assert!(reason.starts_with(expected), "{extra}: {reason}");
        }
        let negative = decal_reason("negative_layer", "layer = -1");
        assert!(negative.contains("line") && negative.contains("layer"), "{negative}");
        let unknown = decal_reason("unknown_decal_key", "normal_texture = 'logo.png'");
        assert!(unknown.contains("unknown field `normal_texture`"), "{unknown}");
        let missing = reason(load_text("decal_no_albedo", "[[decals]]\nposition = [0, 0, 0]\nnormal = [0, 1, 0]\nsize = [1, 1, 1]\n"));
        assert!(missing.contains("missing field `albedo`"), "{missing}");
    }

    #[test]
    fn missing_and_corrupt_decal_images_are_named() {
        let missing = decal_reason("missing_image", "normal_map = 'nope.png'");
        assert!(missing.starts_with("decal 0: normal_map image ") && missing.contains("nope.png: cannot read it"), "{missing}");
        let dir = temp_dir("corrupt_image");
        let mut png = Vec::new();
        image::RgbaImage::new(16, 16).write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).unwrap();
        std::fs::write(dir.join("broken.png"), &png[..png.len() / 2]).unwrap();
        std::fs::write(dir.join("text.png"), "not an image").unwrap();
        for file in ["broken.png", "text.png"] {
            let path = dir.join("scene.toml");
            std::fs::write(&path, format!("[[decals]]\nposition = [0, 0, 0]\nnormal = [0, 1, 0]\nsize = [1, 1, 1]\nalbedo = '{file}'\n"))
                .unwrap();
            let reason = reason(load(&path));
            assert!(reason.starts_with("decal 0: albedo image ") && reason.contains(&format!("{file}: not a readable")), "{reason}");
        }
    }

    #[test]
    fn scattered_and_animated_decals_and_lights() {
        let dir = temp_dir("scatter_decals");
        for file in ["Box.gltf", "Box0.bin"] {
            std::fs::copy(assets_dir().join("box").join(file), dir.join(file)).unwrap();
        }
        let path = dir.join("scene.toml");
        let text = "gltf = 'Box.gltf'\n[[scatter_lights]]\ncount = 40\n\
                    [[scatter_decals]]\ncount = 30\nseed = 4\nsize = 0.2\n[[scatter_decals]]\ncount = 10\n";
        std::fs::write(&path, text).unwrap();
        let still = load(&path).unwrap();
        assert_eq!(still.decals.len(), 40);
        let procedural = crate::scene::decal_textures::find_decal_materials(&still).unwrap();
        assert!(still.decals.iter().all(|d| procedural.contains(&d.material)));
        assert_eq!(still.materials.len(), 1 + procedural.len(), "the procedural materials are added once");
        assert!(still.decals[..30].iter().all(|d| (0.15 - 1e-5..=0.25 + 1e-5).contains(&d.world_from_decal.matrix3.x_axis.length())));
        assert_eq!(still.light_groups, crate::scene::Groups::default());

        std::fs::write(&path, format!("{text}[animate]\ngroups = 4\nseed = 2\n")).unwrap();
        let animated = load(&path).unwrap();
        assert_eq!(animated.light_groups.sizes, [10; 4]);
        assert_eq!(animated.decal_groups.sizes, [10; 4]);
        assert!(animated.light_groups.is_animated() && animated.decal_groups.is_animated());

        std::fs::write(&path, format!("{text}[animate]\n")).unwrap();
        let defaults = load(&path).unwrap();
        assert_eq!(defaults.light_groups.sizes.len(), generators::DEFAULT_ANIMATION_GROUPS);

        let zero =
            reason(load_text("animate_zero", "[[lights]]\ntype = 'point'\nposition = [0, 1, 0]\nintensity = 1.0\n[animate]\ngroups = 0\n"));
        assert!(zero.starts_with("animate:") && zero.contains("at least 1"), "{zero}");
        let unknown = reason(load_text("animate_unknown", "[animate]\nspeed = 2\n"));
        assert!(unknown.contains("unknown field `speed`"), "{unknown}");
        // The box's six faces are six planes: six large decals, one on each, before the scattered ones.
        std::fs::write(&path, "gltf = 'Box.gltf'\n[[large_decals]]\ncount = 8\n[[scatter_decals]]\ncount = 3\n").unwrap();
        let large = load(&path).unwrap();
        assert_eq!(large.decals.len(), 6 + 3);
        let normals: Vec<Vec3> = large.decals[..6].iter().map(|d| Vec3::from(d.world_from_decal.matrix3.z_axis).normalize()).collect();
        for axis in [Vec3::X, Vec3::Y, Vec3::Z, Vec3::NEG_X, Vec3::NEG_Y, Vec3::NEG_Z] {
            assert!(normals.iter().any(|n| n.abs_diff_eq(axis, 1e-4)), "no large decal facing {axis}: {normals:?}");
        }
        std::fs::write(&path, "gltf = 'Box.gltf'\n[particles]\ncount = 500\nemitters = 3\nradius = [0.2, 0.4]\n").unwrap();
        let particles = load(&path).unwrap().particles.unwrap();
        assert_eq!((particles.count, particles.emitters.len(), particles.radius), (500, 3, (0.2, 0.4)));
        std::fs::write(
            &path,
            "gltf = 'Box.gltf'\n[particles]\ncount = 5\nmethod = 'bvh'\nvoxel_size = 0.5\nfilter = 'tricubic'\nsamples = 4\n",
        )
        .unwrap();
        let rendering = super::load(&path).unwrap().1.particles;
        assert_eq!(rendering.method, Some(crate::settings::ParticleMethod::Bvh));
        assert_eq!(
            (rendering.voxel_size, rendering.filter, rendering.samples),
            (Some(0.5), Some(crate::settings::ParticleFilter::Tricubic), Some(4))
        );
        std::fs::write(&path, "gltf = 'Box.gltf'\n[particles]\ncount = 5\nmethod = 'magic'\n").unwrap();
        let magic = reason(load(&path));
        assert!(magic.starts_with("particles:") && magic.contains("\"grid\""), "{magic}");
        std::fs::write(&path, "gltf = 'Box.gltf'\n[particles]\ncount = 5\nvoxel_size = -2.0\n").unwrap();
        assert!(reason(load(&path)).contains("voxel_size -2"));
        std::fs::write(&path, "gltf = 'Box.gltf'\n[particles]\ncount = 5\nradius = [2.0, 1.0]\n").unwrap();
        let inverted = reason(load(&path));
        assert!(inverted.starts_with("particles:") && inverted.contains("radius"), "{inverted}");
        let many = reason(load_text("large_decals_many", "[[large_decals]]\ncount = 1000\n"));
        assert!(many.starts_with("large_decals 0:") && many.contains("exceeds the maximum"), "{many}");
        let size = reason(load_text("scatter_decals_size", "[[scatter_decals]]\ncount = 4\nsize = -1.0\n"));
        assert!(size.starts_with("scatter_decals 0:") && size.contains("size -1 m is outside 0.0001 to 100000 m"), "{size}");
        let dark = reason(load_text("light_dark_no_range", "[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = 0.0\n"));
        assert!(dark.starts_with("light 0:") && dark.contains("intensity 0") && dark.contains("give `range`"), "{dark}");
        let empty = reason(load_text("scatter_decals_empty", "[[scatter_decals]]\ncount = 4\n"));
        assert!(empty.starts_with("scatter_decals 0:") && empty.contains("no triangles"), "{empty}");
    }

    #[test]
    fn missing_files_are_io_errors() {
        let dir = temp_dir("missing");
        let missing = dir.join("nope.toml");
        assert!(matches!(load(&missing), Err(Error::Io { .. })));
        let gltf = load_text("missing_gltf", "gltf = 'nope.gltf'\n");
        assert!(matches!(&gltf, Err(Error::Io { path, .. }) if path.ends_with("nope.gltf")), "{gltf:?}");
    }
}
