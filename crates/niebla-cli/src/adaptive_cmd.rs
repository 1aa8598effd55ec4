//! `niebla render --adaptive THRESHOLD`: an unbiased adaptive render
//! (`niebla::adaptive`), written as an EXR with the samples-per-pixel map
//! and the variance and any layers, or a PNG of the image (RGBA with alpha). Adaptive renders use the
//! independent sampler whatever the scene says (see `niebla::adaptive`).
//! `niebla render --adaptive-pilot`: samples allocated by an independent
//! pilot (`niebla::adaptive::pilot`), written the same way, with any sampler.

use std::path::PathBuf;
use std::time::Instant;

use niebla::adaptive::pilot::{render_pilot, write_pilot_exr, PilotOptions};
use niebla::adaptive::{render_adaptive, write_adaptive_exr, AdaptiveOptions, StopRule};
use niebla::aov::{Aov, AovSet};
use niebla::integrator::IntegratorSettings;
use niebla::scene::Scene;

use crate::error::CliError;

/// What the command line asks of an adaptive render.
pub struct AdaptiveRun {
    /// Relative standard error at which a pixel stops.
    pub threshold: f32,
    /// The most samples a pixel takes.
    pub spp: u32,
    /// Sampler seed.
    pub seed: u64,
    /// Worker threads.
    pub threads: Option<usize>,
    /// PNG exposure.
    pub exposure: f32,
    /// No progress output.
    pub quiet: bool,
    /// Layers to render (`--aovs`, the scene's `film.aovs`, alpha when transparent).
    pub layers: AovSet,
    /// When a pixel stops (`--adaptive-cost`: by cost).
    pub rule: StopRule,
}

/// Checks the request, renders and writes the outputs.
pub fn run(
    scene: &Scene,
    integrator: &IntegratorSettings,
    run: &AdaptiveRun,
    first_sample: u64,
    outputs: &[PathBuf],
) -> Result<(), CliError> {
    if !(run.threshold > 0.0 && run.threshold < 1.0) {
        return Err(CliError::invalid_option("--adaptive", format!("must lie in (0, 1), got {}", run.threshold)));
    }
    if first_sample != 0 {
        return Err(CliError::invalid_option("--adaptive", "renders from sample 0 (no --first-sample)"));
    }
    if matches!(integrator, IntegratorSettings::Photon(_) | IntegratorSettings::Ppm(_) | IntegratorSettings::Ppb(_)) {
        return Err(CliError::invalid_option(
            "--adaptive",
            format!("the {} integrator has no per-pixel sample sums", integrator.name()),
        ));
    }
    let options = AdaptiveOptions {
        spp: run.spp,
        threshold: run.threshold,
        seed: run.seed,
        threads: run.threads,
        layers: run.layers,
        rule: run.rule,
    };
    let start = Instant::now();
    let result = render_adaptive(scene, integrator, &options, &|_, _| {}, None)?;
    let seconds = start.elapsed().as_secs_f64();
    for out in outputs {
        if out.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
            write_adaptive_exr(&result, run.threshold, out)?;
        } else if let Some(alpha) = result.layers.as_ref().and_then(|l| l.get(Aov::Alpha)) {
            niebla::aov::write_rgba_png(&result.image, &alpha.data, out, run.exposure)?;
        } else {
            niebla::film::write_image(&result.image, out, run.exposure)?;
        }
    }
    let taken: u64 = result.spp.iter().sum();
    if !run.quiet {
        println!(
            "rendered {}x{} adaptively (threshold {}{}, at most {} spp, mean {:.1} spp) with {} in {seconds:.2} s",
            scene.camera.width,
            scene.camera.height,
            run.threshold,
            if run.rule == StopRule::Cost { " by cost" } else { "" },
            result.total_spp,
            taken as f64 / result.spp.len().max(1) as f64,
            integrator.name(),
        );
    }
    Ok(())
}

/// What the command line asks of a pilot-allocated render.
pub struct PilotRun {
    /// The render's options (spp the mean of pass 2).
    pub options: PilotOptions,
    /// PNG exposure.
    pub exposure: f32,
    /// No progress output.
    pub quiet: bool,
}

/// Checks the request, renders with a pilot allocation and writes the outputs.
pub fn run_pilot(
    scene: &Scene,
    integrator: &IntegratorSettings,
    run: &PilotRun,
    first_sample: u64,
    outputs: &[PathBuf],
) -> Result<(), CliError> {
    if run.options.pilot_spp < 2 {
        return Err(CliError::invalid_option(
            "--pilot-spp",
            format!("must be at least 2 (a variance needs two samples), got {}", run.options.pilot_spp),
        ));
    }
    if first_sample != 0 {
        return Err(CliError::invalid_option("--adaptive-pilot", "renders from sample 0 (no --first-sample)"));
    }
    if matches!(integrator, IntegratorSettings::Photon(_) | IntegratorSettings::Ppm(_) | IntegratorSettings::Ppb(_)) {
        return Err(CliError::invalid_option(
            "--adaptive-pilot",
            format!("the {} integrator has no per-pixel sample sums", integrator.name()),
        ));
    }
    let start = Instant::now();
    let result = render_pilot(scene, integrator, &run.options, None)?;
    let seconds = start.elapsed().as_secs_f64();
    for out in outputs {
        if out.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
            write_pilot_exr(&result, out)?;
        } else if let Some(alpha) = result.layers.as_ref().and_then(|l| l.get(Aov::Alpha)) {
            niebla::aov::write_rgba_png(&result.image, &alpha.data, out, run.exposure)?;
        } else {
            niebla::film::write_image(&result.image, out, run.exposure)?;
        }
    }
    if !run.quiet {
        let (least, most) =
            (result.spp.iter().min().copied().unwrap_or(0), result.spp.iter().max().copied().unwrap_or(0));
        println!(
            "rendered {}x{} with a pilot allocation ({} pilot spp, then {} spp on average, {least} to {most}, {} sampler) with {} in {seconds:.2} s",
            scene.camera.width,
            scene.camera.height,
            result.pilot_spp,
            run.options.spp,
            run.options.sampler.name(),
            integrator.name(),
        );
    }
    Ok(())
}
