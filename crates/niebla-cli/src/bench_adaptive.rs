//! `niebla bench adaptive`: samples and seconds to reach a relative MSE
//! (`--target`) with plain rendering (independent sampler) and with adaptive
//! sampling (`niebla::adaptive`) at each `--thresholds` value, against a
//! long plain reference, next to the most any allocation of samples over the
//! pixels could gain (`niebla::adaptive::allocation_bound`).
//!
//! Each scene renders with its own integrator at `--width` (height keeps
//! the aspect ratio). Plain renders sweep `--spp`; adaptive renders sweep
//! the same schedule lengths and are placed at the mean samples per pixel
//! they took. Each point is the mean relative MSE and time over `--seeds`
//! renders; the samples and seconds to the target are interpolated on
//! log-log axes between the two bracketing points (`-`: not reached; `<x`:
//! already below the target at the first point).

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use niebla::adaptive::{allocation_bound, per_sample_relative_variance, render_adaptive, AdaptiveOptions};
use niebla::aov::{Aov, AovSet};
use niebla::integrator::PreparedIntegrator;
use niebla::render::RenderOptions;
use niebla::sampling::SamplerKind;

use crate::bench::time_to_reach;
use crate::error::CliError;
use crate::flags::ThreadsFlag;

/// Options of `niebla bench adaptive`.
#[derive(Args, Debug)]
pub struct AdaptiveBenchArgs {
    /// Scenes to measure, each with its own integrator (default:
    /// bench/scenes/fog_spot.json, fog_point.json and milk_cube.json).
    pub scenes: Vec<PathBuf>,
    /// Image width used for the measurements (height keeps the aspect ratio).
    #[arg(long, default_value_t = 48)]
    pub width: u32,
    /// Samples per pixel of the reference (plain, independent sampler).
    #[arg(long, default_value_t = 4096)]
    pub reference_spp: u32,
    /// Samples per pixel of the render whose per-pixel variance gives the
    /// allocation bound.
    #[arg(long, default_value_t = 256)]
    pub variance_spp: u32,
    /// Sample counts swept (plain spp; adaptive schedule length), comma separated.
    #[arg(long, value_delimiter = ',', default_value = "8,16,32,64,128,256,512")]
    pub spp: Vec<u32>,
    /// Adaptive thresholds measured (relative error per pixel, in (0, 1)), comma separated.
    #[arg(long, value_delimiter = ',', default_value = "0.1,0.07,0.05")]
    pub thresholds: Vec<f32>,
    /// Target relative MSE.
    #[arg(long, default_value_t = 1e-2)]
    pub target: f64,
    /// Renders (seeds) averaged per point.
    #[arg(long, default_value_t = 1)]
    pub seeds: u32,
    /// Seconds measured: `wall` (elapsed) or `cpu` (the process's CPU time,
    /// user + system, all threads, from /proc/self/stat in 10 ms ticks;
    /// Linux only): on a machine shared with other work, CPU time is what
    /// the render itself spent.
    #[arg(long, value_enum, default_value_t = Clock::Wall)]
    pub clock: Clock,
    /// `--threads`: worker threads.
    #[command(flatten)]
    pub threads: ThreadsFlag,
}

/// What `niebla bench adaptive` measures seconds with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Clock {
    /// Elapsed time.
    Wall,
    /// CPU time of the process (all threads, user + system).
    Cpu,
}

/// CPU seconds (user + system, all threads, exited ones included) the
/// process has spent: fields 14 and 15 of /proc/self/stat, in ticks of
/// 1/100 s (Linux's USER_HZ).
pub(crate) fn process_cpu_seconds() -> Result<f64, CliError> {
    let fail = |why: &str| CliError::invalid_option("--clock", format!("cpu: cannot read /proc/self/stat ({why})"));
    let stat = std::fs::read_to_string("/proc/self/stat").map_err(|e| fail(&e.to_string()))?;
    // The command name (field 2) is in parentheses and may hold spaces.
    let rest = stat.rsplit_once(')').ok_or_else(|| fail("no command name"))?.1;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let tick = |i: usize| fields.get(i).and_then(|f| f.parse::<u64>().ok()).ok_or_else(|| fail("short line"));
    // `rest` starts at field 3, so fields 14 and 15 are at 11 and 12.
    Ok((tick(11)? + tick(12)?) as f64 / 100.0)
}

