//! The `niebla` command: render scenes, describe them, and measure the renderer.

mod bench;
mod bench_trackers;
mod render_cmd;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// niebla renders participating media (fog, smoke, clouds, fire) with
/// physically based methods.
#[derive(Parser, Debug)]
#[command(name = "niebla", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene file (or the built-in default scene) to EXR and/or PNG.
    Render(render_cmd::RenderArgs),
    /// Print what a scene holds: camera, media, shapes, lights, render settings.
    Info {
        /// Scene file (JSON, version 1). Without it, describes the built-in default scene.
        scene: Option<PathBuf>,
    },
    /// Measure the renderer and print figures.
    #[command(subcommand)]
    Bench(BenchCommand),
}

#[derive(Subcommand, Debug)]
enum BenchCommand {
    /// Samples per second of `single` in each sampling mode and the time to
    /// reach a relative MSE of 1e-2 against a high-spp reference.
    Single(bench::BenchArgs),
    /// Variance x time of the transmittance estimators on a grid medium, with
    /// the majorant grid and with one global majorant.
    Trackers(bench_trackers::TrackerBenchArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render_cmd::run(&args),
        Command::Info { scene } => render_cmd::info(scene.as_deref()),
        Command::Bench(BenchCommand::Single(args)) => bench::run(&args),
        Command::Bench(BenchCommand::Trackers(args)) => bench_trackers::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::FAILURE
        }
    }
}
