//! The one place where a scene file's format is chosen: `.xml` files are
//! Mitsuba 3 scenes converted by [`super::mitsuba`], anything else is niebla
//! JSON. The command line and the Python package read files through
//! [`read_scene_source`].

use std::path::Path;

use super::frames::FrameNumber;
use super::mitsuba::{import_mitsuba_file, is_mitsuba_path};
use super::{parse_scene_frame, SceneDesc, SceneError};

/// A scene file read and parsed.
#[derive(Clone, Debug)]
pub struct SceneSource {
    /// The parsed, validated description.
    pub desc: SceneDesc,
    /// The niebla JSON text the description was read from (for an XML
    /// scene, its conversion, `-D` values applied); hashed into checkpoints.
    pub text: String,
    /// Accepted-but-ignored elements of an XML scene (`file:line: ...`);
    /// empty for JSON.
    pub notes: Vec<String>,
    /// The scene value the description was read from: keyframes removed
    /// and, for a frame of a sequence, applied and its file names put in.
    pub value: serde_json::Value,
}

/// Reads the scene file `path`: niebla JSON, or Mitsuba 3 XML (extension
/// `.xml`) with `defines` (`-D name=value`, which only XML scenes take).
/// Relative file names resolve against the file's folder in both cases.
pub fn read_scene_source(path: &Path, defines: &[(String, String)]) -> Result<SceneSource, SceneError> {
    read_scene_source_frame(path, defines, None)
}

/// [`read_scene_source`] for `frame` of a sequence (see
/// [`super::frames`]); with `None` the same. For a frame, `text` is the
/// frame's scene value written as JSON (so checkpoints of different frames
/// record different scene hashes).
pub fn read_scene_source_frame(
    path: &Path,
    defines: &[(String, String)],
    frame: Option<FrameNumber>,
) -> Result<SceneSource, SceneError> {
    let source = path.display().to_string();
    if is_mitsuba_path(path) {
        let base = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let import = import_mitsuba_file(path, defines, base)?;
        let text = serde_json::to_string_pretty(&import.scene)
            .map_err(|e| SceneError::new(&source, "", format!("cannot write the converted scene: {e}")))?;
        let (desc, value) = parse_scene_frame(&text, &format!("{source} (converted to niebla JSON)"), frame)?;
        let text = frame_text(text, &value, frame);
        return Ok(SceneSource { desc, text, notes: import.notes, value });
    }
    if let Some((name, _)) = defines.first() {
        return Err(SceneError::new(
            &source,
            "",
            format!("-D {name}=...: parameters apply to Mitsuba XML scenes (.xml) only"),
        ));
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::new(&source, "", format!("cannot read scene file: {e}")))?;
    let (desc, value) = parse_scene_frame(&text, &source, frame)?;
    let text = frame_text(text, &value, frame);
    Ok(SceneSource { desc, text, notes: Vec::new(), value })
}

/// The text a scene source records: the file's for a still render, the
/// frame's scene value as JSON for a frame of a sequence.
fn frame_text(text: String, value: &serde_json::Value, frame: Option<FrameNumber>) -> String {
    match frame {
        None => text,
        Some(_) => serde_json::to_string_pretty(value).unwrap_or(text),
    }
}
