//! Mitsuba 3 XML scenes: the importer turns a scene file into the niebla
//! scene description it renders as (the JSON object a niebla scene file
//! holds) plus notes on what it accepted without effect. niebla's usual
//! parser then reads that JSON, so an XML scene gets every check a JSON scene
//! gets.
//!
//! Concerns, one file each: `xml` (syntax, `<default>`/`$name`,
//! `<include>`, `<path>`, positions), `props` (typed properties),
//! `transform` (`<transform>` operations), `convert` (ids, `<ref>`s, the
//! top level), `sensor` (camera, film, sampler, integrator), `shapes`,
//! `emitters`, `media` (media, phases, volumes), `bsdfs`, `textures`.
//!
//! Conventions are Mitsuba's, converted exactly: `max_depth` N is niebla's
//! `volpath` N - 1 (Mitsuba counts path segments, niebla scattering
//! events); `fov` on any `fov_axis` becomes niebla's vertical `fov_y`; a
//! `cube` is niebla's `box` when its `to_world` is an axis-aligned scale and
//! translation, else a 12-triangle mesh; lights keep their numbers (niebla
//! follows Mitsuba 3's radiometry). Errors name `file:line` and the element.

mod bsdfs;
mod convert;
mod emitters;
mod media;
mod props;
mod sensor;
mod shapes;
mod textures;
mod transform;
mod xml;

use std::path::Path;

use crate::scene::SceneError;

/// A Mitsuba scene converted to niebla's description.
#[derive(Clone, Debug, PartialEq)]
pub struct MitsubaImport {
    /// The niebla scene (a JSON object of version 1); file names in it are
    /// relative to the `out_base` folder given to the importer, or absolute.
    pub scene: serde_json::Value,
    /// Accepted-but-ignored elements, each `file:line: element: what happens`.
    pub notes: Vec<String>,
}

/// Whether `path` names a Mitsuba XML scene (extension `.xml`, any case).
pub fn is_mitsuba_path(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml"))
}

/// Converts the Mitsuba 3 XML scene at `path`. `defines` are command-line
/// `-D name=value` pairs (they win over the file's `<default>`s); file names
/// in the result are written relative to `out_base` (the folder the niebla
/// scene will be read from) when they lie under it, else absolute.
///
/// ```
/// let dir = std::env::temp_dir().join("niebla_mitsuba_doc");
/// std::fs::create_dir_all(&dir).unwrap();
/// let xml = dir.join("s.xml");
/// std::fs::write(&xml, r#"<scene version="3.0.0">
///   <default name="spp" value="8"/>
///   <sensor type="perspective"><float name="fov" value="40"/><string name="fov_axis" value="y"/>
///     <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
///     <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/>
///       <rfilter type="box"/></film></sensor>
///   <bsdf type="hair"/>
/// </scene>"#).unwrap();
/// let err = niebla::scene::mitsuba::import_mitsuba_file(&xml, &[], &dir).unwrap_err();
/// assert!(err.to_string().ends_with("s.xml:7: <bsdf type=\"hair\">: not supported at the top level of a scene"), "{err}");
/// ```
pub fn import_mitsuba_file(
    path: &Path,
    defines: &[(String, String)],
    out_base: &Path,
) -> Result<MitsubaImport, SceneError> {
    let xml = xml::read_scene_file(path, defines)?;
    convert_xml(&xml, out_base)
}

/// Converts Mitsuba XML text; `file` names it in messages and `dir` is the
/// folder its relative file names start from (as for [`import_mitsuba_file`]).
pub fn import_mitsuba_str(
    text: &str,
    file: &str,
    dir: &Path,
    defines: &[(String, String)],
) -> Result<MitsubaImport, SceneError> {
    let xml = xml::read_scene_str(text, file, dir, defines)?;
    convert_xml(&xml, dir)
}

fn convert_xml(xml: &xml::SceneXml, out_base: &Path) -> Result<MitsubaImport, SceneError> {
    let (scene, notes) = convert::Converter::new(xml, out_base)?.run()?;
    Ok(MitsubaImport { scene, notes })
}

/// Parses `name=value` (a command-line `-D`).
pub fn parse_define(text: &str) -> Result<(String, String), String> {
    match text.split_once('=') {
        Some((k, v)) if !k.is_empty() && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') => {
            Ok((k.to_string(), v.to_string()))
        }
        _ => Err(format!("expected NAME=VALUE (a name of letters, digits and _), got \"{text}\"")),
    }
}

#[cfg(test)]
mod tests;
