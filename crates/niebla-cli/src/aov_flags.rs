//! `niebla render`'s layers: `--aovs`, `--transparent` and the scene's
//! `film` object combined and checked, resumed checkpoints' layer sums, and
//! `--denoise` (its library, its feature layers, its outputs).

use std::path::Path;

use niebla::aov::{read_aov_sums, unsupported_reason, Aov, AovSet};
use niebla::integrator::IntegratorSettings;
use niebla::progressive::Accumulator;
use niebla::scene::BuiltScene;

use crate::error::CliError;

/// The layers to render: the scene's `film.aovs`, those of `--aovs` and
/// alpha when the film is transparent (`--transparent` sets the scene's
/// flag); an error for unknown names or layers the integrator cannot give.
pub fn layers(
    built: &mut BuiltScene,
    list: Option<&str>,
    transparent: bool,
    integrator: &IntegratorSettings,
) -> Result<AovSet, CliError> {
    let mut set = built.settings.film.aovs;
    if let Some(list) = list {
        set = set.union(AovSet::parse_list(list).map_err(|e| CliError::invalid_option("--aovs", e))?);
    }
    if transparent {
        built.scene.transparent_background = true;
    }
    if built.scene.transparent_background {
        set = set.with(Aov::Alpha);
    }
    if let Some(reason) = unsupported_reason(set, integrator) {
        let option = if list.is_some() { "--aovs" } else { "--integrator" };
        return Err(CliError::invalid_option(option, reason));
    }
    Ok(set)
}

/// The accumulator of a resumed render with the layer sums of its
/// checkpoint at `path`, which must hold exactly the layers `set` (a
/// render without layers resumes as before and ignores any stored).
pub fn resume_layers(path: &Path, acc: Accumulator, set: AovSet, transparent: bool) -> Result<Accumulator, CliError> {
    if set.is_empty() {
        return Ok(acc);
    }
    let (w, h) = (acc.sums().width, acc.sums().height);
    let mismatch = |problem: String| CliError::CheckpointMismatch { path: path.to_path_buf(), problem };
    match read_aov_sums(path, set, transparent, w, h) {
        Ok(Some(sums)) => Ok(acc.with_aovs(sums)),
        Ok(None) => Err(mismatch(
            "holds no layer sums; resume without --aovs/--transparent, or render the layers from the start".into(),
        )),
        Err(e) => Err(mismatch(e)),
    }
}

/// The OIDN library when `--denoise` is asked for (loaded before
/// rendering, so a missing library is reported at once).
pub fn denoiser(asked: bool) -> Result<Option<niebla::denoise::Denoiser>, CliError> {
    if !asked {
        return Ok(None);
    }
    niebla::denoise::Denoiser::load().map(Some).map_err(|e| CliError::invalid_option("--denoise", e.to_string()))
}

/// `set` with the albedo and normal layers the denoiser is guided by.
pub fn with_denoise_features(set: AovSet, denoise: bool, integrator: &IntegratorSettings) -> Result<AovSet, CliError> {
    if !denoise {
        return Ok(set);
    }
    let set = set.with(Aov::Albedo).with(Aov::Normal);
    match unsupported_reason(set, integrator) {
        Some(reason) => Err(CliError::invalid_option("--denoise", reason)),
        None => Ok(set),
    }
}

/// Denoises the final image with its albedo and normal layers and writes
/// it beside each output (`niebla::denoise::denoised_path`), the raw
/// outputs staying as written.
pub fn write_denoised(
    denoiser: &niebla::denoise::Denoiser,
    acc: &Accumulator,
    outputs: &[std::path::PathBuf],
    exposure: f32,
) -> Result<(), CliError> {
    let image = acc.image();
    let layers = acc.aov_image().expect("--denoise renders the albedo and normal layers");
    let (albedo, normal) = (layers.get(Aov::Albedo).expect("albedo"), layers.get(Aov::Normal).expect("normal"));
    let n = image.pixels.len();
    let albedo: Vec<_> = (0..n).map(|i| albedo.rgb(i)).collect();
    let normal: Vec<[f32; 3]> = (0..n).map(|i| normal.vec3(i).to_array()).collect();
    let denoised = denoiser
        .denoise(&image, Some(&albedo), Some(&normal))
        .map_err(|e| CliError::invalid_option("--denoise", e.to_string()))?;
    for out in outputs {
        niebla::film::write_image(&denoised, &niebla::denoise::denoised_path(out), exposure)?;
    }
    Ok(())
}
