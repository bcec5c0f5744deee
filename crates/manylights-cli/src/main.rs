//! `manylights`: render glTF and TOML scenes headless, print GPU information.

mod info;
mod render;
mod scene_args;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "manylights", version, about = "Many lights and decals through GPU-built acceleration structures")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to a PNG (and optionally EXR), with per-pass GPU timings.
    Render(render::RenderArgs),
    /// List GPU adapters, the one manylights would choose, its driver and the features it uses; then
    /// what the scene (with the same scene options as `render`) holds.
    Info(scene_args::SceneArgs),
}

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render::run(&args),
        Command::Info(args) => info::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
