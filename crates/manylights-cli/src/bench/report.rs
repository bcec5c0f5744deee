//! The bench's files: `bench.json` (every figure and the run's details), `bench.csv` (one row per
//! configuration and pass), `bench.md` (the paper's Table 1 layout, the full matrix, the sweeps) and
//! the sweep plots.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context;
use manylights::files::{OutputFormat, StagedOutputs};
use manylights::scene::paper_scenes::PaperScene;
use manylights::settings::{BvhBuild, PipelineKind};

use super::measure::{Measurement, Outcome, PassGroup};
use super::{plot, RunInfo, Suite, SweepArg};

/// The paper's published figures (Hansen & Peters 2021, Table 1; RTX 2070 Super, 1920×1080), in ms:
/// (scene, pipeline or "deferred decals", without → with).
const PAPER: [(&str, &str, Option<f64>, f64); 6] = [
    ("many-decals", "forward", Some(5.1), 16.0),
    ("many-decals", "visbuffer", Some(2.7), 5.0),
    ("many-decals", "deferred", Some(3.1), 6.4),
    ("many-decals", "deferred decals", Some(3.1), 5.5),
    ("small-lights", "forward", None, 27.8),
    ("small-lights", "visbuffer", None, 10.8),
];

/// The files a run may write into its folder, each with its format.
pub(crate) const FILES: [(&str, OutputFormat); 5] = [
    ("bench.json", OutputFormat::Json),
    ("bench.csv", OutputFormat::Csv),
    ("bench.md", OutputFormat::Markdown),
    ("sweep-lights.png", OutputFormat::Png),
    ("sweep-decals.png", OutputFormat::Png),
];

/// Writes the run's files together: a failure leaves every earlier file in the folder as it was.
pub(crate) fn write_all(dir: &Path, info: &RunInfo, results: &[Measurement]) -> anyhow::Result<Vec<PathBuf>> {
    let mut files: Vec<(&str, Vec<u8>)> = vec![
        ("bench.json", serde_json::to_string_pretty(&json(info, results))?.into_bytes()),
        ("bench.csv", csv(info, results).into_bytes()),
    ];
    let mut plots = Vec::new();
    for sweep in [SweepArg::Lights, SweepArg::Decals] {
        let rows: Vec<&Measurement> = results.iter().filter(|r| r.suite == Suite::Sweep(sweep)).collect();
        if !rows.is_empty() {
            let name =
                FILES.iter().map(|(name, _)| *name).find(|name| name.starts_with(Suite::Sweep(sweep).name())).context("a plot's name")?;
            files.push((name, plot::sweep(info, sweep, &rows)?));
            plots.push(name.to_owned());
        }
    }
    files.push(("bench.md", markdown(info, results, &plots).into_bytes()));
    let mut staged = StagedOutputs::new();
    for (name, bytes) in &files {
        staged.stage(&dir.join(name), bytes)?;
    }
    staged.commit()?;
    Ok(files.iter().map(|(name, _)| dir.join(name)).collect())
}

