//! The one place where a scene file's format is chosen: `.xml` files are
//! Mitsuba 3 scenes converted by [`super::mitsuba`], anything else is niebla
//! JSON. The command line and the Python package read files through
//! [`read_scene_source`].

use std::path::Path;

use super::mitsuba::{import_mitsuba_file, is_mitsuba_path};
use super::{parse_scene_str, SceneDesc, SceneError};

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
}

/// Reads the scene file `path`: niebla JSON, or Mitsuba 3 XML (extension
/// `.xml`) with `defines` (`-D name=value`, which only XML scenes take).
/// Relative file names resolve against the file's folder in both cases.
pub fn read_scene_source(path: &Path, defines: &[(String, String)]) -> Result<SceneSource, SceneError> {
    let source = path.display().to_string();
    if is_mitsuba_path(path) {
        let base = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        let import = import_mitsuba_file(path, defines, base)?;
        let text = serde_json::to_string_pretty(&import.scene)
            .map_err(|e| SceneError::new(&source, "", format!("cannot write the converted scene: {e}")))?;
        let desc = parse_scene_str(&text, &format!("{source} (converted to niebla JSON)"))?;
        return Ok(SceneSource { desc, text, notes: import.notes });
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
    let desc = parse_scene_str(&text, &source)?;
    Ok(SceneSource { desc, text, notes: Vec::new() })
}
