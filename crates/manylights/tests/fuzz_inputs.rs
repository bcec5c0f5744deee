//! Hostile inputs: the shared assets' glTF JSON, GLB, binary buffer, PNG and JPEG textures and a scene
//! file, mutated thousands of times with a seeded generator (bit flips, truncations, numbers swapped
//! for extremes, indices out of range). Every load must end in a scene or an error of one line:
//! never a panic (ours, or a parser's that `files::guard` contained), a hang or an abort. A few of the
//! scenes that still load are rendered, which must not panic either.

mod common;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use manylights::{gpu::GpuContext, renderer::Renderer, scene, Error};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// Mutations per kind of input.
const CASES_PER_INPUT: usize = 800;
/// Longest a single load may take before the test calls it a hang.
const HANG: Duration = Duration::from_secs(30);
/// Loaded mutants rendered on the GPU.
const RENDERED: usize = 6;

fn assets() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("manylights-fuzz-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Numbers a careless or hostile file might hold where a sane one does not.
const EXTREMES: [&str; 14] = [
    "-1",
    "0",
    "-0",
    "1e30",
    "-1e30",
    "3.4e38",
    "1e-45",
    "4294967295",
    "4294967296",
    "18446744073709551616",
    "99",
    "65535",
    "2147483648",
    "0.5",
];

/// One mutation of `bytes`: bit flips, a truncation, or (in text) numbers swapped for extremes or
/// for indices just out of range.
fn mutate(bytes: &[u8], text: bool, rng: &mut Pcg64) -> Vec<u8> {
    let mut out = bytes.to_vec();
    let kinds = if text { 4 } else { 3 };
    match rng.random_range(0..kinds) {
        0 => {
            for _ in 0..rng.random_range(1..=4) {
                let i = rng.random_range(0..out.len());
                out[i] ^= 1 << rng.random_range(0..8);
            }
        }
        1 => out.truncate(rng.random_range(0..out.len())),
        2 if !text => {
            // A 32-bit field (a length, a count, a float) set to an extreme.
            let at = rng.random_range(0..out.len().saturating_sub(4).max(1));
            let value: u32 = [u32::MAX, 0, 0x7F80_0000, 0x7FC0_0000, 0xFF7F_FFFF, 0x8000_0000, 65535, 1 << 24][rng.random_range(0..8)];
            let width = 4.min(out.len() - at);
            out[at..at + width].copy_from_slice(&value.to_le_bytes()[..width]);
        }
        _ => {
            let source = String::from_utf8_lossy(bytes).into_owned();
            let numbers = number_spans(&source);
            if numbers.is_empty() {
                out.truncate(out.len() / 2);
                return out;
            }
            let mut text = source.clone();
            let mut picked: Vec<(usize, usize)> =
                (0..rng.random_range(1..=3)).map(|_| numbers[rng.random_range(0..numbers.len())]).collect();
            picked.sort();
            picked.dedup();
            for &(start, end) in picked.iter().rev() {
                let original = &source[start..end];
                let replacement = if rng.random_bool(0.5) && !original.contains('.') {
                    // An index a little past what the file has.
                    (original.parse::<u64>().unwrap_or(0) + rng.random_range(1..8)).to_string()
                } else {
                    EXTREMES[rng.random_range(0..EXTREMES.len())].to_string()
                };
                text.replace_range(start..end, &replacement);
            }
            out = text.into_bytes();
        }
    }
    out
}

/// Byte ranges of the numbers in a JSON or TOML text.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let bytes = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let starts =
            (bytes[i].is_ascii_digit() || bytes[i] == b'-') && (i == 0 || !bytes[i - 1].is_ascii_alphanumeric() && bytes[i - 1] != b'_');
        if starts {
            let start = i;
            i += 1;
            while i < bytes.len() && (bytes[i].is_ascii_digit() || matches!(bytes[i], b'.' | b'e' | b'E' | b'-' | b'+')) {
                i += 1;
            }
            if bytes[start..i].iter().any(u8::is_ascii_digit) {
                spans.push((start, i));
            }
        } else {
            i += 1;
        }
    }
    spans
}

/// Watches the loads: aborts the whole test, naming the case, if one runs past [`HANG`].
struct Watchdog {
    started_ms: Arc<AtomicU64>,
    case: Arc<Mutex<String>>,
    done: Arc<AtomicBool>,
    epoch: Instant,
}

