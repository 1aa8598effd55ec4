//! `niebla bench paths`: samples per second of the scene's own integrator,
//! repeated, with the spread, and a fingerprint of the image (its mean and a
//! hash of its pixel bits) so that an optimisation can show both its speed
//! and that the image did not change.
//!
//! Speed is given per CPU second of the process (user + system time of all
//! its threads, from `/proc/self/stat`, where available) as well as per wall
//! second: on a machine loaded by other work, CPU time is the steadier
//! figure.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use niebla::render::{render, RenderOptions};
use niebla::sampling::SamplerKind;

use crate::error::CliError;
use crate::flags::ThreadsFlag;

/// Options of `niebla bench paths`.
#[derive(Args, Debug)]
pub struct PathsBenchArgs {
    /// Scene to measure (its own integrator, sampler and seed).
    pub scene: PathBuf,
    /// Image width used for the measurements (height keeps the aspect ratio).
    #[arg(long, default_value_t = 64)]
    pub width: u32,
    /// Samples per pixel of each render.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
    /// Timed renders (after one untimed warm-up render).
    #[arg(long, default_value_t = 5)]
    pub repeat: u32,
    /// Sampler kind (default: the scene's).
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(SamplerKind::NAMES))]
    pub sampler: Option<String>,
    /// `--threads`: worker threads.
    #[command(flatten)]
    pub threads: ThreadsFlag,
}

/// User + system CPU seconds of this process so far (all threads), or
/// `None` where `/proc/self/stat` cannot be read.
fn process_cpu_seconds() -> Option<f64> {
    crate::bench_adaptive::process_cpu_seconds().ok()
}

/// FNV-1a over the bits of every pixel channel: equal hashes mean (almost
/// surely) bit-identical images.
fn image_hash(pixels: &[niebla::color::Rgb]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in pixels {
        for c in p.0 {
            for b in c.to_bits().to_le_bytes() {
                h ^= b as u64;
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
    }
    h
}

/// Median, least and largest of `v` (not empty).
fn spread(v: &mut [f64]) -> (f64, f64, f64) {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    let median = if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
    (median, v[0], v[n - 1])
}

/// `niebla bench paths`.
pub fn run(args: &PathsBenchArgs) -> Result<(), CliError> {
    let threads = args.threads.get()?;
    let (built, _) = crate::load::load(Some(&args.scene))?;
    let settings = built.settings.integrator;
    let sampler = match &args.sampler {
        Some(name) => SamplerKind::parse(name).expect("names are checked by clap"),
        None => built.settings.sampler,
    };
    let seed = built.settings.seed;
    let mut scene = built.scene;
    if args.width == 0 || args.width > 16384 {
        return Err(CliError::invalid_option("--width", "must be between 1 and 16384"));
    }
    if args.spp == 0 || args.repeat == 0 {
        return Err(CliError::invalid_option("--spp, --repeat", "must be at least 1"));
    }
    let aspect = scene.camera.height as f64 / scene.camera.width as f64;
    scene.camera.width = args.width;
    scene.camera.height = ((args.width as f64 * aspect).round() as u32).max(1);
    let samples = scene.camera.width as f64 * scene.camera.height as f64 * args.spp as f64;
    let options = RenderOptions { spp: args.spp, seed, first_sample: 0, threads, sampler };
    println!(
        "bench paths: {} ({}), {}x{} pixels, {} spp, sampler {}, seed {seed}, threads {}",
        args.scene.display(),
        settings.key(),
        scene.camera.width,
        scene.camera.height,
        args.spp,
        sampler.name(),
        threads.map_or("all".to_string(), |t| t.to_string()),
    );
    // Warm-up: page in the scene's data, start the thread pool.
    let image = render(&scene, &settings, &options, &|_, _| {}, None)?;
    let n = image.pixels.len() as f64;
    let mut mean = [0.0f64; 3];
    for p in &image.pixels {
        for (m, c) in mean.iter_mut().zip(p.0) {
            *m += c as f64 / n;
        }
    }
    println!("image mean {:.6e} {:.6e} {:.6e}, hash {:016x}", mean[0], mean[1], mean[2], image_hash(&image.pixels));
    println!("{:>4} {:>10} {:>10} {:>14} {:>14}", "run", "wall s", "cpu s", "samples/cpu s", "samples/wall s");
    let (mut per_wall, mut per_cpu) = (Vec::new(), Vec::new());
    for run in 0..args.repeat {
        let cpu0 = process_cpu_seconds();
        let start = Instant::now();
        let again = render(&scene, &settings, &options, &|_, _| {}, None)?;
        let wall = start.elapsed().as_secs_f64();
        let cpu = cpu0.zip(process_cpu_seconds()).map(|(a, b)| b - a);
        if image_hash(&again.pixels) != image_hash(&image.pixels) {
            println!("warning: run {run} rendered a different image (not deterministic)");
        }
        per_wall.push(samples / wall);
        let cpu_text = match cpu {
            Some(c) if c > 0.0 => {
                per_cpu.push(samples / c);
                format!("{c:>10.2} {:>14.4e}", samples / c)
            }
            _ => format!("{:>10} {:>14}", "-", "-"),
        };
        println!("{run:>4} {wall:>10.3} {cpu_text} {:>14.4e}", samples / wall);
    }
    let (m, lo, hi) = spread(&mut per_wall);
    println!("samples/wall s: median {m:.4e} (min {lo:.4e}, max {hi:.4e})");
    if !per_cpu.is_empty() {
        let (m, lo, hi) = spread(&mut per_cpu);
        println!("samples/cpu s:  median {m:.4e} (min {lo:.4e}, max {hi:.4e})");
    }
    Ok(())
}
