//! `manylights`: render glTF and TOML scenes headless, benchmark them, print GPU information.

mod bench;
mod info;
mod light_error;
mod metrics;
mod particle_error;
mod progress;
mod render;
mod scene_args;
mod timing;
mod view;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "manylights", version, about = "Many lights and decals through GPU-built acceleration structures")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

// Every subcommand reads "-1" as a (bad) value, so clap names the flag and why it is refused instead of
// calling the number an unexpected argument.
#[derive(Subcommand)]
enum Command {
    /// Render a scene to a PNG (and optionally EXR), with per-pass GPU timings.
    #[command(allow_negative_numbers = true)]
    Render(render::RenderArgs),
    /// Measure the paper's Table 1 (6 large decals, 100 and 100k small decals, 28k small lights) in
    /// every pipeline with every method, and sweep lights and decals from 1k to 1M; writes Markdown,
    /// JSON, CSV and PNG plots.
    #[command(allow_negative_numbers = true)]
    Bench(bench::BenchArgs),
    /// Compare particle-grid settings (voxel size, filter, samples) with the exact method (the same
    /// particles as point lights through the BVH): error of the particles' light and PSNR.
    #[command(allow_negative_numbers = true)]
    ParticleError(particle_error::ParticleErrorArgs),
    /// Compare `--direct-lighting restir` with `reference` (every light with its own shadow ray) frame by
    /// frame, over a still camera and a moving one: FLIP, relative MSE, PSNR and flicker.
    #[command(allow_negative_numbers = true)]
    LightError(light_error::LightErrorArgs),
    /// List GPU adapters, the one manylights would choose, its driver and the features it uses; then
    /// what the scene (with the same scene options as `render`) holds.
    #[command(allow_negative_numbers = true)]
    Info(scene_args::SceneArgs),
    /// Open a window on a scene: fly through it (WASD, Q/E, right mouse button to look), switch
    /// pipeline, methods, ray-traced and post effects live, and watch per-pass GPU timings.
    #[command(allow_negative_numbers = true)]
    View(view::ViewArgs),
}

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render::run(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Info(args) => info::run(&args),
        Command::ParticleError(args) => particle_error::run(&args),
        Command::LightError(args) => light_error::run(&args),
        Command::View(args) => view::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