impl Watchdog {
    fn start() -> Self {
        let watchdog = Self {
            started_ms: Arc::new(AtomicU64::new(u64::MAX)),
            case: Arc::new(Mutex::new(String::new())),
            done: Arc::new(AtomicBool::new(false)),
            epoch: Instant::now(),
        };
        let (started_ms, case, done, epoch) = (watchdog.started_ms.clone(), watchdog.case.clone(), watchdog.done.clone(), watchdog.epoch);
        std::thread::spawn(move || {
            while !done.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(200));
                let started = started_ms.load(Ordering::Relaxed);
                if started != u64::MAX && epoch.elapsed().as_millis() as u64 > started + HANG.as_millis() as u64 {
                    eprintln!("hang: {} has run for more than {HANG:?}", case.lock().unwrap());
                    std::process::abort();
                }
            }
        });
        watchdog
    }

    fn begin(&self, case: String) {
        *self.case.lock().unwrap() = case;
        self.started_ms.store(self.epoch.elapsed().as_millis() as u64, Ordering::Relaxed);
    }

    fn end(&self) {
        self.started_ms.store(u64::MAX, Ordering::Relaxed);
    }
}

impl Drop for Watchdog {
    fn drop(&mut self) {
        self.done.store(true, Ordering::Relaxed);
    }
}

/// An input file to mutate, beside the unmutated files of its scene; `entry` is what is loaded.
struct Input {
    name: &'static str,
    file: &'static str,
    bytes: Vec<u8>,
    text: bool,
    entry: &'static str,
}