fn json(info: &RunInfo, results: &[Measurement]) -> serde_json::Value {
    let results: Vec<serde_json::Value> = results
        .iter()
        .map(|r| {
            let mut entry = serde_json::json!({
                "suite": r.suite.name(),
                "scene": r.scene,
                "lights": r.lights,
                "decals": r.decals,
                "mean_overlap": r.overlap,
                "pipeline": r.config.pipeline.name(),
                "light_method": r.config.light_method.name(),
                "decal_method": r.config.decal_method.name(),
                "method": r.method(),
                "bvh_build": format!("{:?}", r.config.light_bvh_build),
                "status": r.outcome.status(),
            });
            let fields = entry.as_object_mut().expect("an object");
            match &r.outcome {
                Outcome::Timed(t) => {
                    fields.insert("frames".into(), t.frames.into());
                    fields.insert("light_method_ran".into(), t.chosen.lights.to_string().into());
                    fields.insert("decal_method_ran".into(), t.chosen.decals.to_string().into());
                    fields.insert("frame".into(), t.gpu_frame.to_json());
                    fields.insert("cpu_frame".into(), t.cpu_frame.to_json());
                    fields.insert("wall_ms_per_frame".into(), t.wall_ms_per_frame.into());
                    let groups: serde_json::Map<_, _> = t.groups.iter().map(|(g, s)| (g.name().to_owned(), s.to_json())).collect();
                    fields.insert("groups".into(), groups.into());
                    let passes: serde_json::Map<_, _> = t.passes.iter().map(|(n, s)| (n.to_string(), s.to_json())).collect();
                    fields.insert("passes".into(), passes.into());
                }
                Outcome::OverCap(ms) => {
                    fields.insert("capped_frame_ms".into(), (*ms).into());
                }
                Outcome::Skipped(reason) | Outcome::Failed(reason) => {
                    fields.insert("reason".into(), reason.clone().into());
                }
            }
            entry
        })
        .collect();
    serde_json::json!({
        "device": info.device,
        "driver": info.driver,
        "backend": info.backend,
        "ray_backend": info.ray_tracer,
        "commit": info.commit,
        "scene": info.scene,
        "camera": info.camera,
        "triangles": info.triangles,
        "width": info.width,
        "height": info.height,
        "timed_frames": info.frames,
        "warmup_frames": info.warmup,
        "time_cap_ms": info.time_cap_ms,
        "seed": info.seed,
        "quick": info.quick,
        "results": results,
    })
}

const CSV_HEADER: &str = "device,driver,commit,width,height,suite,scene,lights,decals,mean_overlap,pipeline,light_method,decal_method,method,status,frames,pass,median_ms,p95_ms";

/// One row per configuration and figure: each pass, each group (`group:build`…), `frame`, `cpu_frame`
/// and `wall_per_frame` (median = mean, no p95); configurations not timed get one row with their
/// status and, over the cap, the second frame's time.
fn csv(info: &RunInfo, results: &[Measurement]) -> String {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    for r in results {
        let prefix = [
            quote(&info.device),
            quote(&info.driver),
            info.commit.to_owned(),
            info.width.to_string(),
            info.height.to_string(),
            r.suite.name().to_owned(),
            quote(&r.scene),
            r.lights.to_string(),
            r.decals.to_string(),
            r.overlap.map(|o| format!("{o:.4}")).unwrap_or_default(),
            r.config.pipeline.name().to_owned(),
            r.config.light_method.name().to_owned(),
            r.config.decal_method.name().to_owned(),
            r.method().to_owned(),
            r.outcome.status().to_owned(),
        ]
        .join(",");
        let mut row = |frames: String, pass: &str, median: String, p95: String| {
            let _ = writeln!(out, "{prefix},{frames},{pass},{median},{p95}");
        };
        match &r.outcome {
            Outcome::Timed(t) => {
                let n = t.frames.to_string();
                for (name, s) in &t.passes {
                    row(n.clone(), name, format!("{:.6}", s.median), format!("{:.6}", s.p95));
                }
                for (group, s) in &t.groups {
                    row(n.clone(), &format!("group:{}", group.name()), format!("{:.6}", s.median), format!("{:.6}", s.p95));
                }
                row(n.clone(), "frame", format!("{:.6}", t.gpu_frame.median), format!("{:.6}", t.gpu_frame.p95));
                row(n.clone(), "cpu_frame", format!("{:.6}", t.cpu_frame.median), format!("{:.6}", t.cpu_frame.p95));
                row(n, "wall_per_frame", format!("{:.6}", t.wall_ms_per_frame), String::new());
            }
            Outcome::OverCap(ms) => row("1".into(), "frame", format!("{ms:.6}"), String::new()),
            Outcome::Skipped(_) | Outcome::Failed(_) => row("0".into(), "", String::new(), String::new()),
        }
    }
    out
}

fn quote(field: &str) -> String {
    if field.contains([',', '"', '\n']) {
        format!("\"{}\"", field.replace('"', "\"\""))
    } else {
        field.to_owned()
    }
}

