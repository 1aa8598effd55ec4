//! The `niebla` command: render scenes, describe them, and measure the renderer.

mod adaptive_cmd;
mod aov_flags;
mod bench;
mod bench_adaptive;
mod bench_emission;
mod bench_geometry;
mod bench_interactive;
mod bench_paths;
mod bench_photons;
mod bench_photons_time;
mod bench_sampler;
mod bench_trackers;
mod compare;
mod convert_cmd;
mod error;
mod flags;
mod info_cmd;
mod info_vdb;
mod load;
mod merge_cmd;
mod preview_cmd;
mod render_cmd;
mod render_frames;
mod view_cmd;

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
    /// Render a scene with several integrators under one time budget and write an HTML report.
    Compare(compare::CompareArgs),
    /// Add up renders of disjoint sample ranges of one scene (EXR outputs of
    /// `niebla render --first-sample N --spp M`) into one EXR.
    Merge(merge_cmd::MergeArgs),
    /// Print what a scene holds: camera, media, shapes, lights, render settings;
    /// or, for a `.vdb` file, every grid it holds.
    Info {
        /// Scene file (JSON, version 1, or Mitsuba 3 XML) or OpenVDB file
        /// (`.vdb`). Without it, describes the built-in default scene.
        scene: Option<PathBuf>,
        #[command(flatten)]
        define: flags::DefineFlag,
    },
    /// Convert a Mitsuba 3 XML scene into the niebla scene (JSON) that renders the same.
    Convert(convert_cmd::ConvertArgs),
    /// Render frames repeatedly with an interactive method, report frames/s,
    /// and re-render when the scene file changes.
    Preview(preview_cmd::PreviewArgs),
    /// Serve a live, editable, progressive view of a scene to the browser.
    View(view_cmd::ViewArgs),
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
    /// Frames/s, precomputation and error against volpath of the interactive methods.
    Interactive(bench_interactive::InteractiveBenchArgs),
    /// Photons traced/s, gather queries/s, time of photon, ppm and volpath to a relative MSE of 1e-2.
    Photons(bench_photons::PhotonBenchArgs),
    /// Hierarchy build time and memory, closest-hit and any-hit rays/s on
    /// generated meshes of 10^4 to 10^7 triangles.
    Geometry(bench_geometry::GeometryBenchArgs),
    /// Relative MSE x time of volpath with and without light sampling of
    /// emissive media, on the pixels lit by the fire and those that see it.
    Emission(bench_emission::EmissionBenchArgs),
    /// Relative MSE at 16, 64, 256 spp of the scene's integrator with each
    /// sampler kind (independent, Sobol in draw order, Sobol laid out).
    Sampler(bench_sampler::SamplerBenchArgs),
    /// Samples and seconds to a relative MSE of 1e-2, plain and with
    /// adaptive sampling at each threshold, next to the most any sample
    /// allocation could gain.
    Adaptive(bench_adaptive::AdaptiveBenchArgs),
    /// Samples per second (wall and CPU) of the scene's integrator over
    /// repeated renders, with the image's mean and a hash of its pixels.
    Paths(bench_paths::PathsBenchArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render_cmd::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Merge(args) => merge_cmd::run(&args),
        Command::Info { scene, define } => info_cmd::run(scene.as_deref(), &define.define),
        Command::Convert(args) => convert_cmd::run(&args),
        Command::Bench(BenchCommand::Single(args)) => bench::run(&args),
        Command::Bench(BenchCommand::Trackers(args)) => bench_trackers::run(&args),
        Command::Preview(args) => preview_cmd::run(&args),
        Command::View(args) => view_cmd::run(&args),
        Command::Bench(BenchCommand::Interactive(args)) => bench_interactive::run(&args),
        Command::Bench(BenchCommand::Photons(args)) => bench_photons::run(&args),
        Command::Bench(BenchCommand::Geometry(args)) => bench_geometry::run(&args),
        Command::Bench(BenchCommand::Emission(args)) => bench_emission::run(&args),
        Command::Bench(BenchCommand::Sampler(args)) => bench_sampler::run(&args),
        Command::Bench(BenchCommand::Adaptive(args)) => bench_adaptive::run(&args),
        Command::Bench(BenchCommand::Paths(args)) => bench_paths::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::from(error.exit_code())
        }
    }
}