/// Box.gltf with an external PNG and JPEG texture (the Cesium logo of BoxTextured, re-encoded) added
/// to its material: one file set whose every part is mutated in turn.
fn scene_files(dir: &Path) -> Vec<Input> {
    let read = |relative: &str| std::fs::read(assets().join(relative)).unwrap();
    let logo = scene::gltf::import(&assets().join("box_textured/BoxTextured.glb")).unwrap().textures.remove(0);
    let logo = image::RgbaImage::from_raw(logo.width, logo.height, logo.rgba8).unwrap();
    let small = image::imageops::resize(&logo, 32, 32, image::imageops::FilterType::Triangle);
    let mut png = Vec::new();
    small.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png).unwrap();
    let mut jpeg = Vec::new();
    image::DynamicImage::ImageRgba8(small).to_rgb8().write_to(&mut std::io::Cursor::new(&mut jpeg), image::ImageFormat::Jpeg).unwrap();

    let mut gltf: serde_json::Value = serde_json::from_slice(&read("box/Box.gltf")).unwrap();
    gltf["images"] = serde_json::json!([{ "uri": "logo.png" }, { "uri": "logo.jpg" }]);
    gltf["textures"] = serde_json::json!([{ "source": 0 }, { "source": 1 }]);
    gltf["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = serde_json::json!({ "index": 0 });
    gltf["materials"][0]["emissiveTexture"] = serde_json::json!({ "index": 1 });
    let gltf = serde_json::to_vec_pretty(&gltf).unwrap();
    let toml = String::from(
        "gltf = 'Box.gltf'\nexposure = 1.5\nambient = [0.1, 0.1, 0.1]\n\
         [camera]\nposition = [2.0, 1.5, 3.0]\ntarget = [0.0, 0.0, 0.0]\nyfov_degrees = 50.0\nnear = 0.05\n\
         [sun]\ndirection = [-0.3, -1.0, -0.2]\ncolor = [1.0, 0.9, 0.8]\nilluminance = 3.0\n\
         [[lights]]\ntype = 'spot'\nposition = [0.0, 2.0, 0.0]\nintensity = 20.0\nrange = 5.0\ndirection = [0.0, -1.0, 0.0]\n\
         inner_cone_degrees = 10.0\nouter_cone_degrees = 30.0\n\
         [[scatter_lights]]\ncount = 16\nseed = 3\nrange = [0.2, 0.6]\n\
         [[decals]]\nposition = [0.0, 0.5, 0.0]\nnormal = [0.0, 1.0, 0.0]\nsize = [0.5, 0.5, 0.2]\nalbedo = 'logo.png'\nlayer = 1\n\
         [[scatter_decals]]\ncount = 8\nseed = 2\n\
         [particles]\ncount = 64\nemitters = 2\nradius = [0.2, 0.4]\n\
         [rays]\nshadows = 'soft'\nshadow_rays = 2\nreflections = 1\nlight_shadow_rays = 2\n\
         [[deform]]\nmesh = 'Mesh'\namplitude = 0.05\nwavelength = 0.5\n\
         [animate]\ngroups = 2\nseed = 1\n",
    );
    for (name, bytes) in
        [("Box.gltf", gltf.clone()), ("Box0.bin", read("box/Box0.bin")), ("logo.png", png.clone()), ("logo.jpg", jpeg.clone())]
    {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    vec![
        Input { name: "glTF JSON", file: "Box.gltf", bytes: gltf, text: true, entry: "Box.gltf" },
        Input { name: "binary buffer", file: "Box0.bin", bytes: read("box/Box0.bin"), text: false, entry: "Box.gltf" },
        Input { name: "PNG texture", file: "logo.png", bytes: png, text: false, entry: "Box.gltf" },
        Input { name: "JPEG texture", file: "logo.jpg", bytes: jpeg, text: false, entry: "Box.gltf" },
        Input { name: "GLB", file: "Duck.glb", bytes: read("duck/Duck.glb"), text: false, entry: "Duck.glb" },
        Input { name: "scene file", file: "scene.toml", bytes: toml.into_bytes(), text: true, entry: "scene.toml" },
    ]
}

#[test]
fn mutated_inputs_load_or_fail_with_one_line_never_a_panic() {
    let dir = temp_dir("inputs");
    let inputs = scene_files(&dir);
    // The unmutated files load: the mutations start from working inputs.
    for input in &inputs {
        std::fs::write(dir.join(input.file), &input.bytes).unwrap();
        scene::load_path(&dir.join(input.entry)).unwrap_or_else(|e| panic!("{} unmutated: {e}", input.name));
    }
    let watchdog = Watchdog::start();
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut rng = Pcg64::seed_from_u64(31);
    let (mut loaded, mut rendered, mut failures) = (0, 0, Vec::new());
    let started = Instant::now();
    for input in &inputs {
        for case in 0..CASES_PER_INPUT {
            let mutant = mutate(&input.bytes, input.text, &mut rng);
            std::fs::write(dir.join(input.file), &mutant).unwrap();
            watchdog.begin(format!("{} case {case}", input.name));
            let result = catch_unwind(AssertUnwindSafe(|| scene::load_path(&dir.join(input.entry))));
            watchdog.end();
            match result {
                Err(_) => failures.push(format!("{} case {case}: the load panicked", input.name)),
                Ok(Err(e @ Error::ParserPanic { .. })) => failures.push(format!("{} case {case}: {e}", input.name)),
                Ok(Err(e)) if e.to_string().contains('\n') => {
                    failures.push(format!("{} case {case}: an error of several lines: {e}", input.name))
                }
                Ok(Err(_)) => {}
                Ok(Ok(scene)) => {
                    loaded += 1;
                    // A few of the loaded mutants, spread over the inputs, are drawn.
                    if rendered < RENDERED && case % (CASES_PER_INPUT / 2) == 1 && mutant != input.bytes {
                        rendered += 1;
                        let camera = scene.cameras.first().cloned().unwrap_or_else(|| scene::Camera::framing(&scene.bounds()));
                        let config = common::config(32, 18, manylights::settings::LightMethod::Bvh);
                        watchdog.begin(format!("{} case {case}, rendered", input.name));
                        let drawn = catch_unwind(AssertUnwindSafe(|| {
                            Renderer::new(ctx.clone(), &scene, config).and_then(|mut r| r.render_frames(&camera, 1).map(|_| ()))
                        }));
                        watchdog.end();
                        if drawn.is_err() {
                            failures.push(format!("{} case {case}: rendering the loaded mutant panicked", input.name));
                        }
                    }
                }
            }
        }
        std::fs::write(dir.join(input.file), &input.bytes).unwrap();
    }
    let _ = std::fs::remove_dir_all(&dir);
    println!(
        "{} mutants, {loaded} loaded, {rendered} rendered, in {:.1} s",
        inputs.len() * CASES_PER_INPUT,
        started.elapsed().as_secs_f64()
    );
    assert!(failures.is_empty(), "{} of the mutants failed:\n{}", failures.len(), failures.join("\n"));
    assert!(loaded > 0 && loaded < inputs.len() * CASES_PER_INPUT, "the mutations both break and keep some inputs ({loaded} loaded)");
    assert_eq!(rendered, RENDERED, "loaded mutants were rendered");
}

#[test]
fn number_spans_find_json_and_toml_numbers() {
    let text = r#"{"a": [1, -2.5e3], "b_2": 7} x = 0.25"#;
    let found: Vec<&str> = number_spans(text).into_iter().map(|(s, e)| &text[s..e]).collect();
    assert_eq!(found, ["1", "-2.5e3", "7", "0.25"]);
}
