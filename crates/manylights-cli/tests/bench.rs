//! `manylights bench --quick` on the test GPU (lavapipe) at a small resolution: its JSON, CSV,
//! Markdown and plots are well formed, their numbers positive, and the configurations exactly the
//! ones asked for; bad options are clear errors.

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::process::{Command, Output};

use serde_json::Value;

fn manylights(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_manylights")).args(args).output().expect("run manylights")
}

fn failure(args: &[&str]) -> String {
    let out = manylights(args);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!out.status.success(), "{args:?} succeeded; stderr: {stderr}");
    assert_ne!(out.status.code(), Some(101), "{args:?} panicked: {stderr}");
    stderr
}

/// (suite, scene, pipeline, method) of a result.
type Config = (String, String, String, String);

fn config_of(r: &Value) -> Config {
    let field = |k: &str| r[k].as_str().unwrap_or_else(|| panic!("{k} in {r}")).to_owned();
    (field("suite"), field("scene"), field("pipeline"), field("method"))
}

fn config(suite: &str, scene: &str, pipeline: &str, method: &str) -> Config {
    (suite.into(), scene.into(), pipeline.into(), method.into())
}

/// Splits one CSV line, honouring quoted fields.
fn csv_fields(line: &str) -> Vec<String> {
    let (mut fields, mut field, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted && chars.peek() == Some(&'"') => {
                field.push('"');
                chars.next();
            }
            '"' => quoted = !quoted,
            ',' if !quoted => fields.push(std::mem::take(&mut field)),
            c => field.push(c),
        }
    }
    fields.push(field);
    fields
}

fn positive(v: &Value, what: &str) -> f64 {
    let x = v.as_f64().unwrap_or_else(|| panic!("{what} is not a number: {v}"));
    assert!(x > 0.0 && x.is_finite(), "{what} = {x}");
    x
}

#[test]
fn quick_bench_writes_the_configurations_asked_for() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench_quick");
    let _ = std::fs::remove_dir_all(&out);
    #[rustfmt::skip]
    let args = [
        "bench", "--quick", "--scene", "demo", "--width", "64", "--height", "36", "--anisotropy", "1",
        "--scenes", "small-decals,small-lights", "--pipelines", "visbuffer,deferred",
        "--methods", "off,bvh,deferred-decals", "--sweeps", "lights", "--sweep-max", "4096", "--dense", "none",
        // Generous, so that a slow machine still times every configuration.
        "--time-cap-ms", "60000", "--out", out.to_str().unwrap(),
    ];
    let run = manylights(&args);
    assert!(run.status.success(), "bench failed: {}", String::from_utf8_lossy(&run.stderr));

    let json: Value = serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    assert!(!json["device"].as_str().unwrap().is_empty() && json["commit"].is_string());
    assert_eq!((json["width"].as_u64(), json["height"].as_u64(), json["timed_frames"].as_u64()), (Some(64), Some(36), Some(10)));
    let results = json["results"].as_array().unwrap();
    let got: BTreeSet<Config> = results.iter().map(config_of).collect();
    assert_eq!(got.len(), results.len(), "a configuration ran twice");
    let mut want = BTreeSet::new();
    for pipeline in ["visbuffer", "deferred"] {
        want.insert(config("table", "base", pipeline, "off"));
        want.insert(config("table", "small-decals", pipeline, "bvh"));
        want.insert(config("table", "small-lights", pipeline, "bvh"));
    }
    // Deferred decals only where they apply: decal scenes, deferred pipeline.
    want.insert(config("table", "small-decals", "deferred", "deferred-decals"));
    for count in ["1024", "4096"] {
        for method in ["bvh", "clustered", "brute"] {
            want.insert(config("sweep-lights", count, "visbuffer", method));
        }
    }
    assert_eq!(got, want);

    for r in results {
        let what = format!("{:?}", config_of(r));
        assert_eq!(r["status"], "timed", "{what}: {r}");
        assert_eq!(r["frames"].as_u64(), Some(10), "{what}");
        let median = positive(&r["frame"]["median_ms"], &format!("{what} frame median"));
        assert!(r["frame"]["p95_ms"].as_f64().unwrap() >= median, "{what}: p95 below the median");
        positive(&r["cpu_frame"]["median_ms"], &format!("{what} CPU frame"));
        positive(&r["wall_ms_per_frame"], &format!("{what} wall time"));
        let passes = r["passes"].as_object().unwrap();
        assert!(passes.contains_key("tonemap"), "{what}: {passes:?}");
        let sum: f64 = passes.iter().map(|(name, p)| positive(&p["median_ms"], &format!("{what} {name}"))).sum();
        assert!(sum > 0.0);
        positive(&r["groups"]["shade"]["median_ms"], &format!("{what} shade"));
        // Clustered lists and the BVH of the sweeps are built on the GPU every frame.
        if r["suite"] == "sweep-lights" && r["method"] != "brute" {
            positive(&r["groups"]["build"]["median_ms"], &format!("{what} build"));
        }
        let (lights, decals) = (r["lights"].as_u64().unwrap(), r["decals"].as_u64().unwrap());
        match (r["scene"].as_str().unwrap(), r["suite"].as_str().unwrap()) {
            ("base", _) => assert!(r["mean_overlap"].is_null() && decals == 0),
            ("small-decals", _) => assert_eq!(decals, 100),
            ("small-lights", _) => assert!(lights >= 28_000 && decals == 0),
            (count, _) => assert!(lights >= count.parse::<u64>().unwrap()),
        }
        if r["scene"] != "base" {
            positive(&r["mean_overlap"], &format!("{what} overlap"));
        }
    }

    let csv = std::fs::read_to_string(out.join("bench.csv")).unwrap();
    let mut lines = csv.lines();
    let header = csv_fields(lines.next().unwrap());
    assert_eq!(header.last().map(String::as_str), Some("p95_ms"));
    let column = |name: &str| header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no {name} column"));
    let mut frame_rows = BTreeSet::new();
    for line in lines {
        let fields = csv_fields(line);
        assert_eq!(fields.len(), header.len(), "{line}");
        assert_eq!(fields[column("status")], "timed", "{line}");
        let median: f64 = fields[column("median_ms")].parse().unwrap();
        assert!(median > 0.0, "{line}");
        if fields[column("pass")] == "frame" {
            let key = config(&fields[column("suite")], &fields[column("scene")], &fields[column("pipeline")], &fields[column("method")]);
            frame_rows.insert(key);
        }
    }
    assert_eq!(frame_rows, want, "one frame row per configuration");

    let md = std::fs::read_to_string(out.join("bench.md")).unwrap();
    for needle in [
        "## Table 1",
        "| 100 small decals |",
        "| 28k small lights |",
        "## Every pipeline with every method",
        "## Sweep: lights (visbuffer pipeline; bvh rebuilt on the GPU every frame)",
        "| bvh ÷ clustered |",
        "](sweep-lights.png)",
    ] {
        assert!(md.contains(needle), "bench.md lacks {needle:?}:\n{md}");
    }
    assert!(!md.contains("## Sweep: decals") && !md.contains("6 large decals"), "configurations not asked for:\n{md}");
    let plot = image::open(out.join("sweep-lights.png")).unwrap().to_rgb8();
    assert!(plot.width() >= 800 && plot.height() >= 400);
    // Drawn on: more than a few colours (lines, labels), not a blank canvas.
    let colours: BTreeSet<[u8; 3]> = plot.pixels().map(|p| p.0).collect();
    assert!(colours.len() > 20, "{} colours", colours.len());
    assert!(!out.join("sweep-decals.png").exists());
}

