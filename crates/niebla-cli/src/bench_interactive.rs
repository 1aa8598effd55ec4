//! `niebla bench interactive`: the interactive methods side by side, one
//! table per scene: frames per second at 256x256 and 512x512 (1 spp per
//! frame, precomputation excluded), precomputation time and memory, and the
//! relative MSE against a high-spp `volpath` reference at a small size. A
//! second reference of another seed is measured the same way first: its
//! relative MSE is the floor below which the reference cannot tell methods
//! apart (raise `--reference-spp` until the methods sit well above it).
//!
//! A converged reference takes far longer than the bench: `--reference-exr`
//! reads it instead from EXRs rendered beforehand by `niebla render --width`
//! (the bench's size convention) with volpath at max depth 256. Two
//! independent renders of a scene (different seeds) also give the
//! reference's own noise, which the "corrected" column removes from the
//! relative MSE ([`niebla::film::SplitReference`]).

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use niebla::film::{read_checkpoint_full, Image, SplitReference};
use niebla::integrator::hegeman::{Calibration, SurfaceScattering};
use niebla::integrator::zhou::{Compensation, LocalLights};
use niebla::integrator::SurfaceShadows;
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
    /// Cached references: EXR outputs of `niebla render SCENE --width
    /// ERROR_WIDTH --integrator volpath --max-depth 256` (one or two per
    /// scene, matched to the scenes by the scene hash in their headers; two
    /// must have different seeds, and their weighted mean is the reference
    /// with its noise estimated from their difference). Scenes without one
    /// render their reference as before.
    #[arg(long, value_name = "FILE.exr")]
    pub reference_exr: Vec<PathBuf>,
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

/// Seed of the bench's own volpath reference (when no cached one is given).
const REFERENCE_SEED: u64 = 1_000_003;
/// Seed of the second volpath render measured like a method.
const SECOND_REFERENCE_SEED: u64 = 2_000_003;

/// A cached reference EXR: its file, image, samples per pixel, seed and scene hash.
struct CachedReference {
    path: PathBuf,
    image: Image,
    spp: u64,
    seed: u64,
    scene_hash: String,
}

/// Reads the `--reference-exr` files and checks that each is a volpath
/// render at max depth 256 with finite pixels (size and scene are checked
/// against each scene later).
fn read_references(paths: &[PathBuf]) -> Result<Vec<CachedReference>, CliError> {
    let expected = niebla::integrator::IntegratorSettings::VolPath {
        max_depth: 256,
        volume_light_sampling: true,
        emitter_guiding: true,
    }
    .key();
    let mut out = Vec::new();
    for path in paths {
        let bad =
            |problem: String| CliError::invalid_option("--reference-exr", format!("{}: {problem}", path.display()));
        let checkpoint =
            read_checkpoint_full(path).map_err(|e| CliError::invalid_option("--reference-exr", e.to_string()))?;
        let (integrator, _) = niebla::render::split_recorded_key(&checkpoint.info.integrator);
        if integrator != expected {
            return Err(bad(format!(
                "was rendered with {integrator}; the reference must be {expected} \
                 (niebla render SCENE --width W --integrator volpath --max-depth 256)"
            )));
        }
        if checkpoint.info.spp == 0 || checkpoint.image.pixels.iter().any(|p| !p.is_finite()) {
            return Err(bad("holds no samples or non-finite pixels".to_string()));
        }
        out.push(CachedReference {
            path: path.clone(),
            image: checkpoint.image,
            spp: checkpoint.info.spp,
            seed: checkpoint.info.seed,
            scene_hash: checkpoint.info.scene_hash,
        });
    }
    Ok(out)
}