/// A table cell: the median frame time, or what happened instead.
fn frame_cell(r: Option<&Measurement>) -> String {
    match r.map(|r| &r.outcome) {
        None => "—".into(),
        Some(Outcome::Timed(t)) => format!("{:.3}", t.gpu_frame.median),
        Some(Outcome::OverCap(ms)) => format!("> cap ({ms:.0})"),
        Some(Outcome::Skipped(_)) => "skipped".into(),
        Some(Outcome::Failed(_)) => "failed".into(),
    }
}

fn group_cell(r: &Measurement, group: PassGroup) -> String {
    match &r.outcome {
        Outcome::Timed(t) => t.group(group).map_or("—".into(), |s| format!("{:.3}", s.median)),
        _ => "—".into(),
    }
}

fn markdown(info: &RunInfo, results: &[Measurement], plots: &[String]) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# manylights bench{}\n", if info.quick { " (quick)" } else { "" });
    let _ = writeln!(
        md,
        "- Device: **{}** ({}), driver {}, {} ray backend; commit `{}`\n- Scene: `{}` ({} triangles), camera \"{}\", {}×{}; seed {}\n\
         - Per configuration: {} warm-up frames, then the median (and p95) of {} frames' GPU timestamps, in ms; \
         configurations whose first two frames each took over {} ms are reported as over the cap with the second one's time\n",
        info.device,
        info.backend,
        info.driver,
        info.ray_tracer,
        info.commit,
        info.scene,
        info.triangles,
        info.camera,
        info.width,
        info.height,
        info.seed,
        info.warmup,
        info.frames,
        info.time_cap_ms
    );

    let table: Vec<&Measurement> = results.iter().filter(|r| r.suite == Suite::Table).collect();
    if !table.is_empty() {
        table_one(&mut md, &table);
        matrix(&mut md, &table);
    }
    let dense: Vec<&Measurement> = results.iter().filter(|r| r.suite == Suite::Dense).collect();
    if !dense.is_empty() {
        dense_table(&mut md, &dense);
    }
    for sweep in [SweepArg::Lights, SweepArg::Decals] {
        let rows: Vec<&Measurement> = results.iter().filter(|r| r.suite == Suite::Sweep(sweep)).collect();
        if !rows.is_empty() {
            sweep_table(&mut md, sweep, &rows);
            let plot = format!("{}.png", Suite::Sweep(sweep).name());
            if plots.contains(&plot) {
                let _ = writeln!(md, "![{}]({plot})\n", Suite::Sweep(sweep).name());
            }
        }
    }
    let failures: Vec<&Measurement> = results.iter().filter(|r| matches!(r.outcome, Outcome::Failed(_))).collect();
    if !failures.is_empty() {
        let _ = writeln!(md, "## Failed configurations\n");
        for r in failures {
            if let Outcome::Failed(reason) = &r.outcome {
                let _ = writeln!(md, "- {} {} {} {}: {reason}", r.suite.name(), r.scene, r.config.pipeline.name(), r.method());
            }
        }
        md.push('\n');
    }
    md
}

/// The paper's Table 1 layout: a row per scene, a column per pipeline (bvh frame time) and one for
/// deferred decals; the first row is each pipeline with no local lights or decals. The paper's
/// figures follow.
fn table_one(md: &mut String, table: &[&Measurement]) {
    let find = |scene: &str, pipeline: PipelineKind, method: &str| {
        table.iter().copied().find(|r| r.scene == scene && r.config.pipeline == pipeline && r.method() == method)
    };
    let _ = writeln!(md, "## Table 1: frame time (ms), acceleration structures (bvh)\n");
    let _ = writeln!(md, "| scene | forward | visbuffer | deferred | deferred decals |\n| --- | ---: | ---: | ---: | ---: |");
    let pipelines = [PipelineKind::Forward, PipelineKind::Visbuffer, PipelineKind::Deferred];
    let cells = |scene: &str, method: &str| pipelines.map(|p| frame_cell(find(scene, p, method))).join(" | ");
    let _ = writeln!(md, "| no local lights or decals | {} | — |", cells("base", "off"));
    for paper in PaperScene::ALL {
        if table.iter().any(|r| r.scene == paper.name()) {
            let deferred_decals =
                if paper.has_decals() { frame_cell(find(paper.name(), PipelineKind::Deferred, "deferred-decals")) } else { "—".into() };
            let _ = writeln!(md, "| {} | {} | {deferred_decals} |", paper.label(), cells(paper.name(), "bvh"));
        }
    }
    let _ = writeln!(md, "\nThe paper's figures (RTX 2070 Super, 1920×1080; without → with):\n");
    let _ = writeln!(md, "| scene | forward | visbuffer | deferred | deferred decals |\n| --- | ---: | ---: | ---: | ---: |");
    let paper_cell = |scene: &str, column: &str| {
        PAPER.iter().find(|(s, c, _, _)| *s == scene && *c == column).map_or("—".into(), |(_, _, without, with)| match without {
            Some(w) => format!("{w:.1} → {with:.1}"),
            None => format!("{with:.1}"),
        })
    };
    let row = |scene: &str| ["forward", "visbuffer", "deferred", "deferred decals"].map(|c| paper_cell(scene, c)).join(" | ");
    let _ = writeln!(md, "| 100k small decals | {} |", row("many-decals"));
    let _ = writeln!(md, "| 28k small lights | {} |\n", row("small-lights"));
}

