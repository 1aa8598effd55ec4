//! `niebla bench interactive`: the interactive methods side by side, one
//! table per scene: frames per second at 256x256 and 512x512 (1 spp per
//! frame, precomputation excluded), precomputation time and memory, and the
//! relative MSE against a high-spp `volpath` reference at a small size. A
//! second reference of another seed is measured the same way first: its
//! relative MSE is the floor below which the reference cannot tell methods
//! apart (raise `--reference-spp` until the methods sit well above it).

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use niebla::film::Image;
use niebla::integrator::hegeman::Calibration;
use niebla::integrator::zhou::{Compensation, LocalLights};
use niebla::integrator::{
    HegemanIntegrator, HegemanSettings, Integrator, IntegratorSettings, VolPathIntegrator, ZhouIntegrator, ZhouSettings,
};
use niebla::render::{render_with, RenderOptions};
use niebla::scene::Scene;

use crate::error::CliError;
use crate::flags::ThreadsFlag;

/// Options of `niebla bench interactive`.
#[derive(Args, Debug)]
pub struct InteractiveBenchArgs {
    /// Scenes to measure.
    #[arg(default_values = ["scenes/smoke.json", "scenes/fog.json", "scenes/cloud.json"])]
    pub scenes: Vec<PathBuf>,
    /// Frames timed per method and resolution.
    #[arg(long, default_value_t = 3)]
    pub frames: u32,
    /// Width of the error images (height keeps the scene's aspect).
    #[arg(long, default_value_t = 96)]
    pub error_width: u32,
    /// Samples per pixel of the volpath reference.
    #[arg(long, default_value_t = 256)]
    pub reference_spp: u32,
    /// Samples per pixel of the methods' error images.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
    /// `--threads`: worker threads.
    #[command(flatten)]
    pub threads: ThreadsFlag,
}

/// `scene` at `width` pixels wide and `height` high, or with the height
/// keeping the camera's aspect ([`crate::render_cmd::resized_camera`], the
/// convention `niebla render --width` shares for the cached references).
fn resized(scene: &Scene, width: u32, height: Option<u32>) -> Scene {
    let mut s = scene.clone();
    s.camera = crate::render_cmd::resized_camera(&scene.camera, width);
    if let Some(height) = height {
        s.camera.height = height;
    }
    s
}

fn frame<I: Integrator>(scene: &Scene, integrator: &I, spp: u32, seed: u64, threads: Option<usize>) -> Image {
    let options = RenderOptions { spp, seed, first_sample: 0, threads, sampler: Default::default() };
    render_with(scene, integrator, &options, &|_, _| {}, None).expect("render without cancel flag")
}

/// Frames per second of `integrator` on `scene` at `size` x `size`.
fn fps<I: Integrator>(scene: &Scene, integrator: &I, size: u32, frames: u32, threads: Option<usize>) -> f64 {
    let s = resized(scene, size, Some(size));
    let start = Instant::now();
    for k in 0..frames {
        frame(&s, integrator, 1, k as u64, threads);
    }
    frames as f64 / start.elapsed().as_secs_f64()
}

/// The hegeman settings of the scene file, else the defaults.
fn hegeman_settings(file: IntegratorSettings) -> HegemanSettings {
    match file {
        IntegratorSettings::Hegeman(h) => h,
        _ => HegemanSettings::default(),
    }
}

/// The zhou settings of the scene file, else the defaults; the fit cache is
/// off so that the precomputation column includes the fit.
fn zhou_settings(file: IntegratorSettings) -> ZhouSettings {
    let settings = match file {
        IntegratorSettings::Zhou(z) => z,
        _ => ZhouSettings::default(),
    };
    ZhouSettings { cache: false, ..settings }
}