/// A stopwatch on `clock`.
struct Stopwatch {
    clock: Clock,
    wall: Instant,
    cpu: f64,
}

impl Stopwatch {
    fn start(clock: Clock) -> Result<Stopwatch, CliError> {
        let cpu = if clock == Clock::Cpu { process_cpu_seconds()? } else { 0.0 };
        Ok(Stopwatch { clock, wall: Instant::now(), cpu })
    }

    /// Seconds since [`Stopwatch::start`].
    fn seconds(&self) -> Result<f64, CliError> {
        Ok(match self.clock {
            Clock::Wall => self.wall.elapsed().as_secs_f64(),
            Clock::Cpu => process_cpu_seconds()? - self.cpu,
        })
    }
}

/// Samples (or seconds) at which a sweep of `(x, rel MSE)` points crosses
/// `target`, formatted: `-` if never, `<x` if the first point is below it.
fn to_reach(points: &[(f64, f64)], target: f64, precision: usize) -> String {
    match time_to_reach(points, target) {
        None => "-".to_string(),
        Some(x) if points[0].1 < target => format!("<{x:.precision$}"),
        Some(x) => format!("{x:.precision$}"),
    }
}

/// One row of the final table.
struct Row {
    scene: String,
    bound: f64,
    cells: Vec<String>,
}

