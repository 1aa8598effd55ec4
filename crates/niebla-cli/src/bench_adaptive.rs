//! `niebla bench adaptive`: samples and seconds to reach a relative MSE
//! (`--target`) with plain rendering (independent sampler) and with adaptive
//! sampling (`niebla::adaptive`) at each `--thresholds` value, against a
//! long plain reference, and with the cost rule (`--adaptive-cost`) at each
//! `--cost-thresholds` value, next to the most any allocation of samples
//! over the pixels could gain in samples and in time
//! (`niebla::adaptive::allocation_bound`, `cost_allocation_bound`). It also
//! fits the measured time per sample against the random dimensions a sample
//! draws (the cost proxy of the cost rule, `niebla::adaptive::COST_OFFSET`).
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
use niebla::adaptive::pilot::{
    allocate, pilot_allocation, render_pilot, smooth, weights as pilot_weights, PilotOptions,
};
use niebla::adaptive::{
    allocation_bound, cost_allocation_bound, per_sample_relative_variance, render_adaptive, AdaptiveOptions, StopRule,
    COST_OFFSET,
};
use niebla::aov::{variance_of_mean, AovSet};
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
    /// Thresholds measured with the cost rule (`render --adaptive-cost`),
    /// comma separated (default: none).
    #[arg(long, value_delimiter = ',')]
    pub cost_thresholds: Vec<f32>,
    /// Pilot sizes (samples per pixel) measured with pilot allocation
    /// (`render --adaptive-pilot --pilot-spp N`), comma separated (default:
    /// none). The sweep's `--spp` is then the mean of pass 2; the pilot's
    /// samples, seconds and dimensions count in the figures.
    #[arg(long, value_delimiter = ',')]
    pub pilot_spp: Vec<u32>,
    /// Samplers of the pilot-allocated renders (and, for `sobol`, a plain
    /// Sobol sweep too), comma separated.
    #[arg(long, value_delimiter = ',', default_value = "independent")]
    pub pilot_samplers: Vec<String>,
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
    time_bound: f64,
    cells: Vec<String>,
    /// Random dimensions per pixel to the target: plain, then each threshold.
    work_cells: Vec<String>,
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
    if let Some(t) = args.cost_thresholds.iter().find(|t| !(**t > 0.0 && **t < 1.0)) {
        return Err(CliError::invalid_option("--cost-thresholds", format!("each must lie in (0, 1), got {t}")));
    }
    if let Some(k) = args.pilot_spp.iter().find(|&&k| k < 2) {
        return Err(CliError::invalid_option("--pilot-spp", format!("each must be at least 2, got {k}")));
    }
    let mut pilot_samplers = Vec::new();
    for name in &args.pilot_samplers {
        pilot_samplers.push(SamplerKind::parse(name).ok_or_else(|| {
            CliError::invalid_option(
                "--pilot-samplers",
                format!("unknown sampler {name:?}, expected one of {}", SamplerKind::NAMES.join(", ")),
            )
        })?);
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
        let sampled_options =
            |spp: u32, seed: u64, sampler: SamplerKind| RenderOptions { spp, seed, first_sample: 0, threads, sampler };
        let plain_options = |spp: u32, seed: u64| sampled_options(spp, seed, SamplerKind::Independent);
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
        // Per-pixel variance and random dimensions drawn, from the
        // segment sums of adaptive rendering (7 sums per pixel: R, G, B,
        // their squares, dimensions).
        let n = args.variance_spp as u64;
        let pixels = (scene.camera.width * scene.camera.height) as usize;
        let all: Vec<u32> = (0..pixels as u32).collect();
        let pool = match threads {
            Some(t) => Some(
                rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build()
                    .map_err(|e| CliError::invalid_option("--threads", format!("cannot start {t} threads: {e}")))?,
            ),
            None => None,
        };
        let segment_sums = |list: &[u32]| {
            let render = || prepared.render_segment_sums(&scene, 3, AovSet::EMPTY, list, &[(0, n)], None);
            match &pool {
                Some(pool) => pool.install(render),
                None => render(),
            }
        };
        let sums = segment_sums(&all)?;
        let variance = |i: usize| {
            let cell = &sums[i * 7..][..7];
            niebla::color::Rgb::new(
                variance_of_mean(cell[0], cell[3], n),
                variance_of_mean(cell[1], cell[4], n),
                variance_of_mean(cell[2], cell[5], n),
            )
        };
        let v = per_sample_relative_variance(&reference, n, variance);
        let dimensions: Vec<f64> = (0..pixels).map(|i| sums[i * 7 + 6] as f64 / n as f64).collect();
        let cost: Vec<f64> = dimensions.iter().map(|d| d + COST_OFFSET).collect();
        let bound = allocation_bound(&v);
        let time_bound = cost_allocation_bound(&v, &cost);
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
        println!(
            "  cost per sample (random dimensions + {COST_OFFSET}): mean {:.1}, max {:.1}; time allocation bound {time_bound:.2}x",
            cost.iter().sum::<f64>() / pixels as f64,
            cost.iter().copied().fold(0.0, f64::max)
        );
        // Time against dimensions: the pixels in 8 groups of equal size by
        // their dimensions per sample, each group rendered again (same
        // samples) and timed; least squares of seconds per sample on mean
        // dimensions per sample over the groups.
        let mut order = all.clone();
        order.sort_by(|&a, &b| dimensions[a as usize].total_cmp(&dimensions[b as usize]));
        let groups = 8.min(pixels);
        let mut fit = Vec::new();
        for g in 0..groups {
            let list = &order[g * pixels / groups..(g + 1) * pixels / groups];
            if list.is_empty() {
                continue;
            }
            let watch = Stopwatch::start(args.clock)?;
            segment_sums(list)?;
            let seconds = watch.seconds()?;
            let mean_dimensions = list.iter().map(|&i| dimensions[i as usize]).sum::<f64>() / list.len() as f64;
            fit.push((mean_dimensions, seconds / (list.len() as f64 * n as f64)));
        }
        let m = fit.len() as f64;
        let (mx, my) = (fit.iter().map(|p| p.0).sum::<f64>() / m, fit.iter().map(|p| p.1).sum::<f64>() / m);
        let sxx = fit.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
        let sxy = fit.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>();
        let syy = fit.iter().map(|p| (p.1 - my).powi(2)).sum::<f64>();
        let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
        let intercept = my - slope * mx;
        let r = if sxx > 0.0 && syy > 0.0 { sxy / (sxx * syy).sqrt() } else { 0.0 };
        println!(
            "  time per sample = {:.3} us + {:.4} us x dimensions (8 groups, r = {r:.3}): offset {:.1} dimensions; groups (dimensions, us): {}",
            intercept * 1e6,
            slope * 1e6,
            if slope > 0.0 { intercept / slope } else { f64::NAN },
            fit.iter().map(|(d, t)| format!("({d:.1}, {:.3})", t * 1e6)).collect::<Vec<_>>().join(" ")
        );
        // The pilots' allocations judged by the long render's v and c: the
        // time gain over a uniform allocation for equal relative MSE,
        // `mean(v) mean(c) / (mean(v / n) mean(c n))` (n normalised to mean 1;
        // the time bound for n ~ sqrt(v / c)), and in parentheses with the
        // pilot's cost, `mean(c)` per pilot sample, at the plain render's
        // spp to the target; for smoothing radii 0 to 3.
        let mean_v = v.iter().sum::<f64>() / pixels as f64;
        let mean_c = cost.iter().sum::<f64>() / pixels as f64;
        let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
        for &k in &args.pilot_spp {
            let mut estimates = Vec::new();
            for seed in 0..args.seeds as u64 {
                let mut options = PilotOptions::new(256, 11 + seed, SamplerKind::Independent);
                (options.pilot_spp, options.threads) = (k, threads);
                let allocation = pilot_allocation(&scene, &settings, &options, None)?;
                estimates.push((allocation.variance, allocation.cost));
            }
            let mut line = String::new();
            for radius in 0..=3usize {
                let (mut gains, mut with_pilot) = (0.0, 0.0);
                for (pv, pc) in &estimates {
                    let weights = pilot_weights(&smooth(pv, w, h, radius), &smooth(pc, w, h, radius));
                    let (least, most) = PilotOptions::new(256, 0, SamplerKind::Independent).bounds();
                    let n: Vec<f64> = allocate(&weights, 256, least, most).iter().map(|&n| n as f64 / 256.0).collect();
                    let error = v.iter().zip(&n).map(|(v, n)| v / n).sum::<f64>() / pixels as f64;
                    let time = cost.iter().zip(&n).map(|(c, n)| c * n).sum::<f64>() / pixels as f64;
                    gains += mean_v * mean_c / (error * time);
                    // To the target: plain takes mean_v / target samples,
                    // the allocation error / target (of mean 1) plus the
                    // pilot's k.
                    let plain = mean_v / args.target;
                    with_pilot += plain * mean_c / (error / args.target * time + k as f64 * mean_c);
                }
                let m = estimates.len() as f64;
                line += &format!(" {radius}: {:.2}x ({:.2}x)", gains / m, with_pilot / m);
            }
            println!("  pilot {k} spp, allocation gain in time (with the pilot's cost) by smoothing radius{line}");
        }
        let seeds = args.seeds as u64;
        let (mut spp_points, mut time_points, mut work_points) = (Vec::new(), Vec::new(), Vec::new());
        for &spp in &spp_list {
            let (mut error, mut time) = (0.0, 0.0);
            for seed in 0..seeds {
                let watch = Stopwatch::start(args.clock)?;
                let image = prepared.render(&scene, &plain_options(spp, 11 + seed), &|_, _| {}, None)?;
                time += watch.seconds()?;
                error += image.relative_mse(&reference);
            }
            let (error, time) = (error / seeds as f64, time / seeds as f64);
            // Expected dimensions of a plain render: spp times those of
            // the variance pass per sample.
            let work = spp as f64 * dimensions.iter().sum::<f64>() / pixels as f64;
            println!(
                "  plain          {spp:>6} spp: rel MSE {error:.3e} in {time:.3} s, {work:.1} dimensions per pixel"
            );
            spp_points.push((spp as f64, error));
            time_points.push((time, error));
            work_points.push((work, error));
        }
        let mut cells = vec![to_reach(&spp_points, args.target, 1), to_reach(&time_points, args.target, 3)];
        let mut work_cells = vec![to_reach(&work_points, args.target, 0)];
        let runs = args.thresholds.iter().map(|&t| (StopRule::Error, t));
        for (rule, threshold) in runs.chain(args.cost_thresholds.iter().map(|&t| (StopRule::Cost, t))) {
            let label = if rule == StopRule::Cost { "cost" } else { "adaptive" };
            let (mut spp_points, mut time_points, mut work_points) = (Vec::new(), Vec::new(), Vec::new());
            for &spp in &spp_list {
                let (mut error, mut time, mut taken, mut work) = (0.0, 0.0, 0.0, 0.0);
                for seed in 0..seeds {
                    let options =
                        AdaptiveOptions { spp, threshold, seed: 11 + seed, threads, layers: AovSet::EMPTY, rule };
                    let watch = Stopwatch::start(args.clock)?;
                    let result = render_adaptive(&scene, &settings, &options, &|_, _| {}, None)?;
                    time += watch.seconds()?;
                    error += result.image.relative_mse(&reference);
                    taken += result.spp.iter().sum::<u64>() as f64 / result.spp.len() as f64;
                    work += result.dimensions.iter().sum::<u64>() as f64 / result.spp.len() as f64;
                }
                let (error, time, taken) = (error / seeds as f64, time / seeds as f64, taken / seeds as f64);
                let work = work / seeds as f64;
                println!(
                    "  {label:<8} {threshold:<5} {spp:>6} spp: rel MSE {error:.3e} in {time:.3} s, {taken:.2} spp taken, {work:.1} dimensions per pixel"
                );
                spp_points.push((taken, error));
                time_points.push((time, error));
                work_points.push((work, error));
            }
            cells.push(to_reach(&spp_points, args.target, 1));
            cells.push(to_reach(&time_points, args.target, 3));
            work_cells.push(to_reach(&work_points, args.target, 0));
        }
        for &sampler in pilot_samplers.iter().filter(|&&s| s != SamplerKind::Independent) {
            // The plain sweep with this sampler, to compare the pilot's gain with.
            let (mut spp_points, mut time_points, mut work_points) = (Vec::new(), Vec::new(), Vec::new());
            for &spp in &spp_list {
                let (mut error, mut time) = (0.0, 0.0);
                for seed in 0..seeds {
                    let watch = Stopwatch::start(args.clock)?;
                    let image = prepared.render(&scene, &sampled_options(spp, 11 + seed, sampler), &|_, _| {}, None)?;
                    time += watch.seconds()?;
                    error += image.relative_mse(&reference);
                }
                let (error, time) = (error / seeds as f64, time / seeds as f64);
                let work = spp as f64 * dimensions.iter().sum::<f64>() / pixels as f64;
                println!(
                    "  plain {:<8} {spp:>6} spp: rel MSE {error:.3e} in {time:.3} s, {work:.1} dimensions per pixel",
                    sampler.name()
                );
                spp_points.push((spp as f64, error));
                time_points.push((time, error));
                work_points.push((work, error));
            }
            cells.push(to_reach(&spp_points, args.target, 1));
            cells.push(to_reach(&time_points, args.target, 3));
            work_cells.push(to_reach(&work_points, args.target, 0));
        }
        for &k in &args.pilot_spp {
            for &sampler in &pilot_samplers {
                let (mut spp_points, mut time_points, mut work_points) = (Vec::new(), Vec::new(), Vec::new());
                for &spp in &spp_list {
                    let (mut error, mut time, mut work) = (0.0, 0.0, 0.0);
                    for seed in 0..seeds {
                        let mut options = PilotOptions::new(spp, 11 + seed, sampler);
                        (options.pilot_spp, options.threads) = (k, threads);
                        let watch = Stopwatch::start(args.clock)?;
                        let result = render_pilot(&scene, &settings, &options, None)?;
                        time += watch.seconds()?;
                        error += result.image.relative_mse(&reference);
                        work += result.dimensions.iter().sum::<u64>() as f64 / result.spp.len() as f64;
                    }
                    let (error, time, work) = (error / seeds as f64, time / seeds as f64, work / seeds as f64);
                    let taken = (spp + k) as f64;
                    println!(
                        "  pilot {k} {:<11} {spp:>6} spp: rel MSE {error:.3e} in {time:.3} s, {taken} spp with the pilot's, {work:.1} dimensions per pixel",
                        sampler.name()
                    );
                    spp_points.push((taken, error));
                    time_points.push((time, error));
                    work_points.push((work, error));
                }
                cells.push(to_reach(&spp_points, args.target, 1));
                cells.push(to_reach(&time_points, args.target, 3));
                work_cells.push(to_reach(&work_points, args.target, 0));
            }
        }
        rows.push(Row { scene: stem, bound, time_bound, cells, work_cells });
    }
    println!();
    println!("samples per pixel (spp) and seconds (s) to relative MSE {:.1e}:", args.target);
    let mut header = format!("{:<16} {:>7} {:>10} {:>10}", "scene", "bound", "plain_spp", "plain_s");
    for t in &args.thresholds {
        header += &format!(" {:>10} {:>10}", format!("a{t}_spp"), format!("a{t}_s"));
    }
    for t in &args.cost_thresholds {
        header += &format!(" {:>10} {:>10}", format!("c{t}_spp"), format!("c{t}_s"));
    }
    let sobol_plain: Vec<&SamplerKind> = pilot_samplers.iter().filter(|&&s| s != SamplerKind::Independent).collect();
    for s in &sobol_plain {
        header += &format!(" {:>10} {:>10}", format!("{}_spp", s.name()), format!("{}_s", s.name()));
    }
    let pilot_labels: Vec<String> = args
        .pilot_spp
        .iter()
        .flat_map(|k| pilot_samplers.iter().map(move |s| format!("p{k}{}", &s.name()[..1])))
        .collect();
    for label in &pilot_labels {
        header += &format!(" {:>10} {:>10}", format!("{label}_spp"), format!("{label}_s"));
    }
    println!("{header}");
    for row in &rows {
        let mut line = format!("{:<16} {:>7}", row.scene, format!("{:.2}x", row.bound));
        for cell in &row.cells {
            line += &format!(" {cell:>10}");
        }
        println!("{line}");
    }
    if !args.cost_thresholds.is_empty() || !args.pilot_spp.is_empty() {
        println!();
        println!(
            "random dimensions drawn per pixel (the cost proxy, about proportional to time) to relative MSE {:.1e}:",
            args.target
        );
        let mut header = format!("{:<16} {:>7} {:>10}", "scene", "t_bound", "plain_dim");
        for t in &args.thresholds {
            header += &format!(" {:>10}", format!("a{t}_dim"));
        }
        for t in &args.cost_thresholds {
            header += &format!(" {:>10}", format!("c{t}_dim"));
        }
        for s in &sobol_plain {
            header += &format!(" {:>10}", format!("{}_dim", s.name()));
        }
        for label in &pilot_labels {
            header += &format!(" {:>10}", format!("{label}_dim"));
        }
        println!("{header}");
        for row in &rows {
            let mut line = format!("{:<16} {:>7}", row.scene, format!("{:.2}x", row.time_bound));
            for cell in &row.work_cells {
                line += &format!(" {cell:>10}");
            }
            println!("{line}");
        }
    }
    Ok(())
}
