//! `niebla compare`: one scene, several integrators, the same time budget,
//! and a self-contained HTML report of how close each gets to a reference.
//!
//! Steps: load the scene; read the reference EXR, or render one with
//! `volpath` (with another seed than the candidates, so that its noise is
//! independent of theirs); render each integrator progressively under the
//! time budget, measuring the relative MSE against the reference after every
//! pass (passes double the sample count, so the points are evenly spaced on
//! a log axis); write the report: the images side by side at one exposure,
//! false-color maps of the per-pixel relative error, a log-log plot of
//! relative MSE against time drawn by `plotters`, and a table of time, spp
//! and error. Images are embedded as base64 PNG and the plots as inline
//! SVG, so the report is one file that needs nothing else.
//!
//! The error measure is [`Image::relative_mse`]: the mean over pixels and
//! channels of `(x - r)^2 / (r^2 + eps)`, `eps = (0.01 mean(r))^2`. The
//! error maps show its per-pixel root, `sqrt(mean_c (x - r)^2 / (r^2 +
//! eps))`, on a logarithmic color scale shared by all maps.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use niebla::film::{read_exr, render_memory, write_atomically, write_exr, ExrReadError, Image};
use niebla::integrator::IntegratorSettings;
use niebla::limits::default_memory_limit;
use niebla::progressive::{render_progressive, Budget, PassInfo, ProgressiveOptions};
use serde_json::Value;

use crate::error::CliError;
use crate::flags::{check_output_folder, positive_seconds, ExposureFlag, QuietFlag, SeedFlag, ThreadsFlag};

mod report;

/// Options of `niebla compare`.
#[derive(Args, Debug)]
pub struct CompareArgs {
    /// Scene file (JSON, version 1). Without it, the built-in default scene.
    pub scene: Option<PathBuf>,
    /// Integrators to compare, comma separated: a name (volpath, single,
    /// emission, ...) or single:SAMPLING (march, equiangular, mis). A bare
    /// name the scene itself uses keeps the scene's parameters; otherwise
    /// the integrator's defaults apply.
    #[arg(long, value_delimiter = ',', default_value = "volpath,single")]
    pub integrators: Vec<String>,
    /// Reference image: an EXR of linear radiance at the scene's resolution.
    /// Without it, a volpath render (see --reference-time, --reference-spp)
    /// is the reference; its own noise then is a floor under the errors.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Wall-clock seconds each integrator may render: passes that double the
    /// sample count run while the next one fits (at least one sample per
    /// pixel is always rendered).
    #[arg(long, default_value_t = 10.0)]
    pub time_budget: f64,
    /// Seconds of the volpath reference render when no --reference is given
    /// (default: 4 times --time-budget).
    #[arg(long, conflicts_with_all = ["reference", "reference_spp"])]
    pub reference_time: Option<f64>,
    /// Samples per pixel of the volpath reference render, instead of a time.
    #[arg(long, conflicts_with = "reference")]
    pub reference_spp: Option<u32>,
    /// Also write the rendered reference to this EXR (to reuse with --reference).
    #[arg(long, conflicts_with = "reference")]
    pub save_reference: Option<PathBuf>,
    /// The HTML report to write.
    #[arg(short, long, default_value = "report.html")]
    pub output: PathBuf,
    /// `--threads`: worker threads.
    #[command(flatten)]
    pub threads: ThreadsFlag,
    /// `--seed`: the sampler seed.
    #[command(flatten)]
    pub seed: SeedFlag,
    /// `--exposure`: exposure of the images, in stops.
    #[command(flatten)]
    pub exposure: ExposureFlag,
    /// `--quiet`: no progress bars.
    #[command(flatten)]
    pub quiet: QuietFlag,
}

/// Added to the seed of a rendered reference, so that its random numbers are
/// not those of the candidates (a volpath candidate would otherwise share
/// its first samples with the reference and look better than it is).
const REFERENCE_SEED_OFFSET: u64 = 0x9E37_79B9_7F4A_7C15;