/// `--sweep-build cpu-once` sweeps the bvh built once, and the report says so.
#[test]
fn sweeps_of_bvh_built_once() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench_sweep_once");
    let _ = std::fs::remove_dir_all(&out);
    #[rustfmt::skip]
    let args = [
        "bench", "--quick", "--scene", "demo", "--width", "64", "--height", "36", "--anisotropy", "1",
        "--scenes", "none", "--dense", "none", "--sweeps", "decals", "--sweep-max", "1024", "--sweep-build", "cpu-once",
        "--time-cap-ms", "60000", "--out", out.to_str().unwrap(),
    ];
    let run = manylights(&args);
    assert!(run.status.success(), "bench failed: {}", String::from_utf8_lossy(&run.stderr));
    let json: Value = serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    let results = json["results"].as_array().unwrap();
    let builds: BTreeSet<(String, String)> =
        results.iter().map(|r| (r["method"].as_str().unwrap().to_owned(), r["bvh_build"].as_str().unwrap().to_owned())).collect();
    let want: BTreeSet<(String, String)> = ["bvh", "clustered", "brute"].iter().map(|m| (m.to_string(), "CpuOnce".to_owned())).collect();
    assert_eq!(builds, want);
    let md = std::fs::read_to_string(out.join("bench.md")).unwrap();
    assert!(md.contains("## Sweep: decals (visbuffer pipeline; bvh built once)"), "{md}");
}

