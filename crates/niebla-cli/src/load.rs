//! Loading a scene for a command: the file named on the command line or the
//! built-in default, within a memory limit, and the memory check of an
//! integrator's precomputation.

use std::path::{Path, PathBuf};

use niebla::film::{render_memory, scene_hash};
use niebla::integrator::IntegratorSettings;
use niebla::limits::default_memory_limit;
use niebla::scene::frames::FrameNumber;
use niebla::scene::{
    build_scene_cached, parse_scene_str, read_scene_source, read_scene_source_frame, BuildOptions, BuiltScene,
    SceneCache, SceneDesc, DEFAULT_SCENE,
};

use crate::error::CliError;

/// Load the scene named on the command line, or the built-in default, within
/// the default memory limit.
pub fn load(scene: Option<&Path>) -> Result<(BuiltScene, String), CliError> {
    load_limited(scene, default_memory_limit()).map(|l| (l.built, l.stem))
}

/// Like [`load`], with `-D` parameters for a Mitsuba XML scene; also returns
/// the XML importer's notes.
pub fn load_defined(scene: Option<&Path>, defines: &[(String, String)]) -> Result<(BuiltScene, Vec<String>), CliError> {
    load_limited_defined(scene, default_memory_limit(), defines).map(|l| (l.built, l.notes))
}

/// A scene loaded for rendering.
pub struct LoadedScene {
    /// The built scene and its render settings.
    pub built: BuiltScene,
    /// Output file stem: the scene file's, or `niebla`.
    pub stem: String,
    /// [`scene_hash`] of the scene text (recorded in checkpoints; for a
    /// Mitsuba XML scene, of its conversion to niebla JSON).
    pub hash: String,
    /// Accepted-but-ignored elements of a Mitsuba XML scene.
    pub notes: Vec<String>,
}

/// Load the scene (or the built-in default), printing its warnings to
/// stderr, refusing before allocating
/// anything large an image whose render buffers, or grids and files, would
/// take more than `max_memory` bytes together.
pub fn load_limited(scene: Option<&Path>, max_memory: u64) -> Result<LoadedScene, CliError> {
    load_limited_defined(scene, max_memory, &[])
}

/// [`load_limited`] with `-D` parameters of a Mitsuba XML scene (an error
/// for other scenes when not empty).
pub fn load_limited_defined(
    scene: Option<&Path>,
    max_memory: u64,
    defines: &[(String, String)],
) -> Result<LoadedScene, CliError> {
    let scene_error = |error| CliError::Scene { error, over_memory_limit: false };
    let (desc, text, source, base, stem, notes) = match scene {
        Some(path) => {
            if !path.exists() {
                return Err(CliError::SceneNotFound(path.to_path_buf()));
            }
            let source = path.display().to_string();
            let read = read_scene_source(path, defines).map_err(scene_error)?;
            let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
            let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "niebla".into());
            (read.desc, read.text, source, base, stem, read.notes)
        }
        None => {
            if let Some((name, _)) = defines.first() {
                return Err(CliError::InvalidOption {
                    option: "-D",
                    problem: format!("{name}=...: parameters apply to Mitsuba XML scenes only"),
                });
            }
            let text = DEFAULT_SCENE.to_string();
            let source = "<default scene>".to_string();
            let desc = parse_scene_str(&text, &source).map_err(scene_error)?;
            (desc, text, source, PathBuf::from("."), "niebla".to_string(), Vec::new())
        }
    };
    let read = ReadScene { desc, text, source, base, stem, notes, value: serde_json::Value::Null };
    build_read(read, max_memory, &SceneCache::default())
}

/// A scene file read and parsed, not yet built.
pub struct ReadScene {
    /// The description.
    pub desc: SceneDesc,
    /// The text hashed into checkpoints.
    pub text: String,
    /// The scene's name in messages.
    pub source: String,
    /// The folder relative file names resolve against.
    pub base: PathBuf,
    /// Output file stem.
    pub stem: String,
    /// Notes of the XML importer.
    pub notes: Vec<String>,
    /// The scene value read (for a frame: keyframes applied, file names put in).
    pub value: serde_json::Value,
}

/// Reads frame `frame` of the sequence scene file `path` (see
/// [`niebla::scene::frames`]).
pub fn read_frame(path: &Path, defines: &[(String, String)], frame: FrameNumber) -> Result<ReadScene, CliError> {
    if !path.exists() {
        return Err(CliError::SceneNotFound(path.to_path_buf()));
    }
    let read = read_scene_source_frame(path, defines, Some(frame))
        .map_err(|error| CliError::Scene { error, over_memory_limit: false })?;
    Ok(ReadScene {
        desc: read.desc,
        text: read.text,
        source: path.display().to_string(),
        base: path.parent().unwrap_or(Path::new(".")).to_path_buf(),
        stem: path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "niebla".into()),
        notes: read.notes,
        value: read.value,
    })
}

/// Builds a scene read by [`read_frame`] (or the still scene) within
/// `max_memory`, taking unchanged files from `cache`; prints its warnings.
pub fn build_read(read: ReadScene, max_memory: u64, cache: &SceneCache) -> Result<LoadedScene, CliError> {
    let ReadScene { desc, text, source, base, stem, notes, .. } = read;
    let niebla::scene::CameraDesc::Perspective(camera) = &desc.camera;
    let image_bytes = render_memory(camera.width, camera.height);
    if image_bytes > max_memory {
        return Err(CliError::ImageOverMemoryLimit {
            scene: source,
            width: camera.width,
            height: camera.height,
            bytes: image_bytes,
            limit: max_memory,
        });
    }
    let options = BuildOptions { max_memory: max_memory - image_bytes };
    // The scene builder reports the memory limit in its message only (its
    // MemoryBudget's words), so that is where the hint's condition is read.
    let built = build_scene_cached(&desc, &source, &base, &options, cache).map_err(|error| {
        let over_memory_limit = error.message.contains("memory limit");
        CliError::Scene { error, over_memory_limit }
    })?;
    for warning in &built.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(LoadedScene { built, stem, hash: scene_hash(text.as_bytes()), notes })
}

/// Refuse `settings` when its precomputation (photon maps, lattices) would
/// take more than `left` bytes: the error names the scene (`source`), the
/// field to lower and the estimated size.
pub fn check_precompute_memory(
    source: &str,
    settings: &IntegratorSettings,
    scene: &niebla::scene::Scene,
    left: u64,
) -> Result<(), CliError> {
    match niebla::integrator::precompute_memory(settings, scene) {
        Some(m) if m.bytes > left => Err(CliError::PrecomputeOverMemoryLimit {
            scene: source.to_string(),
            field: m.field,
            what: m.what,
            bytes: m.bytes,
            left,
        }),
        _ => Ok(()),
    }
}

/// The name of a scene in messages: its path, or `<default scene>`.
pub fn scene_label(scene: Option<&Path>) -> String {
    scene.map_or_else(|| "<default scene>".to_string(), |p| p.display().to_string())
}
