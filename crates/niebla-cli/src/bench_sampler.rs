//! `niebla bench sampler`: relative MSE at equal sample counts of the
//! scene's integrator with each sampler kind (independent numbers, Sobol in
//! draw order, Sobol with the integrator's dimension layout).
//!
//! The reference is two renders with other seeds than the measured renders,
//! with independent numbers (or `--reference-sampler`: two Sobol renders
//! with different seeds are independent too, and have a much smaller error
//! where Sobol converges faster); its own error, estimated from the two
//! halves as `relMSE(a, b) / 4`, is printed and subtracted from every
//! figure. Each figure is the mean over `--seeds` renders with different
//! seeds, followed by the standard error of that mean over the seeds.

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
    /// Sampler of the two reference renders.
    #[arg(long, default_value = "independent",
          value_parser = clap::builder::PossibleValuesParser::new(SamplerKind::NAMES))]
    pub reference_sampler: String,
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
        "bench sampler: {} ({}), {}x{} pixels, threads {}, reference 2 x {} spp ({})",
        args.scene.display(),
        settings.key(),
        scene.camera.width,
        scene.camera.height,
        threads.map_or("all".to_string(), |t| t.to_string()),
        args.reference_spp,
        args.reference_sampler
    );
    let reference_kind = SamplerKind::parse(&args.reference_sampler).expect("names are checked by clap");
    let (a, ta) = go(args.reference_spp, 1_000_003, reference_kind)?;
    let (b, tb) = go(args.reference_spp, 2_000_003, reference_kind)?;
    let reference_error = a.relative_mse(&b) / 4.0;
    let mut reference = a.clone();
    for (r, p) in reference.pixels.iter_mut().zip(&b.pixels) {
        *r = (*r + *p) * 0.5;
    }
    println!("reference rendered in {:.1} s; its estimated relative MSE {reference_error:.3e} (subtracted)", ta + tb);
    println!("{:<18} {:>6} {:>12} {:>10} {:>10}", "sampler", "spp", "rel MSE", "+- (seeds)", "time s");
    for name in &args.samplers {
        let kind = SamplerKind::parse(name).expect("names are checked by clap");
        for &spp in &args.spp {
            let (mut errors, mut time) = (Vec::new(), 0.0);
            for seed in 0..args.seeds as u64 {
                let (image, seconds) = go(spp, 11 + seed, kind)?;
                errors.push(image.relative_mse(&reference) - reference_error);
                time += seconds;
            }
            let n = args.seeds as f64;
            let mean = errors.iter().sum::<f64>() / n;
            // Standard error of the mean over the seeds (0 for one seed).
            let spread = if errors.len() > 1 {
                (errors.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt()
            } else {
                0.0
            };
            println!("{name:<18} {spp:>6} {mean:>12.4e} {spread:>10.2e} {:>10.3}", time / n);
        }
    }
    Ok(())
}
