//! Which files an edited scene may name: a scene sent by the page may only
//! refer (through its `file` fields: grids, meshes, textures, tabulated
//! phase functions, environment maps) to files inside the folder of the
//! scene being viewed, or to the very files the original scene named.
//! The server itself serves no files from disk, only its built-in assets.

use std::path::{Component, Path};

use serde_json::Value;

/// Every `file` string of `scene` with its JSON path (e.g.
/// `media.plume.density.file`), in document order.
pub fn file_fields(scene: &Value) -> Vec<(String, String)> {
    let mut out = Vec::new();
    collect(scene, String::new(), &mut out);
    out
}

fn collect(value: &Value, path: String, out: &mut Vec<(String, String)>) {
    let join = |key: &str| if path.is_empty() { key.to_string() } else { format!("{path}.{key}") };
    match value {
        Value::Object(map) => {
            for (key, v) in map {
                match v {
                    Value::String(s) if key == "file" => out.push((join(key), s.clone())),
                    _ => collect(v, join(key), out),
                }
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                collect(v, format!("{path}[{i}]"), out);
            }
        }
        _ => {}
    }
}

/// Check the `file` fields of an edited `scene` against the scene folder
/// `base`: each must be one the original scene named (`allowed`), or a
/// relative path without `..` whose resolved location (symbolic links
/// followed, when the file exists) lies inside `base`. The error names the
/// JSON path.
pub fn check_scene_files(scene: &Value, base: &Path, allowed: &[String]) -> Result<(), String> {
    let base_real = base.canonicalize().unwrap_or_else(|_| base.to_path_buf());
    for (path, file) in file_fields(scene) {
        if allowed.iter().any(|a| a == &file) {
            continue;
        }
        let refuse =
            || Err(format!("{path}: {file:?} is outside the scene's folder; the viewer reads files only inside it"));
        let relative = Path::new(&file);
        if relative.is_absolute()
            || relative.components().any(|c| !matches!(c, Component::Normal(_) | Component::CurDir))
        {
            return refuse();
        }
        if let Ok(real) = base.join(relative).canonicalize() {
            if !real.starts_with(&base_real) {
                return refuse();
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_outside_the_folder_are_refused() {
        let dir = std::env::temp_dir().join(format!("niebla-view-paths-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("grids")).unwrap();
        let scene = |file: &str| serde_json::json!({"media": {"m": {"density": {"type": "vdb", "file": file}}}});
        let allowed = vec!["../shared/cloud.vdb".to_string()];
        assert!(check_scene_files(&scene("grids/a.vdb"), &dir, &allowed).is_ok());
        assert!(check_scene_files(&scene("../shared/cloud.vdb"), &dir, &allowed).is_ok());
        for bad in ["../secret.vdb", "/etc/passwd", "grids/../../x.vdb"] {
            let error = check_scene_files(&scene(bad), &dir, &allowed).unwrap_err();
            assert!(error.starts_with("media.m.density.file: "), "{error}");
        }
        #[cfg(unix)]
        {
            let link = dir.join("escape");
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink("/etc", &link).unwrap();
            assert!(check_scene_files(&scene("escape/passwd"), &dir, &allowed).is_err());
        }
        assert_eq!(file_fields(&serde_json::json!({"shapes": [{"file": "a.ply"}]}))[0].0, "shapes[0].file");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