/// One measurement of a progressive render.
#[derive(Clone, Copy, Debug)]
struct ConvergencePoint {
    /// Render time so far in seconds (excluding the measurements).
    seconds: f64,
    /// Samples per pixel so far.
    spp: u64,
    /// Relative MSE against the reference.
    relative_mse: f64,
}

/// One integrator's render.
struct Run {
    /// As given on the command line, e.g. `single:mis`.
    label: String,
    settings: IntegratorSettings,
    image: Image,
    curve: Vec<ConvergencePoint>,
}

impl Run {
    fn last(&self) -> ConvergencePoint {
        *self.curve.last().expect("a render has at least one pass")
    }
}

/// The reference image and where it came from.
struct Reference {
    image: Image,
    description: String,
}

/// `niebla compare`.
pub fn run(args: &CompareArgs) -> Result<(), CliError> {
    let budget_seconds = positive_seconds("--time-budget", args.time_budget)?;
    let threads = args.threads.get()?;
    if args.reference_spp == Some(0) {
        return Err(CliError::invalid_option("--reference-spp", "must be at least 1"));
    }
    if args.integrators.iter().all(|s| s.trim().is_empty()) {
        return Err(CliError::invalid_option("--integrators", "name at least one integrator"));
    }
    check_output_folder(&args.output)?;
    let (built, _) = crate::load::load(args.scene.as_deref())?;
    let scene_settings = built.settings.integrator;
    let seed = args.seed.or(built.settings.seed);
    let exposure = args.exposure.or(built.settings.exposure)?;
    let candidates = args
        .integrators
        .iter()
        .map(|s| s.trim())
        .filter(|s| !s.is_empty())
        .map(|spec| Ok((spec.to_string(), parse_integrator(spec, &scene_settings)?)))
        .collect::<Result<Vec<_>, String>>()
        .map_err(CliError::Integrator)?;
    let scene = &built.scene;
    let left = default_memory_limit().saturating_sub(render_memory(scene.camera.width, scene.camera.height));
    for (_, settings) in &candidates {
        crate::load::check_precompute_memory(&crate::load::scene_label(args.scene.as_deref()), settings, scene, left)?;
    }

    // The reference.
    let reference = match &args.reference {
        Some(path) => {
            let image = read_reference(path)?;
            if (image.width, image.height) != (scene.camera.width, scene.camera.height) {
                return Err(CliError::ReferenceSize {
                    path: path.clone(),
                    size: (image.width, image.height),
                    scene_size: (scene.camera.width, scene.camera.height),
                });
            }
            Reference { image, description: format!("{} (given)", path.display()) }
        }
        None => {
            let settings = match scene_settings {
                s @ IntegratorSettings::VolPath { .. } => s,
                _ => IntegratorSettings::VolPath {
                    max_depth: IntegratorSettings::DEFAULT_MAX_DEPTH,
                    volume_light_sampling: true,
                    emitter_guiding: true,
                },
            };
            let budget = match (args.reference_spp, args.reference_time) {
                (Some(spp), _) => Budget::Samples(spp),
                (None, Some(t)) => Budget::Time(Duration::from_secs_f64(positive_seconds("--reference-time", t)?)),
                (None, None) => Budget::Time(Duration::from_secs_f64(4.0 * budget_seconds)),
            };
            let bar = progress_bar(args.quiet.quiet, "reference (volpath)", budget);
            let start = Instant::now();
            let mut spp = 0;
            let options = ProgressiveOptions {
                threads,
                progress: &|_, _| tick(&bar, budget, start),
                ..ProgressiveOptions::new(&settings, seed.wrapping_add(REFERENCE_SEED_OFFSET), budget)
            };
            let image = render_progressive(scene, &options, |_: &Image, info: PassInfo| {
                spp = info.spp;
                true
            })?;
            bar.finish_and_clear();
            let seconds = start.elapsed().as_secs_f64();
            if let Some(path) = &args.save_reference {
                write_exr(&image, path)?;
            }
            if !args.quiet.quiet {
                eprintln!("reference: volpath, {spp} spp in {seconds:.1} s");
            }
            Reference {
                image,
                description: format!("volpath, {spp} spp, {seconds:.1} s (seeded apart from the integrators)"),
            }
        }
    };

    // The candidates.
    let budget = Budget::Time(Duration::from_secs_f64(budget_seconds));
    let mut runs = Vec::new();
    for (label, settings) in candidates {
        let bar = progress_bar(args.quiet.quiet, &label, budget);
        let start = Instant::now();
        let mut curve = Vec::new();
        let mut measuring = Duration::ZERO;
        let options = ProgressiveOptions {
            threads,
            progress: &|_, _| tick(&bar, budget, start),
            ..ProgressiveOptions::new(&settings, seed, budget)
        };
        let image = render_progressive(scene, &options, |image: &Image, info: PassInfo| {
            let t0 = Instant::now();
            let relative_mse = image.relative_mse(&reference.image);
            curve.push(ConvergencePoint {
                seconds: info.elapsed.saturating_sub(measuring).as_secs_f64(),
                spp: info.spp,
                relative_mse,
            });
            measuring += t0.elapsed();
            true
        })?;
        bar.finish_and_clear();
        let run = Run { label, settings, image, curve };
        let last = run.last();
        println!("{}: {} spp in {:.2} s, relative MSE {:.3e}", run.label, last.spp, last.seconds, last.relative_mse);
        runs.push(run);
    }

    let title = args.scene.as_ref().map_or("<default scene>".to_string(), |p| p.display().to_string());
    let html = report::report_html(&title, &reference, &runs, exposure, budget_seconds)?;
    write_atomically(&args.output, html.as_bytes())?;
    println!("report -> {}", args.output.display());
    Ok(())
}