/// `niebla bench adaptive`.
pub fn run(args: &AdaptiveBenchArgs) -> Result<(), CliError> {
    let threads = args.threads.get()?;
    if args.width == 0 || args.width > 16384 {
        return Err(CliError::invalid_option("--width", "must be between 1 and 16384"));
    }
    if args.reference_spp == 0
        || args.variance_spp < 2
        || args.seeds == 0
        || args.spp.is_empty()
        || args.spp.contains(&0)
    {
        return Err(CliError::invalid_option(
            "--reference-spp, --variance-spp, --seeds, --spp",
            "must be at least 1 (--variance-spp at least 2, --spp not empty)",
        ));
    }
    if let Some(t) = args.thresholds.iter().find(|t| !(**t > 0.0 && **t < 1.0)) {
        return Err(CliError::invalid_option("--thresholds", format!("each must lie in (0, 1), got {t}")));
    }
    if !(args.target > 0.0 && args.target.is_finite()) {
        return Err(CliError::invalid_option("--target", "must be a positive number"));
    }
    let scenes: Vec<PathBuf> = if args.scenes.is_empty() {
        ["fog_spot", "fog_point", "milk_cube"]
            .iter()
            .map(|n| Path::new("bench/scenes").join(format!("{n}.json")))
            .collect()
    } else {
        args.scenes.clone()
    };
    let mut spp_list = args.spp.clone();
    spp_list.sort_unstable();
    spp_list.dedup();
    println!(
        "bench adaptive: width {}, threads {}, reference {} spp, target relative MSE {:.1e}, {} seed(s) per point, {} seconds",
        args.width,
        threads.map_or("all".to_string(), |t| t.to_string()),
        args.reference_spp,
        args.target,
        args.seeds,
        if args.clock == Clock::Cpu { "CPU" } else { "wall" }
    );
    let mut rows = Vec::new();
    for path in &scenes {
        let (built, stem) = crate::load::load(Some(path))?;
        let settings = built.settings.integrator;
        let mut scene = built.scene;
        let aspect = scene.camera.height as f64 / scene.camera.width as f64;
        scene.camera.width = args.width;
        scene.camera.height = ((args.width as f64 * aspect).round() as u32).max(1);
        let prepared = PreparedIntegrator::new(&scene, &settings);
        let plain_options = |spp: u32, seed: u64| RenderOptions {
            spp,
            seed,
            first_sample: 0,
            threads,
            sampler: SamplerKind::Independent,
        };
        let start = Instant::now();
        let reference = prepared.render(&scene, &plain_options(args.reference_spp, 1), &|_, _| {}, None)?;
        println!(
            "{stem} ({}x{}, {}): reference {} spp in {:.2} s",
            scene.camera.width,
            scene.camera.height,
            settings.key(),
            args.reference_spp,
            start.elapsed().as_secs_f64()
        );
        let set = AovSet::EMPTY.with(Aov::Variance);
        let n = args.variance_spp as u64;
        let (sums, layers) =
            prepared.render_aov_sums(&scene, &plain_options(args.variance_spp, 3), set, &|_, _| {}, None)?;
        let layers = layers.layers(&sums, n);
        let variance = layers.get(Aov::Variance).expect("the variance layer was asked for");
        let v = per_sample_relative_variance(&reference, n, |i| variance.rgb(i));
        let bound = allocation_bound(&v);
        let mut sorted = v.clone();
        sorted.sort_by(f64::total_cmp);
        let q = |f: f64| sorted[((sorted.len() - 1) as f64 * f) as usize];
        println!(
            "  per-sample relative variance ({} spp): quantiles 10% {:.3} 50% {:.3} 90% {:.3}; allocation bound {bound:.2}x",
            args.variance_spp,
            q(0.1),
            q(0.5),
            q(0.9)
        );
        let seeds = args.seeds as u64;
        let (mut spp_points, mut time_points) = (Vec::new(), Vec::new());
        for &spp in &spp_list {
            let (mut error, mut time) = (0.0, 0.0);
            for seed in 0..seeds {
                let watch = Stopwatch::start(args.clock)?;
                let image = prepared.render(&scene, &plain_options(spp, 11 + seed), &|_, _| {}, None)?;
                time += watch.seconds()?;
                error += image.relative_mse(&reference);
            }
            let (error, time) = (error / seeds as f64, time / seeds as f64);
            println!("  plain          {spp:>6} spp: rel MSE {error:.3e} in {time:.3} s");
            spp_points.push((spp as f64, error));
            time_points.push((time, error));
        }
        let mut cells = vec![to_reach(&spp_points, args.target, 1), to_reach(&time_points, args.target, 3)];
        for &threshold in &args.thresholds {
            let (mut spp_points, mut time_points) = (Vec::new(), Vec::new());
            for &spp in &spp_list {
                let (mut error, mut time, mut taken) = (0.0, 0.0, 0.0);
                for seed in 0..seeds {
                    let options = AdaptiveOptions { spp, threshold, seed: 11 + seed, threads, layers: AovSet::EMPTY };
                    let watch = Stopwatch::start(args.clock)?;
                    let result = render_adaptive(&scene, &settings, &options, &|_, _| {}, None)?;
                    time += watch.seconds()?;
                    error += result.image.relative_mse(&reference);
                    taken += result.spp.iter().sum::<u64>() as f64 / result.spp.len() as f64;
                }
                let (error, time, taken) = (error / seeds as f64, time / seeds as f64, taken / seeds as f64);
                println!(
                    "  adaptive {threshold:<5} {spp:>6} spp: rel MSE {error:.3e} in {time:.3} s, {taken:.2} spp taken"
                );
                spp_points.push((taken, error));
                time_points.push((time, error));
            }
            cells.push(to_reach(&spp_points, args.target, 1));
            cells.push(to_reach(&time_points, args.target, 3));
        }
        rows.push(Row { scene: stem, bound, cells });
    }
    println!();
    println!("samples per pixel (spp) and seconds (s) to relative MSE {:.1e}:", args.target);
    let mut header = format!("{:<16} {:>7} {:>10} {:>10}", "scene", "bound", "plain_spp", "plain_s");
    for t in &args.thresholds {
        header += &format!(" {:>10} {:>10}", format!("a{t}_spp"), format!("a{t}_s"));
    }
    println!("{header}");
    for row in &rows {
        let mut line = format!("{:<16} {:>7}", row.scene, format!("{:.2}x", row.bound));
        for cell in &row.cells {
            line += &format!(" {cell:>10}");
        }
        println!("{line}");
    }
    Ok(())
}
