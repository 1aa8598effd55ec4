//! `niebla convert`: a Mitsuba 3 XML scene into the niebla scene (JSON) that
//! renders the same, the same conversion `render` and `info` apply.

use std::path::{Path, PathBuf};

use clap::Args;
use niebla::scene::mitsuba::{import_mitsuba_file, is_mitsuba_path};
use niebla::scene::{parse_scene_str, SceneError};

use crate::error::CliError;
use crate::flags::DefineFlag;

/// Options of `niebla convert`.
#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// Mitsuba 3 scene (.xml).
    pub scene: PathBuf,
    /// The niebla scene to write (.json); file names in it are written
    /// relative to its folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// `-D NAME=VALUE`: parameters of the XML scene.
    #[command(flatten)]
    pub define: DefineFlag,
}

/// `niebla convert`.
pub fn run(args: &ConvertArgs) -> Result<(), CliError> {
    let scene_error = |error: SceneError| CliError::Scene { error, over_memory_limit: false };
    if !args.scene.exists() {
        return Err(CliError::SceneNotFound(args.scene.clone()));
    }
    if !is_mitsuba_path(&args.scene) {
        return Err(CliError::InvalidOption {
            option: "SCENE",
            problem: format!("{}: convert reads Mitsuba 3 XML scenes (.xml)", args.scene.display()),
        });
    }
    let out_dir = match args.output.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !out_dir.is_dir() {
        return Err(CliError::OutputFolderMissing { path: args.output.clone(), folder: out_dir });
    }
    let import = import_mitsuba_file(&args.scene, &args.define.define, &out_dir).map_err(scene_error)?;
    let mut text = serde_json::to_string_pretty(&import.scene)
        .map_err(|e| CliError::Io { path: args.output.clone(), error: std::io::Error::other(e) })?;
    text.push('\n');
    // The result must be a scene niebla reads; checked before anything is written.
    parse_scene_str(&text, &format!("{} (converted)", args.scene.display())).map_err(scene_error)?;
    write_atomically(&args.output, text.as_bytes())
        .map_err(|error| CliError::Io { path: args.output.clone(), error })?;
    for note in &import.notes {
        eprintln!("note: {note}");
    }
    Ok(())
}

/// Writes `bytes` to a temporary file beside `path`, then renames it over
/// `path`, so that no half-written file is left.
fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = path.with_file_name(format!(".{name}.partial"));
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}