/// Every configuration of the table: per-group medians, frame median and p95, CPU time.
fn matrix(md: &mut String, table: &[&Measurement]) {
    let _ = writeln!(md, "## Every pipeline with every method\n");
    let _ = writeln!(
        md,
        "| scene | pipeline | method | overlap | build | raster | deferred decals | shade | frame | p95 | CPU | frames |\n\
         | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    for r in table {
        let (p95, cpu, frames) = match &r.outcome {
            Outcome::Timed(t) => (format!("{:.3}", t.gpu_frame.p95), format!("{:.3}", t.cpu_frame.median), t.frames.to_string()),
            Outcome::OverCap(_) => ("—".into(), "—".into(), "1".into()),
            _ => ("—".into(), "—".into(), "0".into()),
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {p95} | {cpu} | {frames} |",
            r.scene,
            r.config.pipeline.name(),
            r.method(),
            r.overlap.map_or("—".into(), |o| format!("{o:.2}")),
            group_cell(r, PassGroup::Build),
            group_cell(r, PassGroup::Raster),
            group_cell(r, PassGroup::DeferredDecals),
            group_cell(r, PassGroup::Shade),
            frame_cell(Some(r)),
        );
    }
    md.push_str("\nbuild: per-frame GPU builds (clustered lists; the bvh of the table is built once: one placed group's cell lists on the GPU in the first frame, other groups' BVHs on the CPU at load); CPU: recording and submitting a frame.\n\n");
}

/// Per count: the mean overlap, then build, shade and frame medians of each method.
fn sweep_table(md: &mut String, sweep: SweepArg, rows: &[&Measurement]) {
    let what = if sweep == SweepArg::Lights { "lights" } else { "decals" };
    let build = match rows[0].config.decal_bvh_build {
        BvhBuild::CpuOnce => "built once",
        BvhBuild::GpuEveryFrame => "rebuilt on the GPU every frame",
    };
    let _ = writeln!(md, "## Sweep: {what} ({} pipeline; bvh {build})\n", rows[0].config.pipeline.name());
    let methods = ["bvh", "clustered", "brute"];
    let _ = writeln!(
        md,
        "| {what} | overlap | {} | bvh ÷ clustered |\n| ---: | ---: |{}",
        methods.map(|m| format!("{m} build | {m} shade | {m} frame")).join(" | "),
        " ---: |".repeat(methods.len() * 3 + 1)
    );
    let mut counts: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    counts.dedup();
    for count in counts {
        let at: Vec<&&Measurement> = rows.iter().filter(|r| r.scene == count).collect();
        let overlap = at.first().and_then(|r| r.overlap).map_or("—".into(), |o| format!("{o:.2}"));
        let cells = methods.map(|m| match at.iter().find(|r| r.method() == m) {
            Some(r) if r.outcome.is_timed() => {
                format!("{} | {} | {}", group_cell(r, PassGroup::Build), group_cell(r, PassGroup::Shade), frame_cell(Some(r)))
            }
            found => format!("— | — | {}", frame_cell(found.map(|r| **r))),
        });
        let frame = |method: &str| at.iter().find(|r| r.method() == method).and_then(|r| frame_ms(r));
        let ratio = ratio_cell(frame("bvh"), frame("clustered"));
        let _ = writeln!(md, "| {count} | {overlap} | {} | {ratio} |", cells.join(" | "));
    }
    md.push('\n');
}

