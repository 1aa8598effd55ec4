//! `niebla bench`: figures, not tests. Renders the default scene with the
//! `single` integrator in each sampling mode at doubling sample counts and
//! reports samples per second and the time to reach a relative MSE of 1e-2
//! against a high-spp reference (interpolated on log-log axes between the
//! two bracketing renders).

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use niebla::film::Image;
use niebla::integrator::{IntegratorSettings, SingleSampling};
use niebla::render::{render, RenderOptions};
use niebla::scene::Scene;
use niebla::tracking::TransmittanceMethod;

use crate::error::CliError;
use crate::flags::ThreadsFlag;

/// Options of `niebla bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scene to measure (default: the built-in default scene).
    pub scene: Option<PathBuf>,
    /// Image width used for the measurements (height keeps the aspect ratio).
    #[arg(long, default_value_t = 240)]
    pub width: u32,
    /// Samples per pixel of the reference render (MIS sampling).
    #[arg(long, default_value_t = 512)]
    pub reference_spp: u32,
    /// Largest sample count tried per mode.
    #[arg(long, default_value_t = 256)]
    pub max_spp: u32,
    /// Target relative MSE.
    #[arg(long, default_value_t = 1e-2)]
    pub target: f64,
    /// `--threads`: worker threads.
    #[command(flatten)]
    pub threads: ThreadsFlag,
}

fn single(sampling: SingleSampling) -> IntegratorSettings {
    IntegratorSettings::Single {
        step: None,
        sampling,
        transmittance: TransmittanceMethod::Analytic,
        volume_lights: false,
    }
}

/// Render `spp` samples per pixel with `seed`; the image and the seconds it took.
pub(crate) fn timed(
    scene: &Scene,
    settings: &IntegratorSettings,
    spp: u32,
    seed: u64,
    threads: Option<usize>,
) -> Result<(Image, f64), CliError> {
    let options = RenderOptions { spp, seed, first_sample: 0, threads, sampler: Default::default() };
    let start = Instant::now();
    let image = render(scene, settings, &options, &|_, _| {}, None)?;
    Ok((image, start.elapsed().as_secs_f64()))
}

/// `niebla bench`.
pub fn run(args: &BenchArgs) -> Result<(), CliError> {
    let threads = args.threads.get()?;
    let (built, _) = crate::load::load(args.scene.as_deref())?;
    let mut scene = built.scene;
    if args.width == 0 || args.width > 16384 {
        return Err(CliError::invalid_option("--width", "must be between 1 and 16384"));
    }
    let aspect = scene.camera.height as f64 / scene.camera.width as f64;
    scene.camera.width = args.width;
    scene.camera.height = ((args.width as f64 * aspect).round() as u32).max(1);
    let pixels = scene.camera.width as f64 * scene.camera.height as f64;
    println!(
        "bench: {}x{} pixels, threads {}, reference {} spp (single, mis)",
        scene.camera.width,
        scene.camera.height,
        threads.map_or("all".to_string(), |t| t.to_string()),
        args.reference_spp
    );
    let (reference, ref_time) = timed(&scene, &single(SingleSampling::Mis), args.reference_spp, 1_000_003, threads)?;
    println!("reference rendered in {ref_time:.2} s");
    println!("{:<12} {:>6} {:>10} {:>14} {:>12}", "sampling", "spp", "time s", "samples/s", "rel MSE");
    for (name, sampling) in
        [("march", SingleSampling::March), ("equiangular", SingleSampling::Equiangular), ("mis", SingleSampling::Mis)]
    {
        let mut points: Vec<(f64, f64)> = Vec::new();
        let mut spp = 1;
        while spp <= args.max_spp {
            let (image, seconds) = timed(&scene, &single(sampling), spp, 7, threads)?;
            let error = image.relative_mse(&reference);
            println!("{name:<12} {spp:>6} {seconds:>10.3} {:>14.3e} {error:>12.3e}", pixels * spp as f64 / seconds);
            points.push((seconds, error));
            if error < args.target {
                break;
            }
            spp *= 2;
        }
        match time_to_reach(&points, args.target) {
            Some(t) => println!("{name:<12} reaches relative MSE {:.0e} in {t:.3} s", args.target),
            None => println!("{name:<12} did not reach relative MSE {:.0e} within {} spp", args.target, args.max_spp),
        }
    }
    Ok(())
}

/// Time at which the error curve crosses `target`, by log-log interpolation
/// between the last point above and the first point below it.
pub(crate) fn time_to_reach(points: &[(f64, f64)], target: f64) -> Option<f64> {
    let i = points.iter().position(|&(_, e)| e < target)?;
    if i == 0 {
        return Some(points[0].0);
    }
    let ((t0, e0), (t1, e1)) = (points[i - 1], points[i]);
    let f = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
    Some((t0.ln() + f * (t1.ln() - t0.ln())).exp())
}