/// The reference of one scene: its cached files (`cached`, already matched
/// by scene hash) checked against the error image size, or a volpath render.
fn scene_reference(
    path: &std::path::Path,
    small: &Scene,
    cached: &[&CachedReference],
    spp: u32,
    threads: Option<usize>,
) -> Result<(SplitReference, String), CliError> {
    let (w, h) = (small.camera.width, small.camera.height);
    for r in cached {
        if (r.image.width, r.image.height) != (w, h) {
            return Err(CliError::invalid_option(
                "--reference-exr",
                format!(
                    "{}: is {} x {} pixels; the error images of {} are {w} x {h} (render it with --width {w})",
                    r.path.display(),
                    r.image.width,
                    r.image.height,
                    path.display()
                ),
            ));
        }
        if r.seed == SECOND_REFERENCE_SEED {
            return Err(CliError::invalid_option(
                "--reference-exr",
                format!(
                    "{}: seed {SECOND_REFERENCE_SEED} is the bench's second volpath render's; \
                     render the reference with another --seed",
                    r.path.display()
                ),
            ));
        }
    }
    let describe = |r: &CachedReference| format!("{} ({} spp, seed {})", r.path.display(), r.spp, r.seed);
    match cached {
        [] => {
            let start = Instant::now();
            let image = frame(small, &VolPathIntegrator::new(256), spp, REFERENCE_SEED, threads);
            let line = format!("reference volpath {w}x{h} at {spp} spp in {:.1} s", start.elapsed().as_secs_f64());
            Ok((SplitReference::single(image), line))
        }
        [one] => Ok((SplitReference::single(one.image.clone()), format!("reference {}", describe(one)))),
        [a, b] => {
            if a.seed == b.seed {
                return Err(CliError::invalid_option(
                    "--reference-exr",
                    format!(
                        "{} and {} have the same seed {}: the two halves of a reference must be independent \
                         (different --seed)",
                        a.path.display(),
                        b.path.display(),
                        a.seed
                    ),
                ));
            }
            let reference = SplitReference::halves(a.image.clone(), a.spp, b.image.clone(), b.spp);
            let line = format!(
                "reference {} + {}: {w}x{h} at {} spp; its noise (subtracted in \"corrected\") {:.3e} +- {:.1e}",
                describe(a),
                describe(b),
                a.spp + b.spp,
                reference.noise().unwrap_or(0.0),
                reference.noise_standard_error().unwrap_or(0.0)
            );
            Ok((reference, line))
        }
        more => Err(CliError::invalid_option(
            "--reference-exr",
            format!("{} files were rendered from {}: give one or two per scene", more.len(), path.display()),
        )),
    }
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
    let cached = read_references(&args.reference_exr)?;
    let mut loaded = Vec::new();
    for path in &args.scenes {
        loaded.push(crate::load::load_limited(Some(path), niebla::limits::default_memory_limit())?);
    }
    if let Some(r) = cached.iter().find(|r| !loaded.iter().any(|l| l.hash == r.scene_hash)) {
        let scenes: Vec<String> =
            args.scenes.iter().zip(&loaded).map(|(p, l)| format!("{} ({})", p.display(), l.hash)).collect();
        return Err(CliError::invalid_option(
            "--reference-exr",
            format!(
                "{}: was rendered from a scene of hash {}, none of the scenes measured: {}",
                r.path.display(),
                r.scene_hash,
                scenes.join(", ")
            ),
        ));
    }
    for (path, scene_loaded) in args.scenes.iter().zip(loaded) {
        let built = scene_loaded.built;
        let scene = built.scene;
        let small = resized(&scene, args.error_width, None);
        let mine: Vec<&CachedReference> = cached.iter().filter(|r| r.scene_hash == scene_loaded.hash).collect();
        let (reference, line) = scene_reference(path, &small, &mine, args.reference_spp, threads)?;
        println!("\n{}: {line}", path.display());
        println!(
            "{:<25} {:>10} {:>10} {:>14} {:>12} {:>10} {:>10} {:>9}",
            "method", "fps 256^2", "fps 512^2", "precompute s", "memory MiB", "rel MSE", "corrected", "mean/ref"
        );
        let reference_mean = reference.mean().mean().average();
        // Relative MSE, the same with the reference's noise removed ("-"
        // without two halves), and the mean against the reference's.
        let measure = |image: Image| {
            let corrected = match reference.noise_corrected_relative_mse(&image) {
                Some(c) => format!("{c:.4}"),
                None => "-".to_string(),
            };
            (reference.relative_mse(&image), corrected, image.mean().average() / reference_mean)
        };
        // A second volpath render of --reference-spp and another seed,
        // measured like the methods: against the bench's own reference its
        // relative MSE is the floor below which the reference cannot tell
        // methods apart; against a converged one, volpath's own error at
        // that sample count.
        let (floor_error, floor_corrected, floor_ratio) =
            measure(frame(&small, &VolPathIntegrator::new(256), args.reference_spp, SECOND_REFERENCE_SEED, threads));
        println!(
            "{:<25} {:>10} {:>10} {:>14} {:>12} {:>10.4} {:>10} {:>9.3}",
            format!("volpath ({} spp)", args.reference_spp),
            "-",
            "-",
            "-",
            "-",
            floor_error,
            floor_corrected,
            floor_ratio
        );
        let single = crate::preview_cmd::interactive_single();
        let (single_error, single_corrected, single_ratio) = measure(frame(&small, &single, args.spp, 7, threads));
        println!(
            "{:<25} {:>10.2} {:>10.2} {:>14.3} {:>12.2} {:>10.4} {:>10} {:>9.3}",
            "single (ray march)",
            fps(&scene, &single, 256, args.frames, threads),
            fps(&scene, &single, 512, args.frames, threads),
            0.0,
            0.0,
            single_error,
            single_corrected,
            single_ratio
        );
        for (name, multiple, calibration, surface) in [
            ("hegeman", true, Calibration::None, SurfaceScattering::Cone),
            ("hegeman (line surfaces)", true, Calibration::None, SurfaceScattering::Line),
            ("hegeman (direct surfaces)", true, Calibration::None, SurfaceScattering::Off),
            ("hegeman (mc_tables)", true, Calibration::McTables, SurfaceScattering::Cone),
            ("hegeman (mc_fluence)", true, Calibration::McFluence, SurfaceScattering::Cone),
            ("hegeman (single only)", false, Calibration::None, SurfaceScattering::Off),
            ("hegeman (march shadows)", true, Calibration::None, SurfaceScattering::Cone),
            ("hegeman (lattice lights)", true, Calibration::None, SurfaceScattering::Cone),
        ] {
            let base = hegeman_settings(built.settings.integrator);
            let settings = HegemanSettings {
                multiple_scattering: multiple,
                calibration,
                surface_scattering: surface,
                surface_shadows: if name.contains("march shadows") {
                    SurfaceShadows::March
                } else if name.contains("lattice lights") {
                    SurfaceShadows::Lattice
                } else {
                    base.surface_shadows
                },
                ..base
            };
            let hegeman = HegemanIntegrator::new(&scene, settings);
            let (error, corrected, ratio) = measure(frame(&small, &hegeman, args.spp, 7, threads));
            println!(
                "{name:<25} {:>10.2} {:>10.2} {:>14.3} {:>12.2} {:>10.4} {:>10} {:>9.3}",
                fps(&scene, &hegeman, 256, args.frames, threads),
                fps(&scene, &hegeman, 512, args.frames, threads),
                hegeman.precompute_seconds,
                hegeman.memory_bytes() as f64 / (1024.0 * 1024.0),
                error,
                corrected,
                ratio
            );
        }
        let base = zhou_settings(built.settings.integrator);
        let variants = [
            ("zhou", base),
            ("zhou (single only)", ZhouSettings { multiple_scattering: false, ..base }),
            ("zhou (march shadows)", ZhouSettings { surface_shadows: SurfaceShadows::March, ..base }),
            ("zhou (lattice lights)", ZhouSettings { surface_shadows: SurfaceShadows::Lattice, ..base }),
            ("zhou (local lights rbf)", ZhouSettings { local_lights: LocalLights::Rbf, ..base }),
            ("zhou (no compensation)", ZhouSettings { compensation: Compensation::Off, ..base }),
            ("zhou (source only)", ZhouSettings { compensation: Compensation::SourceOnly, ..base }),
        ];
        for (name, settings) in variants {
            let zhou = ZhouIntegrator::new(&scene, settings);
            let (error, corrected, ratio) = measure(frame(&small, &zhou, args.spp, 7, threads));
            println!(
                "{name:<25} {:>10.2} {:>10.2} {:>14.3} {:>12.2} {:>10.4} {:>10} {:>9.3}   (fit error {:.3})",
                fps(&scene, &zhou, 256, args.frames, threads),
                fps(&scene, &zhou, 512, args.frames, threads),
                zhou.fit_seconds + zhou.lighting_seconds,
                zhou.memory_bytes() as f64 / (1024.0 * 1024.0),
                error,
                corrected,
                ratio,
                zhou.fit_errors().iter().copied().fold(0.0, f64::max)
            );
        }
    }
    Ok(())
}