/// The dense-light suite: a range found for the overlap asked, bvh built once and every frame against
/// clustered shading, and `auto`, which says what it ran.
#[test]
fn dense_bench_compares_bvh_with_clustered_and_auto() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench_dense");
    let _ = std::fs::remove_dir_all(&out);
    #[rustfmt::skip]
    let args = [
        "bench", "--scene", "demo", "--width", "64", "--height", "36", "--anisotropy", "1", "--frames", "3", "--warmup", "1",
        "--scenes", "none", "--sweeps", "none", "--dense", "overlap-10", "--pipelines", "visbuffer",
        "--time-cap-ms", "60000", "--out", out.to_str().unwrap(),
    ];
    let run = manylights(&args);
    assert!(run.status.success(), "bench failed: {}", String::from_utf8_lossy(&run.stderr));
    let json: Value = serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    let results = json["results"].as_array().unwrap();
    let got: BTreeSet<(String, String)> =
        results.iter().map(|r| (r["method"].as_str().unwrap().to_owned(), r["bvh_build"].as_str().unwrap().to_owned())).collect();
    let want: BTreeSet<(String, String)> =
        [("bvh", "CpuOnce"), ("bvh", "GpuEveryFrame"), ("clustered", "CpuOnce"), ("auto", "CpuOnce"), ("auto", "GpuEveryFrame")]
            .map(|(m, b)| (m.to_owned(), b.to_owned()))
            .into_iter()
            .collect();
    assert_eq!((got, results.len()), (want, 5));
    for r in results {
        assert_eq!(
            (r["suite"].as_str(), r["scene"].as_str(), r["status"].as_str()),
            (Some("dense"), Some("overlap-10"), Some("timed")),
            "{r}"
        );
        let overlap = r["mean_overlap"].as_f64().unwrap();
        assert!((5.0..=20.0).contains(&overlap), "overlap {overlap}, asked about 10");
        let ran = r["light_method_ran"].as_str().unwrap();
        match r["method"].as_str().unwrap() {
            "auto" => assert!(["bvh (auto: ", "clustered (auto: "].iter().any(|m| ran.starts_with(m)), "{ran}"),
            method => assert_eq!(ran, format!("{method} (asked for)")),
        }
    }
    let md = std::fs::read_to_string(out.join("bench.md")).unwrap();
    assert!(md.contains("## Dense lights") && md.contains("| overlap-10 |") && !md.contains("## Table 1"), "{md}");
}

/// A scene that cannot be generated is a failed configuration in the report, not the end of the run.
#[test]
fn scenes_that_cannot_be_generated_are_reported_failed() {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bench_failed_scene");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out).unwrap();
    // Grouped lights: scattering more into them is refused (`generators::add_scattered_lights`).
    let box_gltf = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets/box/Box.gltf");
    let scene = out.join("grouped.toml");
    std::fs::write(&scene, format!("gltf = {:?}\n[[scatter_lights]]\ncount = 20\n[animate]\ngroups = 2\n", box_gltf.to_str().unwrap()))
        .unwrap();
    #[rustfmt::skip]
    let args = [
        "bench", "--quick", "--scene", scene.to_str().unwrap(), "--width", "32", "--height", "18", "--anisotropy", "1",
        "--scenes", "small-lights", "--pipelines", "visbuffer", "--methods", "off,bvh", "--sweeps", "none",
        "--out", out.to_str().unwrap(),
    ];
    let run = manylights(&args);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "bench failed: {stderr}");
    assert!(stderr.contains("cannot generate the small-lights scene"), "{stderr}");
    let json: Value = serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    let results = json["results"].as_array().unwrap();
    let status = |scene: &str| results.iter().find(|r| r["scene"] == scene).map(|r| r["status"].as_str().unwrap().to_owned());
    assert_eq!(status("base").as_deref(), Some("timed"));
    assert_eq!(status("small-lights").as_deref(), Some("failed"));
    let failed = results.iter().find(|r| r["scene"] == "small-lights").unwrap();
    assert!(failed["reason"].as_str().unwrap().contains("grouped"), "{failed}");
    let md = std::fs::read_to_string(out.join("bench.md")).unwrap();
    assert!(md.contains("## Failed configurations") && md.contains("grouped"), "{md}");
}

#[test]
fn bad_bench_options_are_clear_errors() {
    let missing = failure(&["bench", "--scene", "/nonexistent/scene.gltf", "--quick"]);
    assert!(missing.contains("/nonexistent/scene.gltf") && missing.contains("--scene"), "{missing}");
    let nothing = failure(&["bench", "--scene", "demo", "--scenes", "none", "--sweeps", "none", "--dense", "none"]);
    assert!(nothing.contains("nothing to run"), "{nothing}");
    let none_and_more = failure(&["bench", "--scene", "demo", "--dense", "none,overlap-10"]);
    assert!(none_and_more.contains("--dense") && none_and_more.contains("alone"), "{none_and_more}");
    let small = failure(&["bench", "--scene", "demo", "--sweep-max", "100"]);
    assert!(small.contains("--sweep-max 100") && small.contains("1024"), "{small}");
    let cap = failure(&["bench", "--scene", "demo", "--time-cap-ms", "-5"]);
    assert!(cap.contains("--time-cap-ms"), "{cap}");
    let frames = failure(&["bench", "--scene", "demo", "--frames", "0"]);
    assert!(frames.contains("--frames"), "{frames}");
    let unknown = failure(&["bench", "--scene", "demo", "--methods", "magic"]);
    assert!(unknown.contains("magic") && unknown.contains("bvh"), "{unknown}");
    let resolution = failure(&["bench", "--scene", "demo", "--quick", "--width", "0", "--scenes", "small-decals", "--sweeps", "none"]);
    assert!(resolution.contains("0×"), "{resolution}");
}