fn frame_ms(r: &Measurement) -> Option<f64> {
    match &r.outcome {
        Outcome::Timed(t) => Some(t.gpu_frame.median),
        _ => None,
    }
}

/// `a ÷ b` to two places, bold where `a` is faster; — without both.
fn ratio_cell(a: Option<f64>, b: Option<f64>) -> String {
    match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => {
            let ratio = a / b;
            if ratio < 1.0 {
                format!("**{ratio:.2}**")
            } else {
                format!("{ratio:.2}")
            }
        }
        _ => "—".into(),
    }
}

/// Dense lights: per scene and pipeline, bvh built once and rebuilt every frame against clustered
/// shading, and what `auto` chose in each case, against the fastest of the explicit methods.
fn dense_table(md: &mut String, rows: &[&Measurement]) {
    let _ = writeln!(md, "## Dense lights: bvh against clustered shading, and auto\n");
    let _ = writeln!(
        md,
        "| scene | overlap | pipeline | bvh once | bvh every frame | clustered | bvh ÷ clustered (once) | bvh ÷ clustered (every frame) | auto once | auto every frame | auto ÷ best |\n\
         | --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | --- | --- | ---: |"
    );
    let mut scenes: Vec<&str> = rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        for pipeline in PipelineKind::ALL {
            let at: Vec<&&Measurement> = rows.iter().filter(|r| r.scene == scene && r.config.pipeline == pipeline).collect();
            if at.is_empty() {
                continue;
            }
            let find = |method: &str, build: BvhBuild| {
                at.iter().copied().copied().find(|r| r.method() == method && (method == "clustered" || r.config.light_bvh_build == build))
            };
            let ms = |m: Option<&Measurement>| m.and_then(frame_ms);
            let (bvh_once, bvh_every, clustered) =
                (find("bvh", BvhBuild::CpuOnce), find("bvh", BvhBuild::GpuEveryFrame), find("clustered", BvhBuild::CpuOnce));
            let (auto_once, auto_every) = (find("auto", BvhBuild::CpuOnce), find("auto", BvhBuild::GpuEveryFrame));
            let auto_cell = |r: Option<&Measurement>| match r.map(|r| &r.outcome) {
                Some(Outcome::Timed(t)) => format!("{:.3} ({})", t.gpu_frame.median, t.chosen.lights.method.name()),
                _ => frame_cell(r),
            };
            // auto against the fastest explicit method for the same build, the worse of the two builds.
            let best = |bvh: Option<f64>| [bvh, ms(clustered)].into_iter().flatten().reduce(f64::min);
            let worst_ratio = [(ms(auto_once), best(ms(bvh_once))), (ms(auto_every), best(ms(bvh_every)))]
                .into_iter()
                .filter_map(|(auto, best)| Some(auto? / best?))
                .reduce(f64::max);
            let overlap = at.first().and_then(|r| r.overlap).map_or("—".into(), |o| format!("{o:.2}"));
            let _ = writeln!(
                md,
                "| {scene} | {overlap} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                pipeline.name(),
                frame_cell(bvh_once),
                frame_cell(bvh_every),
                frame_cell(clustered),
                ratio_cell(ms(bvh_once), ms(clustered)),
                ratio_cell(ms(bvh_every), ms(clustered)),
                auto_cell(auto_once),
                auto_cell(auto_every),
                worst_ratio.map_or("—".into(), |r| format!("{r:.3}")),
            );
        }
    }
    md.push_str("\nonce: built once (one placed group's cell lists on the GPU in the first frame, or its BVH on the CPU at load where dense); every frame: rebuilt on the GPU each frame (cell lists or an LBVH), its build in the frame time; clustered lists are built every frame in both. auto ÷ best: auto's frame against the faster of bvh and clustered for the same build, the worse of the two builds.\n\n");
}
