//! TOML scene files: a glTF scene plus what it lacks for benchmarking (a camera, a sun, exposure,
//! explicit lights and seeded scattered lights).
//!
//! Every key is optional except where noted; unknown keys are errors. Relative paths are relative to
//! the TOML file. Angles are in degrees, directions need not be normalized.
//!
//! ```toml
//! gltf = "../shared/assets/sponza/Sponza.gltf"   # absent: an empty scene
//! exposure = 1.0                  # linear scale before tonemapping
//! ambient = [0.03, 0.03, 0.03]    # uniform ambient radiance
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
//!
//! [[scatter_lights]]      # point lights scattered over the surfaces (generators::ScatterLights)
//! count = 256             # required
//! seed = 1                # default 1
//! offset = 0.2            # distance along the surface normal; default a tenth of the mean range
//! range = [0.5, 2.0]      # uniform in [min, max]; default about 4 % of the scene's diagonal
//! intensity = [0.5, 3.0]  # uniform in [min, max]; default (range / 2)² per light
//! ```

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;

use super::generators::{self, ScatterLights};
use super::{validate_light, Camera, Light, LightKind, Scene, Sun, DEFAULT_LIGHT_CUTOFF};
use crate::{Error, Result};

/// Loads a TOML scene file and the glTF it references.
pub fn load(path: &Path) -> Result<Scene> {
    let text = std::fs::read_to_string(path).map_err(|error| Error::Io { path: path.to_owned(), error })?;
    let invalid = |reason: String| Error::SceneFile { path: path.to_owned(), reason };
    let file: SceneFile = toml::from_str(&text).map_err(|e| invalid(e.to_string().trim_end().to_owned()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut scene = match &file.gltf {
        Some(gltf) => super::gltf::import(&dir.join(gltf))?,
        None => Scene::default(),
    };
    file.apply(&mut scene).map_err(invalid)?;
    Ok(scene)
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
    camera: Option<CameraSpec>,
    sun: Option<SunSpec>,
    #[serde(default)]
    lights: Vec<LightSpec>,
    #[serde(default)]
    scatter_lights: Vec<ScatterSpec>,
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

impl SceneFile {
    /// Applies the file's settings on top of the loaded glTF; errors are reasons for `Error::SceneFile`.
    fn apply(&self, scene: &mut Scene) -> Result<(), String> {
        if let Some(exposure) = self.exposure {
            scene.exposure = exposure;
        }
        if let Some(ambient) = self.ambient {
            scene.ambient = Vec3::from(ambient);
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
        for (i, spec) in self.scatter_lights.iter().enumerate() {
            generators::add_scattered_lights(scene, &spec.to_params()).map_err(|e| format!("scatter_lights {i}: {}", inner_message(e)))?;
        }
        // Exposure, ambient and sun are checked here; the glTF part was checked on import.
        scene.validate().map_err(inner_message)
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
        let forward = (target - position).normalize_or_zero();
        // The camera's up is +Y, so it cannot look straight up or down.
        if forward.cross(Vec3::Y).length() < 1e-4 {
            return Err("target must differ from position, and not lie straight above or below it".into());
        }
        if !(yfov_degrees > 0.0 && yfov_degrees < 180.0) {
            return Err(format!("yfov_degrees {yfov_degrees} must lie strictly between 0 and 180"));
        }
        if !(near.is_finite() && near > 0.0) {
            return Err(format!("near {near} must be finite and > 0"));
        }
        Ok(Camera::look_at("scene file", position, target, yfov_degrees.to_radians(), near))
    }
}

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
        Ok(Light {
            kind,
            position: Vec3::from(self.position),
            direction,
            color,
            intensity: self.intensity,
            range: self.range.unwrap_or_else(|| Light::range_from_cutoff(self.intensity, color, DEFAULT_LIGHT_CUTOFF)),
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

    fn reason(result: Result<Scene>) -> String {
        match result {
            Err(Error::SceneFile { reason, .. }) => reason,
            other => panic!("expected a scene-file error, got {other:?}"),
        }
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
        let scene = load(&path).unwrap();
        assert_eq!(scene.drawn_triangle_count(), 12);
        assert_eq!(scene.exposure, 2.0);
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
    fn empty_file_is_an_empty_scene() {
        let scene = load_text("empty", "").unwrap();
        assert!(scene.instances.is_empty() && scene.lights.is_empty() && scene.cameras.is_empty());
        assert_eq!(scene.exposure, 1.0);
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
        assert!(reason(load_text("exposure", "exposure = 0.0\n")).contains("exposure must be finite and > 0"));
        let scatter = reason(load_text("scatter", "[[scatter_lights]]\ncount = 4\n"));
        assert!(scatter.starts_with("scatter_lights 0:") && scatter.contains("no triangles"), "{scatter}");
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
