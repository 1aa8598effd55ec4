//! `niebla bench sampler`: relative MSE at equal sample counts of the
//! scene's integrator with each sampler kind (independent numbers, Sobol in
//! draw order, Sobol with the integrator's dimension layout).
//!
//! The reference is two renders with independent numbers and other seeds
//! than the measured renders; its own error, estimated from the two halves
//! as `relMSE(a, b) / 4`, is printed and subtracted from every figure. Each
//! figure is the mean over `--seeds` renders with different seeds.

use std::path::PathBuf;

use clap::Args;
use niebla::film::Image;
use niebla::render::{render, RenderOptions};
use niebla::sampling::SamplerKind;

use crate::error::CliError;
use crate::flags::ThreadsFlag;

/// Options of `niebla bench sampler`.
#[derive(Args, Debug)]
pub struct SamplerBenchArgs {
    /// Scene to measure (its own integrator).
    pub scene: PathBuf,
    /// Image width used for the measurements (height keeps the aspect ratio).
    #[arg(long, default_value_t = 64)]
    pub width: u32,
    /// Samples per pixel of each half of the reference.
    #[arg(long, default_value_t = 4096)]
    pub reference_spp: u32,
    /// Sample counts measured, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "16,64,256")]
    pub spp: Vec<u32>,
    /// Sampler kinds measured, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "independent,sobol_sequential,sobol",
          value_parser = clap::builder::PossibleValuesParser::new(SamplerKind::NAMES))]
    pub samplers: Vec<String>,
    /// Renders (seeds) averaged per figure.
    #[arg(long, default_value_t = 2)]
    pub seeds: u32,
    /// `--threads`: worker threads.
    #[command(flatten)]
    pub threads: ThreadsFlag,
}

/// `niebla bench sampler`.
pub fn run(args: &SamplerBenchArgs) -> Result<(), CliError> {
    let threads = args.threads.get()?;
    let (built, _) = crate::load::load(Some(&args.scene))?;
    let settings = built.settings.integrator;
    let mut scene = built.scene;
    if args.width == 0 || args.width > 16384 {
        return Err(CliError::invalid_option("--width", "must be between 1 and 16384"));
    }
    if args.reference_spp == 0 || args.seeds == 0 || args.spp.contains(&0) {
        return Err(CliError::invalid_option("--reference-spp, --seeds, --spp", "must be at least 1"));
    }
    let aspect = scene.camera.height as f64 / scene.camera.width as f64;
    scene.camera.width = args.width;
    scene.camera.height = ((args.width as f64 * aspect).round() as u32).max(1);
    let go = |spp: u32, seed: u64, sampler: SamplerKind| -> Result<(Image, f64), CliError> {
        let options = RenderOptions { spp, seed, first_sample: 0, threads, sampler };
        let start = std::time::Instant::now();
        let image = render(&scene, &settings, &options, &|_, _| {}, None)?;
        Ok((image, start.elapsed().as_secs_f64()))
    };
    println!(
        "bench sampler: {} ({}), {}x{} pixels, threads {}, reference 2 x {} spp (independent)",
        args.scene.display(),
        settings.key(),
        scene.camera.width,
        scene.camera.height,
        threads.map_or("all".to_string(), |t| t.to_string()),
        args.reference_spp
    );
    let (a, ta) = go(args.reference_spp, 1_000_003, SamplerKind::Independent)?;
    let (b, tb) = go(args.reference_spp, 2_000_003, SamplerKind::Independent)?;
    let reference_error = a.relative_mse(&b) / 4.0;
    let mut reference = a.clone();
    for (r, p) in reference.pixels.iter_mut().zip(&b.pixels) {
        *r = (*r + *p) * 0.5;
    }
    println!("reference rendered in {:.1} s; its estimated relative MSE {reference_error:.3e} (subtracted)", ta + tb);
    println!("{:<18} {:>6} {:>12} {:>10}", "sampler", "spp", "rel MSE", "time s");
    for name in &args.samplers {
        let kind = SamplerKind::parse(name).expect("names are checked by clap");
        for &spp in &args.spp {
            let (mut error, mut time) = (0.0, 0.0);
            for seed in 0..args.seeds as u64 {
                let (image, seconds) = go(spp, 11 + seed, kind)?;
                error += image.relative_mse(&reference) - reference_error;
                time += seconds;
            }
            let n = args.seeds as f64;
            println!("{name:<18} {spp:>6} {:>12.4e} {:>10.3}", error / n, time / n);
        }
    }
    Ok(())
}
