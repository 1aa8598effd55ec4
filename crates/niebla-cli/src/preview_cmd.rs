//! `niebla preview`: render a scene again and again at a chosen resolution,
//! report frames per second, and start over (precomputation included) when
//! the scene file changes (its modification time is polled before every
//! frame). Frames go to one image that is rewritten (`--output`) or to a
//! numbered sequence (`--sequence DIR`); `--frames N` stops after N frames.

use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime};

use clap::Args;
use niebla::film::write_image;
use niebla::integrator::{IntegratorSettings, PreparedIntegrator, SingleIntegrator, SingleSampling};
use niebla::render::RenderOptions;
use niebla::scene::{load_scene, Scene};
use niebla::tracking::{MarchStep, TransmittanceMethod};

use crate::error::CliError;
use crate::flags::{ExposureFlag, MaxMemoryFlag, ThreadsFlag};

/// The `--integrator` values of `preview`: the integrators the registry
/// marks interactive, with their summaries.
fn interactive_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(
        niebla::integrator::registry::INTEGRATORS
            .iter()
            .filter(|e| e.interactive)
            .map(|e| clap::builder::PossibleValue::new(e.name).help(e.summary)),
    )
}

/// Options of `niebla preview`.
#[derive(Args, Debug)]
pub struct PreviewArgs {
    /// Scene file (JSON, version 1).
    pub scene: PathBuf,
    /// The integrator (the scene file's settings when it names the same
    /// integrator, else its defaults; single marches shadow rays too).
    #[arg(long, value_parser = interactive_names(), default_value = "hegeman")]
    pub integrator: String,
    /// Frame width in pixels (default: the scene's).
    #[arg(long)]
    pub width: Option<u32>,
    /// Frame height in pixels (default: the scene's, or the width times the scene's aspect).
    #[arg(long)]
    pub height: Option<u32>,
    /// Samples per pixel per frame.
    #[arg(long, default_value_t = 1)]
    pub spp: u32,
    /// `--max-memory`: the memory limit.
    #[command(flatten)]
    pub max_memory: MaxMemoryFlag,
    /// Stop after this many frames (default: run until interrupted).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Image rewritten after every frame (.png or .exr).
    #[arg(long, short = 'o')]
    pub output: Option<PathBuf>,
    /// Folder for a numbered sequence `frame_00000.png`, ...
    #[arg(long, conflicts_with = "output")]
    pub sequence: Option<PathBuf>,
    /// `--threads`: worker threads.
    #[command(flatten)]
    pub threads: ThreadsFlag,
    /// `--exposure`: exposure of the images, in stops.
    #[command(flatten)]
    pub exposure: ExposureFlag,
}

/// The settings `name` previews with: the scene file's when it names the
/// same integrator, else the defaults; `single` always runs as the
/// interactive ray marcher ([`interactive_single`]).
fn preview_settings(name: &str, from_file: IntegratorSettings) -> IntegratorSettings {
    if name == "single" {
        let SingleIntegrator { step, sampling, transmittance, .. } = interactive_single();
        // The scene file's choice of emissive media as lights is kept.
        let volume_lights = matches!(from_file, IntegratorSettings::Single { volume_lights: true, .. });
        return IntegratorSettings::Single { step, sampling, transmittance, volume_lights };
    }
    if from_file.name() == name {
        return from_file;
    }
    niebla::integrator::registry::defaults(name).expect("clap admits only registered names")
}

/// `single` as an interactive ray marcher: stratified march along the view
/// ray, shadow rays ray-marched with 32 steps per segment.
pub fn interactive_single() -> SingleIntegrator {
    SingleIntegrator {
        step: None,
        sampling: SingleSampling::March,
        transmittance: TransmittanceMethod::RayMarch(MarchStep::Count(32)),
        volume_lights: None,
    }
}

fn modified(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// `niebla preview`.
pub fn run(args: &PreviewArgs) -> Result<(), CliError> {
    if args.spp == 0 {
        return Err(CliError::invalid_option("--spp", "must be at least 1"));
    }
    if args.width == Some(0) || args.height == Some(0) {
        return Err(CliError::invalid_option("--width/--height", "must be at least 1"));
    }
    let threads = args.threads.get()?;
    if let Some(dir) = &args.sequence {
        std::fs::create_dir_all(dir).map_err(|error| CliError::Io { path: dir.clone(), error })?;
    }
    let mut loaded: Option<(SystemTime, Scene, PreparedIntegrator, f32)> = None;
    let mut frame = 0u64;
    let mut last_report = Instant::now();
    let mut frames_since_report = 0u32;
    while args.frames.is_none_or(|n| frame < n) {
        // Reload and precompute again when the file changed.
        let stamp = modified(&args.scene).ok_or_else(|| CliError::SceneNotFound(args.scene.clone()))?;
        if loaded.as_ref().is_none_or(|(t, ..)| *t != stamp) {
            let label = args.scene.display().to_string();
            let loaded_scene =
                load_scene(&args.scene).map_err(|error| CliError::Scene { error, over_memory_limit: false });
            let checked = loaded_scene.and_then(|built| {
                let settings = preview_settings(&args.integrator, built.settings.integrator);
                let limit = args.max_memory.limit();
                crate::load::check_precompute_memory(&label, &settings, &built.scene, limit)?;
                Ok(built)
            });
            match checked {
                Ok(built) => {
                    for warning in &built.warnings {
                        eprintln!("warning: {warning}");
                    }
                    let settings = preview_settings(&args.integrator, built.settings.integrator);
                    let mut scene = built.scene;
                    let aspect = scene.camera.height as f64 / scene.camera.width as f64;
                    let width = args.width.unwrap_or(scene.camera.width);
                    let height = args.height.unwrap_or_else(|| ((width as f64 * aspect).round() as u32).max(1));
                    scene.camera.width = width;
                    scene.camera.height = height;
                    let start = Instant::now();
                    let prepared = PreparedIntegrator::new(&scene, &settings);
                    let exposure = args.exposure.or(built.settings.exposure)?;
                    eprintln!(
                        "preview: {} at {width}x{height}, {}, precomputed in {:.3} s",
                        args.scene.display(),
                        args.integrator,
                        start.elapsed().as_secs_f64()
                    );
                    loaded = Some((stamp, scene, prepared, exposure));
                }
                // A half-saved or broken file: keep showing the last good scene.
                Err(e) if loaded.is_some() => {
                    eprintln!("preview: {e} (keeping the previous version)");
                    if let Some(entry) = loaded.as_mut() {
                        entry.0 = stamp;
                    }
                }
                Err(e) => return Err(e),
            }
        }
        let (_, scene, prepared, exposure) = loaded.as_ref().expect("a scene is loaded");
        let options =
            RenderOptions { spp: args.spp, seed: frame, first_sample: 0, threads, sampler: Default::default() };
        let image = prepared.render(scene, &options, &|_, _| {}, None)?;
        if let Some(path) = &args.output {
            write_image(&image, path, *exposure)?;
        }
        if let Some(dir) = &args.sequence {
            let path = dir.join(format!("frame_{frame:05}.png"));
            write_image(&image, &path, *exposure)?;
        }
        frame += 1;
        frames_since_report += 1;
        let elapsed = last_report.elapsed().as_secs_f64();
        if elapsed >= 1.0 || args.frames == Some(frame) {
            println!("frame {frame}: {:.2} frames/s", frames_since_report as f64 / elapsed);
            last_report = Instant::now();
            frames_since_report = 0;
        }
    }
    Ok(())
}