/// `NAME` or `NAME:SAMPLING` as integrator settings, read by the
/// integrator registry (so every integrator works, with its defaults and its
/// messages). A bare name the scene uses keeps the scene's settings, as
/// `niebla render --integrator` does.
fn parse_integrator(spec: &str, scene_settings: &IntegratorSettings) -> Result<IntegratorSettings, String> {
    let (name, sampling) = match spec.split_once(':') {
        Some((name, sampling)) => (name.trim(), Some(sampling.trim())),
        None => (spec, None),
    };
    if sampling.is_none() && name == scene_settings.name() {
        return Ok(*scene_settings);
    }
    let mut object = serde_json::Map::new();
    object.insert("type".into(), Value::from(name));
    if let Some(sampling) = sampling {
        object.insert("sampling".into(), Value::from(sampling));
    }
    niebla::integrator::registry::parse(&object)
        .map_err(|e| format!("--integrators {spec}: render.integrator.{}: {}", e.path, e.message))
}

/// The reference image at `path`: an EXR's RGB channels.
fn read_reference(path: &std::path::Path) -> Result<Image, CliError> {
    read_exr(path).map(|exr| exr.image).map_err(|e| match e {
        ExrReadError::Missing { path } => CliError::ReferenceNotFound(path),
        other => CliError::ReferenceUnreadable { path: path.to_path_buf(), reason: other.reason() },
    })
}

fn progress_bar(quiet: bool, label: &str, budget: Budget) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = match budget {
        Budget::Time(t) => ProgressBar::new((t.as_secs_f64() * 1000.0) as u64),
        Budget::Samples(_) => ProgressBar::new_spinner(),
    };
    let template = "{spinner} {msg} [{elapsed_precise}] {wide_bar} {percent:>3}%";
    if let Ok(style) = ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar.set_message(label.to_string());
    bar
}

fn tick(bar: &ProgressBar, budget: Budget, start: Instant) {
    match budget {
        Budget::Time(_) => bar.set_position(start.elapsed().as_millis() as u64),
        Budget::Samples(_) => bar.tick(),
    }
}