/// `niebla bench interactive`.
pub fn run(args: &InteractiveBenchArgs) -> Result<(), CliError> {
    if args.frames == 0 || args.spp == 0 || args.reference_spp == 0 || args.error_width == 0 {
        return Err(CliError::invalid_option(
            "--frames, --spp, --reference-spp and --error-width",
            "must be at least 1",
        ));
    }
    let threads = args.threads.get()?;
    for path in &args.scenes {
        let (built, _) = crate::load::load(Some(path))?;
        let scene = built.scene;
        let small = resized(&scene, args.error_width, None);
        let start = Instant::now();
        let reference = frame(&small, &VolPathIntegrator::new(256), args.reference_spp, 1_000_003, threads);
        println!(
            "\n{}: reference volpath {}x{} at {} spp in {:.1} s",
            path.display(),
            small.camera.width,
            small.camera.height,
            args.reference_spp,
            start.elapsed().as_secs_f64()
        );
        println!(
            "{:<25} {:>10} {:>10} {:>14} {:>12} {:>14} {:>9}",
            "method", "fps 256^2", "fps 512^2", "precompute s", "memory MiB", "rel MSE", "mean/ref"
        );
        let reference_mean = reference.mean().average();
        let measure = |image: Image| (image.relative_mse(&reference), image.mean().average() / reference_mean);
        // The reference's own noise: a second volpath render of the same spp
        // and another seed, measured like the methods. A method's relative MSE
        // below this floor is not resolved by the reference.
        let (floor_error, floor_ratio) =
            measure(frame(&small, &VolPathIntegrator::new(256), args.reference_spp, 2_000_003, threads));
        println!(
            "{:<25} {:>10} {:>10} {:>14} {:>12} {:>14.4} {:>9.3}",
            "volpath (2nd reference)", "-", "-", "-", "-", floor_error, floor_ratio
        );
        let single = crate::preview_cmd::interactive_single();
        let (single_error, single_ratio) = measure(frame(&small, &single, args.spp, 7, threads));
        println!(
            "{:<25} {:>10.2} {:>10.2} {:>14.3} {:>12.2} {:>14.4} {:>9.3}",
            "single (ray march)",
            fps(&scene, &single, 256, args.frames, threads),
            fps(&scene, &single, 512, args.frames, threads),
            0.0,
            0.0,
            single_error,
            single_ratio
        );
        for (name, multiple, calibration, surface) in [
            ("hegeman", true, Calibration::None, false),
            ("hegeman (lit surfaces)", true, Calibration::None, true),
            ("hegeman (mc_tables)", true, Calibration::McTables, false),
            ("hegeman (mc_fluence)", true, Calibration::McFluence, false),
            ("hegeman (single only)", false, Calibration::None, false),
        ] {
            let settings = HegemanSettings {
                multiple_scattering: multiple,
                calibration,
                surface_scattering: surface,
                ..hegeman_settings(built.settings.integrator)
            };
            let hegeman = HegemanIntegrator::new(&scene, settings);
            let (error, ratio) = measure(frame(&small, &hegeman, args.spp, 7, threads));
            println!(
                "{name:<25} {:>10.2} {:>10.2} {:>14.3} {:>12.2} {:>14.4} {:>9.3}",
                fps(&scene, &hegeman, 256, args.frames, threads),
                fps(&scene, &hegeman, 512, args.frames, threads),
                hegeman.precompute_seconds,
                hegeman.memory_bytes() as f64 / (1024.0 * 1024.0),
                error,
                ratio
            );
        }
        let base = zhou_settings(built.settings.integrator);
        let variants = [
            ("zhou", base),
            ("zhou (single only)", ZhouSettings { multiple_scattering: false, ..base }),
            ("zhou (local lights rbf)", ZhouSettings { local_lights: LocalLights::Rbf, ..base }),
            ("zhou (no compensation)", ZhouSettings { compensation: Compensation::Off, ..base }),
            ("zhou (source only)", ZhouSettings { compensation: Compensation::SourceOnly, ..base }),
        ];
        for (name, settings) in variants {
            let zhou = ZhouIntegrator::new(&scene, settings);
            let (error, ratio) = measure(frame(&small, &zhou, args.spp, 7, threads));
            println!(
                "{name:<25} {:>10.2} {:>10.2} {:>14.3} {:>12.2} {:>14.4} {:>9.3}   (fit error {:.3})",
                fps(&scene, &zhou, 256, args.frames, threads),
                fps(&scene, &zhou, 512, args.frames, threads),
                zhou.fit_seconds + zhou.lighting_seconds,
                zhou.memory_bytes() as f64 / (1024.0 * 1024.0),
                error,
                ratio,
                zhou.fit_errors().iter().copied().fold(0.0, f64::max)
            );
        }
    }
    Ok(())
}
