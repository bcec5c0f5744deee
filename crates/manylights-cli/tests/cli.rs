//! The `manylights` binary end to end: it renders, and every kind of bad input ends in a clear error
//! message and a non-zero exit, never a panic.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn assets() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn manylights(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_manylights")).args(args).output().expect("run manylights")
}

/// Runs a command that must fail; returns its stderr after checking the exit code and that it did
/// not panic.
fn failure(args: &[&str]) -> String {
    let out = manylights(args);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!out.status.success(), "{args:?} succeeded; stderr: {stderr}");
    assert_ne!(out.status.code(), Some(101), "{args:?} panicked: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    stderr
}

fn render_to(dir: &Path, extra: &[&str]) -> Output {
    let out = dir.join("out.png");
    let mut args = vec!["render", "--width", "64", "--height", "36", "-o", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    manylights(&args)
}

#[test]
fn renders_the_demo_and_a_gltf_with_timings() {
    let dir = temp_dir("render_ok");
    let json = dir.join("timings.json");
    let exr = dir.join("out.exr");
    let out = render_to(&dir, &["--timings", "--timings-json", json.to_str().unwrap(), "--exr", exr.to_str().unwrap(), "--frames", "2"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    for pass in ["visbuffer_raster", "visbuffer_shade", "tonemap"] {
        assert!(stdout.contains(pass), "--timings output lacks {pass}: {stdout}");
    }
    let png = image::open(dir.join("out.png")).unwrap();
    assert_eq!((png.width(), png.height()), (64, 36));
    assert!(image::open(&exr).is_ok(), "EXR not readable");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["timed_frames"], 2);
    assert!(report["passes"]["visbuffer_shade"]["median_ms"].as_f64().unwrap() > 0.0);
    assert_eq!(report["passes"]["visbuffer_shade"]["samples_ms"].as_array().unwrap().len(), 2);

    let duck = assets().join("duck/Duck.glb");
    let out = render_to(&dir, &["--scene", duck.to_str().unwrap(), "--lights", "16", "--seed", "3"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

/// With no flags, auto methods run and say why in --timings and the JSON, and the exposure is
/// metered; --exposure fixes it, within its range, and not together with --auto-exposure.
#[test]
fn auto_methods_and_exposure_are_the_defaults_and_say_so() {
    let dir = temp_dir("auto_defaults");
    let json = dir.join("timings.json");
    let out = render_to(&dir, &["--lights", "64", "--decals", "4", "--timings", "--timings-json", json.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    // Four decals, one placed group: read from cell lists by the software walk, else looped over.
    let few_decals = if stdout.contains("ray backend: software") { "bvh" } else { "brute" };
    assert!(stdout.contains("lights: bvh (auto: ") && stdout.contains(&format!("decals: {few_decals} (auto: 4")), "{stdout}");
    assert!(stdout.contains("exposure_histogram"), "auto exposure's passes: {stdout}");
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!((report["light_method"].as_str(), report["decal_method"].as_str()), (Some("bvh"), Some(few_decals)));
    assert!(report["light_method_why"].as_str().unwrap().contains("reaching"), "{report}");
    assert!(report["post"]["exposure"]["auto"].is_object(), "{report}");
    let fixed = render_to(&dir, &["--exposure", "2", "--timings", "--light-method", "clustered"]);
    let stdout = String::from_utf8_lossy(&fixed.stdout);
    assert!(fixed.status.success() && !stdout.contains("exposure_histogram") && stdout.contains("clustered (asked for)"), "{stdout}");
    // Candidates asked through the light tree take the BVH it lives in, however few the lights.
    let boxed = assets().join("box/Box.gltf");
    #[rustfmt::skip]
    let tree = render_to(&dir, &[
        "--scene", boxed.to_str().unwrap(), "--lights", "3", "--direct-lighting", "restir", "--restir-candidates", "tree", "--timings",
    ]);
    let stdout = String::from_utf8_lossy(&tree.stdout);
    assert!(tree.status.success(), "{}", String::from_utf8_lossy(&tree.stderr));
    assert!(stdout.contains("lights: bvh (auto: restir's candidates are drawn through the light tree"), "{stdout}");
    let range = failure(&["render", "--exposure", "99", "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(range.contains("--exposure 99") && range.contains("EV100"), "{range}");
    let both = failure(&["render", "--exposure", "1", "--auto-exposure", "-o", dir.join("x.png").to_str().unwrap()]);
    assert!(both.contains("--auto-exposure") && both.contains("--exposure"), "{both}");
}

#[test]
fn missing_file() {
    let err = failure(&["render", "--scene", "/nonexistent/scene.gltf"]);
    assert!(err.contains("/nonexistent/scene.gltf") && err.contains("cannot read"), "{err}");
}

#[test]
fn unknown_scene_type() {
    let dir = temp_dir("unknown_type");
    let path = dir.join("scene.obj");
    std::fs::write(&path, "v 0 0 0").unwrap();
    let err = failure(&["render", "--scene", path.to_str().unwrap()]);
    assert!(err.contains(".gltf, .glb or .toml"), "{err}");
}

#[test]
fn truncated_gltf() {
    let dir = temp_dir("truncated");
    let bytes = std::fs::read(assets().join("box/Box.glb")).unwrap();
    let path = dir.join("Box.glb");
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let err = failure(&["render", "--scene", path.to_str().unwrap()]);
    assert!(err.contains("not a valid glTF"), "{err}");
}

#[test]
fn required_unsupported_extension() {
    let dir = temp_dir("extension");
    let path = dir.join("required.gltf");
    std::fs::write(
        &path,
        r#"{"asset":{"version":"2.0"},"extensionsUsed":["KHR_materials_diffuse_transmission"],"extensionsRequired":["KHR_materials_diffuse_transmission"],"scenes":[{"nodes":[]}],"scene":0}"#,
    )
    .unwrap();
    let err = failure(&["render", "--scene", path.to_str().unwrap()]);
    assert!(err.contains("KHR_materials_diffuse_transmission") && err.contains("does not support"), "{err}");
}

#[test]
fn zero_resolution() {
    let err = failure(&["render", "--width", "0", "--height", "36"]);
    assert!(err.contains("at least 1"), "{err}");
}

#[test]
fn oversized_resolution() {
    let err = failure(&["render", "--width", "1000000", "--height", "36"]);
    assert!(err.contains("over this GPU's limit"), "{err}");
}

#[test]
fn nan_in_a_scene_file_light() {
    let dir = temp_dir("nan_light");
    let path = dir.join("scene.toml");
    std::fs::write(
        &path,
        "[[lights]]\ntype = \"point\"\nposition = [nan, 1.0, 0.0]\ncolor = [1.0, 1.0, 1.0]\nintensity = 5.0\nrange = 3.0\n",
    )
    .unwrap();
    let err = failure(&["render", "--scene", path.to_str().unwrap()]);
    assert!(err.contains("scene.toml") && err.contains("light 0") && err.contains("NaN"), "{err}");
}

#[test]
fn bad_particle_options() {
    let zero = failure(&["render", "--particles", "100", "--particle-voxel-size", "0", "--width", "16", "--height", "16"]);
    assert!(zero.contains("particle voxel size 0") && zero.contains("> 0"), "{zero}");
    let negative = failure(&["render", "--particles", "100", "--particle-voxel-size", "-1", "--width", "16", "--height", "16"]);
    assert!(negative.contains("particle voxel size -1"), "{negative}");
    let tiny = failure(&["render", "--particles", "100", "--particle-voxel-size", "0.001", "--width", "16", "--height", "16"]);
    assert!(tiny.contains("3D texture limit") && tiny.contains("larger voxels"), "{tiny}");
    let samples = failure(&["render", "--particles", "100", "--particle-samples", "0", "--width", "16", "--height", "16"]);
    assert!(samples.contains("particle samples") && samples.contains("1 to 64"), "{samples}");
    let emitters = failure(&["render", "--particles", "100", "--particle-emitters", "0", "--width", "16", "--height", "16"]);
    assert!(emitters.contains("emitters") && emitters.contains("1 to"), "{emitters}");
    let cascades = failure(&["render", "--particles", "100", "--particle-cascades", "9", "--width", "16", "--height", "16"]);
    assert!(cascades.contains("9 particle cascades") && cascades.contains("give 1 to 8"), "{cascades}");
    let odd = failure(&["render", "--particles", "100", "--particle-cascades", "2", "--particle-cascade-resolution", "33"]);
    assert!(odd.contains("resolution 33") && odd.contains("even"), "{odd}");
    // Given without cascades it is still a mistake, not ignored.
    let unused = failure(&["render", "--particles", "100", "--particle-cascade-resolution", "33", "--width", "16", "--height", "16"]);
    assert!(unused.contains("resolution 33"), "{unused}");
    let listed = failure(&["particle-error", "--particles", "10", "--voxel-sizes", "1,-1", "--width", "16", "--height", "16"]);
    assert!(listed.contains("particle voxel size -1") && !listed.contains("PSNR"), "checked before the first frame: {listed}");
}

/// A scene file's particle rendering choices apply unless a flag overrides them.
#[test]
fn scene_file_particle_settings_yield_to_flags() {
    let dir = temp_dir("particle_scene");
    let scene = dir.join("particles.toml");
    let gltf = assets().join("box/Box.gltf");
    std::fs::write(&scene, format!("gltf = {:?}\n[particles]\ncount = 200\nmethod = 'bvh'\n", gltf.to_str().unwrap())).unwrap();
    let scene = scene.to_str().unwrap();
    // bvh particles need bvh lights: the scene's choice applied, refused with brute lights asked for.
    let err = failure(&["render", "--scene", scene, "--width", "16", "--height", "16", "--light-method", "brute"]);
    assert!(err.contains("--particle-method bvh") && err.contains("--light-method bvh"), "{err}");
    let out = dir.join("out.png");
    // `auto` (the default) picks bvh for them.
    for extra in [["--light-method", "auto"], ["--light-method", "bvh"], ["--particle-method", "grid"]] {
        let mut args = vec!["render", "--scene", scene, "--width", "16", "--height", "16", "-o", out.to_str().unwrap()];
        args.extend(extra);
        let run = manylights(&args);
        assert!(run.status.success(), "{extra:?}: {}", String::from_utf8_lossy(&run.stderr));
    }
    // Particles from the command line would silently replace the file's: an error instead.
    let twice = failure(&["render", "--scene", scene, "--particles", "50", "--width", "16", "--height", "16"]);
    assert!(twice.contains("already has [particles]") && twice.contains("200 particles"), "{twice}");
    // The timings JSON says how the particles were rendered.
    let json = dir.join("timings.json");
    #[rustfmt::skip]
    let run = manylights(&[
        "render", "--scene", scene, "--particle-method", "grid", "--particle-cascades", "2", "--particle-cascade-resolution", "24",
        "--width", "16", "--height", "16", "-o", out.to_str().unwrap(), "--timings-json", json.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let particles = &json["particles"];
    assert_eq!((particles["count"].as_u64(), particles["method"].as_str()), (Some(200), Some("grid")), "{json}");
    assert_eq!((particles["cascades"].as_u64(), particles["cascade_resolution"].as_u64()), (Some(2), Some(24)), "{json}");
}

/// Extensions a glTF only uses are named in one warning each when the importer ignores them, and
/// not at all when it honours them.
#[test]
fn ignored_gltf_extensions_are_named_once_each() {
    let dir = temp_dir("gltf_extensions_used");
    std::fs::copy(assets().join("box/Box0.bin"), dir.join("Box0.bin")).unwrap();
    let json = std::fs::read_to_string(assets().join("box/Box.gltf")).unwrap().replacen(
        '{',
        r#"{"extensionsUsed": ["KHR_lights_punctual", "KHR_materials_iridescence", "KHR_materials_anisotropy"], "#,
        1,
    );
    let scene = dir.join("Box.gltf");
    std::fs::write(&scene, json).unwrap();
    let out = render_to(&dir, &["--scene", scene.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    for ignored in ["KHR_materials_iridescence", "KHR_materials_anisotropy"] {
        let lines = stderr.lines().filter(|l| l.contains(ignored) && l.contains("not supported")).count();
        assert_eq!(lines, 1, "{ignored}: {stderr}");
    }
    assert!(!stderr.lines().any(|l| l.contains("KHR_lights_punctual is not supported")), "{stderr}");
}

#[test]
fn particle_error_compares_grid_settings_with_the_exact_method() {
    #[rustfmt::skip]
    let out = manylights(&[
        "particle-error", "--particles", "2000", "--width", "48", "--height", "27",
        "--voxel-sizes", "1,0.5", "--filters", "trilinear", "--samples", "1", "--cascades", "0,2", "--cascade-resolution", "32",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // One row per setting: cascades, voxel, filter, samples, error %, PSNR dB.
    let rows: Vec<Vec<&str>> =
        stdout.lines().map(|l| l.split_whitespace().collect::<Vec<_>>()).filter(|f| f.len() == 6 && f[2] == "trilinear").collect();
    assert_eq!(rows.len(), 4, "{stdout}");
    for row in rows {
        let error: f64 = row[4].parse().unwrap();
        let psnr: f64 = row[5].parse().unwrap();
        assert!(error.is_finite() && error > 0.0 && psnr.is_finite() && psnr > 0.0, "{row:?}");
    }
    let none = failure(&["particle-error", "--width", "16", "--height", "16"]);
    assert!(none.contains("no particles") && none.contains("--particles"), "{none}");
    // Shadowed: restir through the particles' light tree, sampled and denoised, against the reference.
    #[rustfmt::skip]
    let out = manylights(&[
        "particle-error", "--particles", "2000", "--width", "48", "--height", "27", "--voxel-sizes", "1", "--filters", "trilinear",
        "--samples", "1", "--restir-frames", "3", "--restir-candidates", "tree",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // restir, candidates, error %, PSNR dB.
    let rows: Vec<Vec<&str>> =
        stdout.lines().map(|l| l.split_whitespace().collect::<Vec<_>>()).filter(|f| f.len() == 4 && f[1] == "tree").collect();
    assert_eq!(rows.iter().map(|r| r[0]).collect::<Vec<_>>(), ["sampled", "denoised"], "{stdout}");
    for row in rows {
        let (error, psnr): (f64, f64) = (row[2].parse().unwrap(), row[3].parse().unwrap());
        assert!(error.is_finite() && error > 0.0 && psnr.is_finite() && psnr > 0.0, "{row:?}");
    }
    let early =
        failure(&["particle-error", "--particles", "10", "--restir-frames", "64", "--time", "0.5", "--width", "16", "--height", "16"]);
    assert!(early.contains("--restir-frames 64") && early.contains("before time 0"), "{early}");
    let many = failure(&["particle-error", "--particles", "10", "--restir-frames", "200000", "--width", "16", "--height", "16"]);
    assert!(many.contains("--restir-frames 200000") && many.contains("at most"), "{many}");
}

#[test]
fn light_error_compares_restir_with_the_reference_over_a_still_and_a_moving_camera() {
    let dir = temp_dir("light_error");
    let json = dir.join("light-error.json");
    #[rustfmt::skip]
    let out = manylights(&[
        "light-error", "--lights", "64", "--width", "64", "--height", "36", "--frames", "3", "--path-length", "0.5",
        "--restir-reuse", "spatiotemporal", "--json", json.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!((report["restir_reuse"].as_str(), report["path_length_m"].as_f64()), (Some("spatiotemporal"), Some(0.5)));
    for path in ["still", "moving"] {
        for restir in ["sampled", "denoised"] {
            let frames =
                report["paths"][path][restir]["frames"].as_array().unwrap_or_else(|| panic!("no {path} {restir} frames: {report}"));
            assert_eq!(frames.len(), 3, "{path} {restir}");
            for (i, frame) in frames.iter().enumerate() {
                let flip = frame["flip"].as_f64().unwrap();
                // Sampled shadows of 64 lights differ from the reference somewhere, and far from everywhere.
                assert!(flip > 0.0 && flip < 0.5, "{path} {restir} frame {i}: FLIP {flip}");
                let (relative_mse, psnr) = (frame["relative_mse"].as_f64().unwrap(), frame["psnr"].as_f64().unwrap());
                assert!(relative_mse > 0.0 && psnr > 10.0, "{path} {restir} frame {i}: {frame}");
                // Flicker compares a still camera's frame with the one before.
                assert_eq!(frame["flicker"].is_f64(), path == "still" && i > 0, "{path} {restir} frame {i}: {frame}");
            }
        }
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.lines().filter(|l| l.contains("mean")).count() == 4, "{stdout}");
    let frames = failure(&["light-error", "--frames", "0"]);
    assert!(frames.contains("--frames 0") && frames.contains("1 to 1024"), "{frames}");
    let length = failure(&["light-error", "--path-length", "-1"]);
    assert!(length.contains("--path-length -1"), "{length}");
    let boxed = assets().join("box/Box.gltf");
    let unlit = failure(&["light-error", "--scene", boxed.to_str().unwrap(), "--width", "16", "--height", "16"]);
    assert!(unlit.contains("no local lights") && unlit.contains("--lights"), "{unlit}");
}

#[test]
fn huge_frame_counts_are_refused_not_allocated() {
    let err = failure(&["render", "--frames", "4294967295", "--width", "64", "--height", "36"]);
    assert!(err.contains("--frames must be between 1 and"), "{err}");
}

#[test]
fn negative_numbers_name_their_flag_and_outputs_need_files_of_their_own() {
    let err = failure(&["render", "--lights", "-1"]);
    assert!(err.contains("invalid value '-1' for '--lights"), "{err}");
    let dir = temp_dir("same_outputs");
    let same = dir.join("same.png");
    let link = dir.join("same.exr");
    let _ = std::fs::remove_file(&link);
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&same, &link).unwrap();
        let err = failure(&["render", "-o", same.to_str().unwrap(), "--exr", link.to_str().unwrap()]);
        assert!(err.contains("-o and --exr name the same file"), "{err}");
    }
    let err = failure(&["bench", "--scenes", "none,small-decals", "--sweeps", "none"]);
    assert!(err.contains("--scenes: `none`") && err.contains("alone"), "{err}");
}

#[test]
fn camera_out_of_range() {
    let err = failure(&["render", "--camera", "7", "--width", "64", "--height", "36"]);
    assert!(err.contains("--camera 7"), "{err}");
}

#[test]
fn renders_animated_decals_through_the_bvh() {
    let dir = temp_dir("render_decals");
    let json = dir.join("timings.json");
    let out = render_to(&dir, &["--decals", "50", "--decal-method", "bvh", "--animate", "--timings-json", json.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let png = image::open(dir.join("out.png")).unwrap();
    assert_eq!((png.width(), png.height()), (64, 36));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(
        (report["decals"].as_u64(), report["decal_method"].as_str(), report["animated"].as_bool()),
        (Some(50), Some("bvh"), Some(true))
    );
}

#[test]
fn bad_decal_sizes_are_refused() {
    for (size, shown) in [
        ("-1", "-1"),
        ("nan", "NaN"),
        ("0", "0"),
        ("inf", "inf"),
        ("1e-30", "0.000000000000000000000000000001"),
        ("1e30", "1000000000000000000000000000000"),
    ] {
        let err = failure(&["render", "--width", "64", "--height", "36", "--decals", "4", "--decal-size", size]);
        assert!(err.contains(&format!("--decal-size {shown}:")) && err.contains("from 0.0001 to 100000"), "{size}: {err}");
    }
    let err = failure(&["render", "--decal-size", "1"]);
    assert!(err.contains("--decals"), "--decal-size without --decals: {err}");
}

#[test]
fn bad_animation_groups_are_refused() {
    let err = failure(&["render", "--width", "64", "--height", "36", "--animate", "--groups", "0"]);
    assert!(err.contains("--groups 0") && err.contains("at least 1"), "{err}");
    let err = failure(&["render", "--groups", "4"]);
    assert!(err.contains("--animate"), "--groups without --animate: {err}");

    let dir = temp_dir("animate_twice");
    let path = dir.join("scene.toml");
    std::fs::write(&path, format!("gltf = '{}'\n[[scatter_lights]]\ncount = 8\n[animate]\n", assets().join("box/Box.glb").display()))
        .unwrap();
    let err = failure(&["render", "--width", "64", "--height", "36", "--scene", path.to_str().unwrap(), "--animate"]);
    assert!(err.contains("grouped already") && err.contains("--animate"), "{err}");
    let err = failure(&["render", "--width", "64", "--height", "36", "--scene", path.to_str().unwrap(), "--lights", "4"]);
    assert!(err.contains("lights are grouped") && err.contains("--animate"), "{err}");
}

#[test]
fn decals_need_surfaces() {
    let dir = temp_dir("decals_without_surfaces");
    let path = dir.join("lamp.toml");
    std::fs::write(&path, "[[lights]]\ntype = 'point'\nposition = [0, 1, 0]\nintensity = 1.0\n").unwrap();
    let err = failure(&["render", "--width", "64", "--height", "36", "--scene", path.to_str().unwrap(), "--decals", "5"]);
    assert!(err.contains("cannot scatter 5 decals") && err.contains("no triangles"), "{err}");
}

#[test]
fn bad_decals_in_a_scene_file_name_the_image() {
    let dir = temp_dir("decal_image");
    let path = dir.join("scene.toml");
    std::fs::write(&path, "[[decals]]\nposition = [0, 0, 0]\nnormal = [0, 1, 0]\nsize = [1, 1, 1]\nalbedo = 'missing.png'\n").unwrap();
    let err = failure(&["render", "--width", "64", "--height", "36", "--scene", path.to_str().unwrap()]);
    assert!(err.contains("scene.toml") && err.contains("decal 0: albedo image") && err.contains("missing.png"), "{err}");
}

#[test]
fn no_matching_adapter_explains_how_to_install_a_driver() {
    let out = Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(["render", "--width", "64", "--height", "36"])
        .env("WGPU_ADAPTER_NAME", "no-such-gpu-anywhere")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("no usable GPU adapter") && err.contains("mesa-vulkan-drivers"), "{err}");
}

#[test]
fn info_lists_the_chosen_adapter() {
    let out = manylights(&["info"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("chosen:") && stdout.contains("features used"), "{stdout}");
    // Mesa 25's lavapipe emulates ray queries on the CPU, slower than the software BVHs: `auto`
    // leaves them to those who ask.
    assert!(stdout.contains("[usable, ray queries]"), "lavapipe 25 has ray queries: {stdout}");
    assert!(stdout.contains("ray backend: auto picks software (this CPU adapter emulates ray queries"), "{stdout}");
}

#[test]
fn info_counts_decals_and_groups() {
    let out = manylights(&["info", "--decals", "10", "--animate", "--groups", "3"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("scene demo:"), "{stdout}");
    assert!(stdout.contains("decals: 10 in 3 group(s), 3 instance(s), animated"), "{stdout}");
    assert!(stdout.contains("lights: 7 in 3 group(s), 3 instance(s), animated"), "{stdout}");
    // The overlap statistics, through the groups' instances.
    assert!(
        stdout.contains("lights reaching a surface point: mean") && stdout.contains("decals reaching a surface point: mean"),
        "{stdout}"
    );
}

#[test]
fn every_pipeline_renders_with_its_passes_timed() {
    let dir = temp_dir("render_pipelines");
    let json = dir.join("timings.json");
    for (pipeline, passes) in [
        ("visbuffer", ["visbuffer_raster", "visbuffer_shade"]),
        ("deferred", ["gbuffer_raster", "deferred_shade"]),
        ("forward", ["depth_prepass", "forward_shade"]),
    ] {
        let out = render_to(&dir, &["--pipeline", pipeline, "--lights", "20", "--decals", "20", "--timings-json", json.to_str().unwrap()]);
        assert!(out.status.success(), "{pipeline}: {}", String::from_utf8_lossy(&out.stderr));
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        assert_eq!(report["pipeline"].as_str(), Some(pipeline));
        for pass in passes {
            assert!(report["passes"][pass]["median_ms"].as_f64().unwrap() > 0.0, "{pipeline}: no {pass} timing");
        }
    }
    let err = failure(&["render", "--pipeline", "tiled"]);
    assert!(err.contains("--pipeline") && err.contains("visbuffer") && err.contains("deferred") && err.contains("forward"), "{err}");
}

#[test]
fn every_method_renders_with_its_builds_timed() {
    let dir = temp_dir("render_methods");
    let json = dir.join("timings.json");
    let cases: [(&[&str], &[&str]); 4] = [
        (&["--light-method", "clustered", "--decal-method", "clustered"], &["light_cluster_build", "decal_cluster_build"]),
        (&["--light-method", "off", "--decal-method", "off"], &["visbuffer_shade"]),
        (&["--pipeline", "deferred", "--decal-method", "deferred-decals"], &["deferred_decals", "deferred_shade"]),
        (&["--pipeline", "forward", "--light-method", "clustered"], &["light_cluster_build", "forward_shade"]),
    ];
    for (flags, passes) in cases {
        let mut args = vec!["--lights", "20", "--decals", "20", "--timings-json", json.to_str().unwrap()];
        args.extend_from_slice(flags);
        let out = render_to(&dir, &args);
        assert!(out.status.success(), "{flags:?}: {}", String::from_utf8_lossy(&out.stderr));
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        for pass in passes {
            assert!(report["passes"][pass]["median_ms"].as_f64().unwrap() > 0.0, "{flags:?}: no {pass} timing");
        }
    }
    for pipeline in ["visbuffer", "forward"] {
        let err = failure(&["render", "--width", "32", "--height", "18", "--pipeline", pipeline, "--decal-method", "deferred-decals"]);
        assert!(err.contains("deferred decals") && err.contains("--pipeline deferred"), "{err}");
    }
}

#[test]
fn ray_traced_effects_render_with_their_passes_timed() {
    let dir = temp_dir("render_rays");
    let json = dir.join("timings.json");
    for pipeline in ["visbuffer", "deferred", "forward"] {
        #[rustfmt::skip]
        let out = render_to(&dir, &[
            "--pipeline", pipeline, "--shadows", "soft", "--shadow-rays", "2", "--reflections", "--bounces", "2",
            "--reflection-roughness", "0.6", "--light-shadow-rays", "2", "--timings-json", json.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{pipeline}: {}", String::from_utf8_lossy(&out.stderr));
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        for pass in ["ray_shadows", "shadow_filter"] {
            assert!(report["passes"][pass]["median_ms"].as_f64().unwrap() > 0.0, "{pipeline}: no {pass} timing");
        }
        let rays = &report["rays"];
        assert_eq!(
            (rays["shadows"].as_str(), rays["shadow_rays"].as_u64(), rays["reflection_bounces"].as_u64()),
            (Some("soft"), Some(2), Some(2))
        );
        assert_eq!(rays["light_shadow_rays"].as_u64(), Some(2));
    }
    // Shadowed local lights, sampled: the ray hierarchy is built for them alone.
    let out = render_to(&dir, &["--direct-lighting", "restir", "--restir-shadow-rays", "2", "--timings-json", json.to_str().unwrap()]);
    assert!(out.status.success(), "restir: {}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rays = &report["rays"];
    assert_eq!((rays["direct_lighting"].as_str(), rays["restir_shadow_rays"].as_u64()), (Some("restir"), Some(2)));
    assert!(rays["hierarchy"]["triangles"].as_u64().unwrap() > 0, "restir traces rays: {rays}");
}

#[test]
fn bad_ray_options_are_refused() {
    let small = ["--width", "16", "--height", "16"];
    let run = |flags: &[&str]| failure(&[&["render"], flags, &small].concat());
    let rays = run(&["--shadows", "soft", "--shadow-rays", "0"]);
    assert!(rays.contains("0 shadow rays") && rays.contains("1 to 64") && rays.contains("--shadow-rays"), "{rays}");
    let angle = run(&["--shadows", "soft", "--sun-angle", "-1"]);
    assert!(angle.contains("sun angle -1") && angle.contains("--sun-angle"), "{angle}");
    let nan = run(&["--sun-angle", "NaN"]);
    assert!(nan.contains("sun angle NaN"), "{nan}");
    let bounces = run(&["--reflections", "--bounces", "9"]);
    assert!(bounces.contains("9 reflection bounces") && bounces.contains("--bounces"), "{bounces}");
    let none = run(&["--reflections", "--bounces", "0"]);
    assert!(none.contains("--bounces 0") && none.contains("leave out --reflections"), "{none}");
    let without = run(&["--bounces", "2"]);
    assert!(without.contains("--reflections"), "{without}");
    let roughness = run(&["--reflections", "--reflection-roughness", "0"]);
    assert!(roughness.contains("roughness threshold 0") && roughness.contains("--reflection-roughness"), "{roughness}");
    let lamps = run(&["--light-shadow-rays", "65"]);
    assert!(lamps.contains("65 shadow rays per point towards lights") && lamps.contains("--light-shadow-rays"), "{lamps}");
    let samples = run(&["--direct-lighting", "restir", "--restir-shadow-rays", "5"]);
    assert!(
        samples.contains("5 restir shadow rays") && samples.contains("1 to 4") && samples.contains("--restir-shadow-rays"),
        "{samples}"
    );
    let lighting = run(&["--direct-lighting", "stochastic"]);
    assert!(lighting.contains("--direct-lighting") && lighting.contains("reference") && lighting.contains("restir"), "{lighting}");
    let mode = run(&["--shadows", "ambient"]);
    assert!(mode.contains("--shadows") && mode.contains("hard") && mode.contains("soft"), "{mode}");
}

#[test]
fn post_effects_render_with_their_passes_timed_and_bad_ones_name_their_flag() {
    let dir = temp_dir("render_post");
    let json = dir.join("timings.json");
    #[rustfmt::skip]
    let out = render_to(&dir, &[
        "--auto-exposure", "--exposure-compensation", "0.5", "--bloom", "--bloom-intensity", "0.2", "--depth-of-field",
        "--f-number", "1.4", "--motion-blur", "--shutter", "1", "--camera-velocity", "5,0,0", "--frames", "2",
        "--vignette", "0.5", "--timings-json", json.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    #[rustfmt::skip]
    let passes = [
        "depth_of_field_tiles", "depth_of_field", "velocity", "motion_blur_tiles", "motion_blur", "exposure_histogram",
        "exposure_average", "bloom", "tonemap",
    ];
    for pass in passes {
        assert!(report["passes"][pass]["median_ms"].as_f64().unwrap() > 0.0, "no {pass} timing");
    }
    let post = &report["post"];
    assert_eq!(post["bloom"]["intensity"].as_f64(), Some(0.2f32 as f64));
    assert_eq!(post["motion_blur"]["shutter"].as_f64(), Some(1.0));
    assert_eq!(post["camera_velocity"][0].as_f64(), Some(5.0));

    let small = ["--width", "16", "--height", "16"];
    let run = |flags: &[&str]| failure(&[&["render"], flags, &small].concat());
    let vignette = run(&["--vignette", "2"]);
    assert!(vignette.contains("vignette strength 2") && vignette.contains("--vignette"), "{vignette}");
    let without = run(&["--bloom-intensity", "0.5"]);
    assert!(without.contains("--bloom"), "{without}");
    let samples = run(&["--motion-blur", "--motion-blur-samples", "0"]);
    assert!(samples.contains("0 motion blur samples") && samples.contains("--motion-blur-samples"), "{samples}");
    let focus = run(&["--depth-of-field", "--focus-distance", "-2"]);
    assert!(focus.contains("focus distance -2") && focus.contains("--focus-distance"), "{focus}");
    let velocity = run(&["--camera-velocity", "1,2"]);
    assert!(velocity.contains("three numbers"), "{velocity}");
}

/// The viewer under Xvfb (`scripts/ensure-xvfb.sh` installs it): a scripted run opens the window,
/// renders frames, switches the light method, the scattered lights' count (the scene generated
/// again) and the pipeline between them, writes a screenshot of the last frame that is not blank,
/// and exits 0.
#[test]
fn the_viewer_runs_a_scripted_session_under_xvfb_and_writes_a_screenshot() {
    let dir = temp_dir("view");
    let screenshot = dir.join("view.png");
    let _ = std::fs::remove_file(&screenshot);
    #[rustfmt::skip]
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 800x600x24", env!("CARGO_BIN_EXE_manylights"), "view", "--width", "560", "--height", "240",
               "--frames", "6", "--set", "2:light-method=clustered", "--set", "3:lights=40", "--set", "4:pipeline=deferred",
               "--set", "4:bloom=on",
               "--screenshot", screenshot.to_str().unwrap()])
        .output()
        .expect("xvfb-run (install Xvfb: scripts/ensure-xvfb.sh)");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "the viewer failed: {stderr}");
    let image = image::open(&screenshot).expect("the screenshot").into_rgba8();
    // The image beside the panel: the window's width less the panel's 270 points.
    assert_eq!((image.width(), image.height()), (290, 240));
    let distinct: std::collections::HashSet<[u8; 4]> = image.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 500, "the screenshot looks blank: {} distinct colours", distinct.len());
}

/// The viewer starts from a scene file's `[methods]` and `[particles]`: brute-force lights asked for
/// there cannot light its particles as exact lights, and it says so.
#[test]
fn the_viewer_takes_a_scene_files_methods_and_particles() {
    let dir = temp_dir("view_scene_file");
    let scene = dir.join("scene.toml");
    let gltf = assets().join("box/Box.gltf");
    std::fs::write(
        &scene,
        format!("gltf = {:?}\n[methods]\nlights = 'brute'\n[particles]\ncount = 50\nmethod = 'bvh'\n", gltf.to_str().unwrap()),
    )
    .unwrap();
    #[rustfmt::skip]
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 800x600x24", env!("CARGO_BIN_EXE_manylights"), "view", "--width", "320", "--height", "180",
               "--frames", "2", "--scene", scene.to_str().unwrap()])
        .output()
        .expect("xvfb-run (install Xvfb: scripts/ensure-xvfb.sh)");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && out.status.code() != Some(101), "{stderr}");
    assert!(stderr.contains("--light-method brute") && stderr.contains("--particle-method bvh"), "{stderr}");
}

#[test]
fn the_viewer_without_a_display_says_how_to_get_one() {
    let out = Command::new(env!("CARGO_BIN_EXE_manylights"))
        .args(["view", "--frames", "1"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && out.status.code() != Some(101), "{stderr}");
    assert!(stderr.contains("DISPLAY") && stderr.contains("xvfb-run"), "{stderr}");
    let bad = failure(&["view", "--set", "3:light-method=magic"]);
    assert!(bad.contains("light-method=magic") && bad.contains("clustered"), "{bad}");
    // Checked before a window opens, display or not.
    for (args, words) in [
        (&["view", "--width", "0"][..], &["window 0×720", "--width"][..]),
        (&["view", "--width", "100000", "--height", "100000"], &["window 100000×100000", "32767"]),
        (&["view", "--frames", "0"], &["--frames 0", "at least 1"]),
        (&["view", "--frames", "2", "--set", "10:bloom=on"], &["--set 10:bloom=on", "0 to 1"]),
    ] {
        let err = failure(args);
        assert!(words.iter().all(|w| err.contains(w)), "{args:?}: {err}");
    }
}

/// A scripted switch the renderer refuses (deferred decals outside the deferred pipeline) ends the
/// run with its reason, where the panel would only show it; so does a window the GPU cannot draw.
#[test]
fn the_viewer_ends_a_scripted_run_whose_switch_is_refused() {
    #[rustfmt::skip]
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 800x600x24", env!("CARGO_BIN_EXE_manylights"), "view", "--width", "400", "--height", "200",
               "--frames", "3", "--set", "1:decal-method=deferred-decals"])
        .output()
        .expect("xvfb-run (install Xvfb: scripts/ensure-xvfb.sh)");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && out.status.code() != Some(101) && !stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("frame 1: a --set switch was refused") && stderr.contains("--pipeline deferred"), "{stderr}");
    // A window over the GPU's surface limit (lavapipe's 16384) is refused once the GPU is known.
    #[rustfmt::skip]
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 800x600x24", env!("CARGO_BIN_EXE_manylights"), "view", "--width", "20000", "--height", "200",
               "--frames", "2"])
        .output()
        .expect("xvfb-run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && out.status.code() != Some(101) && !stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("over this GPU's surface limit"), "{stderr}");
}

/// A scene file's ray-traced effects apply unless flags override them; bad values name the key.
#[test]
fn scene_file_ray_settings_yield_to_flags_and_bad_ones_name_their_key() {
    let dir = temp_dir("ray_scene");
    let scene = dir.join("rays.toml");
    let write = |rays: &str| {
        let lamp = "[[lights]]\ntype = 'point'\nposition = [0, 1, 0]\nintensity = 1.0\n";
        std::fs::write(&scene, format!("{lamp}[sun]\ndirection = [0.3, -1.0, 0.2]\nilluminance = 2.0\n[rays]\n{rays}")).unwrap()
    };
    let json = dir.join("timings.json");
    let render = |extra: &[&str]| {
        let mut args = vec!["--scene", scene.to_str().unwrap(), "--timings-json", json.to_str().unwrap()];
        args.extend_from_slice(extra);
        let out = render_to(&dir, &args);
        assert!(out.status.success(), "{extra:?}: {}", String::from_utf8_lossy(&out.stderr));
        let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        report["rays"].clone()
    };
    write("shadows = 'soft'\nshadow_rays = 3\nreflections = 2\n");
    let rays = render(&[]);
    assert_eq!(
        (rays["shadows"].as_str(), rays["shadow_rays"].as_u64(), rays["reflection_bounces"].as_u64()),
        (Some("soft"), Some(3), Some(2))
    );
    let rays = render(&["--shadows", "hard", "--reflections", "--bounces", "1"]);
    assert_eq!((rays["shadows"].as_str(), rays["reflection_bounces"].as_u64()), (Some("hard"), Some(1)));
    // The ray backend: the scene file's, unless the flag says otherwise; `auto` by default.
    write("backend = 'software'\n");
    assert_eq!(render(&["--light-method", "bvh"])["backend"].as_str(), Some("software"));
    // Mesa 25's lavapipe, which the tests run on, has ray queries.
    assert_eq!(render(&["--light-method", "bvh", "--ray-backend", "hardware"])["backend"].as_str(), Some("hardware"));
    for (bad, words) in [
        ("shadow_rays = 65\n", ["rays", "65 shadow rays", "shadow_rays"]),
        ("reflections = 10\n", ["rays", "10 reflection bounces", "reflections"]),
        ("shadows = 'blurry'\n", ["rays", "blurry", "\"soft\""]),
        ("sun_angle = 120.0\n", ["rays", "sun angle 120", "sun_angle"]),
        ("light_shadow_rays = 100\n", ["rays", "100 shadow rays per point", "light_shadow_rays"]),
        ("restir_shadow_rays = 0\n", ["rays", "0 restir shadow rays", "restir_shadow_rays"]),
        ("direct_lighting = 'sampled'\n", ["rays", "sampled", "\"restir\""]),
        ("backend = 'rtx'\n", ["rays", "rtx", "\"hardware\""]),
    ] {
        write(bad);
        let err = failure(&["render", "--scene", scene.to_str().unwrap(), "--width", "16", "--height", "16"]);
        for word in words {
            assert!(err.contains(word), "{bad}: {err}");
        }
        assert!(!err.contains("--"), "{bad}: a scene file's error names its key, not a flag: {err}");
    }
}

/// A failure that prints exactly one `error:` line (and maybe warnings) and exits 1.
fn one_error_line(args: &[&str]) -> String {
    let out = manylights(args);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{args:?}: {stderr}");
    assert!(stderr.lines().all(|l| l.starts_with("error:") || l.contains("WARN")), "{args:?}: {stderr}");
    errors[0].to_owned()
}

/// Box.gltf beside its buffer and a small PNG the material reads: a scene whose inputs are files.
fn textured_box(dir: &Path) -> PathBuf {
    std::fs::copy(assets().join("box/Box0.bin"), dir.join("Box0.bin")).unwrap();
    image::RgbaImage::from_pixel(8, 8, image::Rgba([200, 60, 40, 255])).save(dir.join("logo.png")).unwrap();
    let mut gltf: serde_json::Value = serde_json::from_slice(&std::fs::read(assets().join("box/Box.gltf")).unwrap()).unwrap();
    gltf["images"] = serde_json::json!([{ "uri": "logo.png" }]);
    gltf["textures"] = serde_json::json!([{ "source": 0 }]);
    gltf["materials"][0]["emissiveTexture"] = serde_json::json!({ "index": 0 });
    let path = dir.join("box.gltf");
    std::fs::write(&path, serde_json::to_vec(&gltf).unwrap()).unwrap();
    path
}

#[test]
fn outputs_are_checked_before_rendering_and_never_replace_an_input() {
    let dir = temp_dir("output_checks");
    let scene = textured_box(&dir);
    let scene = scene.to_str().unwrap();
    let keep = dir.join("keep.png");
    let out = manylights(&["render", "--width", "64", "--height", "36", "-o", keep.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let before = std::fs::read(&keep).unwrap();
    let small = ["render", "--scene", scene, "--width", "64", "--height", "36"];
    fn with<'a>(small: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
        [small, extra].concat()
    }
    // Devices, unknown formats, missing folders and folders are refused before anything is drawn.
    assert!(one_error_line(&with(&small, &["-o", "/dev/full"])).contains("this path has no extension"));
    assert!(one_error_line(&with(&small, &["-o", "out.bmp"])).contains("-o writes .png, .jpg, .jpeg files"));
    assert!(one_error_line(&with(&small, &["--timings-json", "t.txt"])).contains("--timings-json writes .json files"));
    let err = one_error_line(&with(&small, &["-o", keep.to_str().unwrap(), "--exr", "/nonexistent/x.exr"]));
    assert!(err.contains("the folder /nonexistent does not exist"), "{err}");
    assert_eq!(std::fs::read(&keep).unwrap(), before, "a failed run left the earlier image as it was");
    // An output may not be any file the scene is read from: its texture here.
    let logo = dir.join("logo.png");
    let logo_bytes = std::fs::read(&logo).unwrap();
    let err = one_error_line(&with(&small, &["-o", logo.to_str().unwrap()]));
    assert!(err.contains("would overwrite") && err.contains("logo.png"), "{err}");
    assert_eq!(std::fs::read(&logo).unwrap(), logo_bytes);
    // JPEG for .jpg, PNG for .png.
    let jpeg = dir.join("out.jpg");
    let out = manylights(&with(&small, &["-o", jpeg.to_str().unwrap()]));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(image::ImageFormat::from_path(&jpeg).unwrap(), image::ImageFormat::Jpeg);
    assert!(std::fs::read(&jpeg).unwrap().starts_with(&[0xFF, 0xD8, 0xFF]), "a JPEG file");
}

/// A full file system (a 256 KiB tmpfs in a private mount namespace, filled): the render fails with
/// one error line and the image it would have replaced is still whole.
#[test]
fn a_full_disk_fails_the_render_and_keeps_the_earlier_image() {
    if !Command::new("unshare").args(["-rm", "true"]).status().is_ok_and(|s| s.success()) {
        eprintln!("skipped: needs `unshare -rm` (user and mount namespaces) to mount a small tmpfs");
        return;
    }
    let dir = temp_dir("full_disk");
    let mount = dir.join("small");
    std::fs::create_dir_all(&mount).unwrap();
    let bin = env!("CARGO_BIN_EXE_manylights");
    let script = format!(
        "set -e; mount -t tmpfs -o size=256k tmpfs '{m}'; cd '{m}'; \
         '{bin}' render --width 64 --height 36 -o out.png >/dev/null; cp out.png before.png; \
         cat /dev/zero > filler 2>/dev/null || true; \
         if '{bin}' render --lights 40 --width 320 --height 240 -o out.png 2>&1; then echo SUCCEEDED; fi; \
         cmp -s out.png before.png && echo INTACT; ls -a",
        m = mount.display()
    );
    let out = Command::new("unshare").args(["-rm", "sh", "-c", &script]).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(!stdout.contains("SUCCEEDED"), "the render reported success on a full disk: {stdout}");
    assert!(stdout.contains("error: cannot write out.png: No space left on device"), "{stdout}");
    assert!(stdout.contains("INTACT"), "the earlier image was replaced: {stdout}");
    assert!(!stdout.contains(".partial"), "a temporary file was left: {stdout}");
}

#[test]
fn malformed_and_endless_inputs_are_one_line_errors() {
    let dir = temp_dir("hostile_inputs");
    let gltf: serde_json::Value = serde_json::from_slice(&std::fs::read(assets().join("box/Box.gltf")).unwrap()).unwrap();
    std::fs::copy(assets().join("box/Box0.bin"), dir.join("Box0.bin")).unwrap();
    let write = |name: &str, edit: &dyn Fn(&mut serde_json::Value)| {
        let mut json = gltf.clone();
        edit(&mut json);
        let path = dir.join(name);
        std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
        path.to_str().unwrap().to_owned()
    };
    // An accessor index the glTF validator reads without checking.
    let position = write("position99.gltf", &|j| j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 99.into());
    for args in [&["render", "--scene", &position, "--width", "64", "--height", "36"][..], &["info", "--scene", &position]] {
        let err = one_error_line(args);
        assert!(err.contains("POSITION names accessor 99, and the file has 3 accessors"), "{err}");
        assert!(err.contains("re-export the file from its authoring tool, or check it with the Khronos glTF Validator"), "{err}");
    }
    // Endless and enormous files are refused before they are read.
    let zero = write("zero.gltf", &|j| j["buffers"][0]["uri"] = "/dev/zero".into());
    assert!(one_error_line(&["info", "--scene", &zero]).contains("only regular files are read"));
    let image = write("zero_image.gltf", &|j| {
        j["images"] = serde_json::json!([{ "uri": "/dev/zero" }]);
        j["textures"] = serde_json::json!([{ "source": 0 }]);
    });
    assert!(one_error_line(&["info", "--scene", &image]).contains("only regular files are read"));
    let sparse = dir.join("sparse.bin");
    std::fs::File::create(&sparse).unwrap().set_len(100 << 30).unwrap();
    let huge = write("huge.gltf", &|j| {
        j["buffers"][0]["uri"] = "sparse.bin".into();
        j["buffers"][0]["byteLength"] = (100u64 << 30).into();
    });
    let started = std::time::Instant::now();
    let err = one_error_line(&["info", "--scene", &huge]);
    assert!(err.contains("100.0 GiB is over the 2.0 GiB"), "{err}");
    assert!(started.elapsed().as_secs() < 30, "refused without reading");
    // Emission outside glTF's range is refused; a huge strength renders white.
    let negative = write("negative.gltf", &|j| j["materials"][0]["emissiveFactor"] = serde_json::json!([-3, -3, -3]));
    let err = one_error_line(&["render", "--scene", &negative, "--width", "64", "--height", "36"]);
    assert!(err.contains("emissiveFactor [-3.0, -3.0, -3.0] must be 0 to 1") && err.contains("KHR_materials_emissive_strength"), "{err}");
    for (strength, tonemap) in [(1e30, "aces"), (3.4e38, "aces"), (3.4e38, "agx"), (3.4e38, "none")] {
        let bright = write("bright.gltf", &|j| {
            j["materials"][0]["emissiveFactor"] = serde_json::json!([1, 1, 1]);
            j["materials"][0]["extensions"] = serde_json::json!({ "KHR_materials_emissive_strength": { "emissiveStrength": strength } });
            j["extensionsUsed"] = serde_json::json!(["KHR_materials_emissive_strength"]);
        });
        let png = dir.join("bright.png");
        let out = manylights(&[
            "render",
            "--scene",
            &bright,
            "--width",
            "64",
            "--height",
            "36",
            "--tonemap",
            tonemap,
            "-o",
            png.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let image = image::open(&png).unwrap().into_rgb8();
        let white = image.get_pixel(32, 18).0.iter().all(|&c| c >= 250);
        assert!(white, "an emissive strength of {strength} through {tonemap} shows {:?}, not white", image.get_pixel(32, 18).0);
    }
}

#[test]
fn info_refuses_what_render_refuses_at_once() {
    for args in [["info", "--decals", "16777216"], ["info", "--lights", "16777216"]] {
        let started = std::time::Instant::now();
        let err = one_error_line(&args);
        assert!(err.contains("use fewer"), "{err}");
        assert!(started.elapsed().as_secs() < 20, "{args:?} took {:?}", started.elapsed());
    }
}

#[test]
fn scene_file_mistakes_are_one_line_with_the_fix() {
    let dir = temp_dir("scene_file_mistakes");
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        path.to_str().unwrap().to_owned()
    };
    let syntax = write("syntax.toml", b"exposure = 1.0\n[sun\n");
    assert!(one_error_line(&["info", "--scene", &syntax]).contains("line 2, column"));
    let latin1 = write("latin1.toml", b"# caf\xe9\n");
    assert!(one_error_line(&["info", "--scene", &latin1]).contains("save it as UTF-8"));
    let empty = write("empty.toml", b"");
    assert!(one_error_line(&["info", "--scene", &empty]).contains("sets nothing to render"));
}

#[test]
fn sky_and_environment_flags_render_and_bad_ones_are_refused() {
    let dir = temp_dir("sky_and_environment");
    let duck = assets().join("duck/Duck.glb");
    let duck = duck.to_str().unwrap();
    for sky in ["auto", "daylight", "off"] {
        let out = render_to(&dir, &["--scene", duck, "--sky", sky]);
        assert!(out.status.success(), "--sky {sky}: {}", String::from_utf8_lossy(&out.stderr));
    }
    let hdr = dir.join("sky.hdr");
    let pixels = vec![image::Rgb([0.5f32, 0.6, 0.9]); 8];
    image::codecs::hdr::HdrEncoder::new(std::fs::File::create(&hdr).unwrap()).encode(&pixels, 4, 2).unwrap();
    let out = render_to(&dir, &["--scene", duck, "--environment", hdr.to_str().unwrap()]);
    assert!(out.status.success(), "--environment: {}", String::from_utf8_lossy(&out.stderr));

    let small = ["render", "--width", "16", "--height", "16", "--scene", duck];
    let both = failure(&[&small[..], &["--sky", "off", "--environment", hdr.to_str().unwrap()]].concat());
    assert!(both.starts_with("error: --sky off with --environment") && both.lines().count() == 1, "{both}");
    let missing = failure(&[&small[..], &["--environment", "no/such/sky.hdr"]].concat());
    assert!(missing.contains("no/such/sky.hdr") && missing.contains("check that the path exists"), "{missing}");
    let png = dir.join("flat.png");
    std::fs::write(&png, b"\x89PNG\r\n\x1a\n not really").unwrap();
    let wrong = failure(&[&small[..], &["--environment", png.to_str().unwrap()]].concat());
    assert!(wrong.contains("not a Radiance HDR (.hdr) or OpenEXR (.exr) image"), "{wrong}");
    let bad_sky = failure(&[&small[..], &["--sky", "night"]].concat());
    assert!(bad_sky.contains("--sky") && bad_sky.contains("daylight"), "{bad_sky}");
}
