//! Options that several commands take, each defined once with its help text
//! and its check, and included in a command's options with
//! `#[command(flatten)]`; plus the checks shared by options that differ in
//! name only (a number of seconds, an output file's folder).

use std::path::Path;

use clap::Args;

use crate::error::CliError;

/// `--threads N`.
#[derive(Args, Clone, Copy, Debug)]
pub struct ThreadsFlag {
    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
}

impl ThreadsFlag {
    /// The thread count asked for (`None`: all cores); 0 is refused.
    pub fn get(&self) -> Result<Option<usize>, CliError> {
        match self.threads {
            Some(0) => Err(CliError::invalid_option("--threads", "must be at least 1")),
            n => Ok(n),
        }
    }
}

/// `--seed N`.
#[derive(Args, Clone, Copy, Debug)]
pub struct SeedFlag {
    /// Sampler seed (overrides the scene's `render.seed`).
    #[arg(long)]
    pub seed: Option<u64>,
}

impl SeedFlag {
    /// The seed asked for, else the scene's.
    pub fn or(&self, scene_seed: u64) -> u64 {
        self.seed.unwrap_or(scene_seed)
    }
}

/// `--exposure STOPS`.
#[derive(Args, Clone, Copy, Debug)]
pub struct ExposureFlag {
    /// Exposure in stops of the images to look at (PNG, the compare report):
    /// they show the radiance times 2^E (overrides the scene's
    /// `render.exposure`). EXR images are never scaled.
    #[arg(long, allow_negative_numbers = true)]
    pub exposure: Option<f32>,
}

impl ExposureFlag {
    /// The exposure asked for, else the scene's; it must be finite.
    pub fn or(&self, scene_exposure: f32) -> Result<f32, CliError> {
        let exposure = self.exposure.unwrap_or(scene_exposure);
        if exposure.is_finite() {
            Ok(exposure)
        } else {
            Err(CliError::invalid_option("--exposure", "must be a finite number of stops"))
        }
    }
}

/// `--quiet`.
#[derive(Args, Clone, Copy, Debug)]
pub struct QuietFlag {
    /// Do not draw progress bars.
    #[arg(long)]
    pub quiet: bool,
}

/// `--max-memory SIZE`.
#[derive(Args, Clone, Copy, Debug)]
pub struct MaxMemoryFlag {
    /// Most memory the render may take for its image, grids, files and
    /// precomputation, e.g. 8G, 512M (binary units); a scene needing more is
    /// refused before anything large is allocated. Default: half of the
    /// machine's memory.
    #[arg(long, value_parser = niebla::limits::parse_memory_size)]
    pub max_memory: Option<u64>,
}

impl MaxMemoryFlag {
    /// The limit in bytes: the one asked for, else half of the machine's memory.
    pub fn limit(&self) -> u64 {
        self.max_memory.unwrap_or_else(niebla::limits::default_memory_limit)
    }
}

/// `t` if it is a positive, finite number of seconds (below 1e7), else the
/// error of `option`.
pub fn positive_seconds(option: &'static str, t: f64) -> Result<f64, CliError> {
    if t.is_finite() && t > 0.0 && t < 1e7 {
        Ok(t)
    } else {
        Err(CliError::invalid_option(option, format!("expected a positive number of seconds, got {t}")))
    }
}

/// Refuses an output file whose folder does not exist (before anything is
/// rendered).
pub fn check_output_folder(path: &Path) -> Result<(), CliError> {
    match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) if !dir.is_dir() => {
            Err(CliError::OutputFolderMissing { path: path.to_path_buf(), folder: dir.to_path_buf() })
        }
        _ => Ok(()),
    }
}

/// `-D NAME=VALUE` (repeatable): values of a Mitsuba XML scene's
/// `<default>` parameters.
#[derive(Args, Clone, Debug, Default)]
pub struct DefineFlag {
    /// Set a Mitsuba XML scene's parameter (`<default name="NAME">`, used as
    /// `$NAME`), e.g. `-D spp=64`; repeatable. XML scenes only.
    #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = niebla::scene::mitsuba::parse_define)]
    pub define: Vec<(String, String)>,
}
