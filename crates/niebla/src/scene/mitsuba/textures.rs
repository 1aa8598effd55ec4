//! `<texture>`: `bitmap` and `checkerboard` into niebla textures, for the
//! colors niebla's surfaces can texture (a diffuse `reflectance`, a plastic's
//! `diffuse_reflectance`, a rough conductor's `specular_reflectance`).
//!
//! uv conventions: Mitsuba 3's bitmap puts `v = 0` at the image's top row,
//! niebla's at the bottom, so a bitmap's niebla `to_uv` is Mitsuba's `to_uv`
//! followed by `v -> 1 - v`. The shapes' own uvs are Mitsuba's (meshes get
//! Mitsuba's `flip_tex_coords`, see `shapes`). Mitsuba's `to_uv` is a 4x4
//! transform of which the bitmap uses rows and columns 0, 1 and 3 (so
//! `<translate x=".." y=".."/>` shifts u and v). A checkerboard has no image
//! orientation: its `to_uv` is copied as it is.

use serde_json::{json, Value};

use super::convert::{color_json, Converter};
use super::props::Props;
use super::transform::Mat4;
use super::xml::Node;
use crate::scene::SceneError;

/// The color property `name` of `p` as niebla JSON: a texture object for a
/// nested `<texture>` (or a `<ref>` to one), else the constant color; `None`
/// when the property is absent.
pub(super) fn color_or_texture<'a>(
    c: &mut Converter<'a>,
    p: &Props<'a>,
    name: &str,
) -> Result<Option<Value>, SceneError> {
    if let Some(node) = p.plugin_named(name) {
        let node = c.resolve(node, "texture")?;
        return convert_texture(c, node).map(Some);
    }
    Ok(p.color(name)?.map(color_json))
}

/// Whether niebla JSON `v` (a surface) holds a texture object.
pub(super) fn has_texture(v: &Value) -> bool {
    match v {
        Value::Object(o) => {
            matches!(o.get("type").and_then(Value::as_str), Some("bitmap" | "checkerboard"))
                || o.values().any(has_texture)
        }
        Value::Array(a) => a.iter().any(has_texture),
        _ => false,
    }
}

/// A string property restricted to `allowed` (the first is the default);
/// an error at the property's own line otherwise.
fn choice<'a>(p: &Props<'a>, name: &str, allowed: &[&'a str]) -> Result<&'a str, SceneError> {
    let Some(v) = p.string(name)? else { return Ok(allowed[0]) };
    if let Some(a) = allowed.iter().find(|a| **a == v) {
        return Ok(*a);
    }
    let line = p.node.children.iter().find(|c| c.attr("name") == Some(name)).map_or(&p.node.loc, |c| &c.loc);
    Err(line.error(format!("{}: `{name}` \"{v}\": expected {}", p.what(), allowed.join(", "))))
}

/// Mitsuba's `to_uv` as the rows of a 2D affine map (rows and columns 0, 1
/// and 3 of the 4x4 matrix); a projective one is an error.
fn to_uv_rows(p: &Props, m: &Mat4) -> Result<[[f64; 3]; 2], SceneError> {
    if m[3][0].abs() > 1e-9 || m[3][1].abs() > 1e-9 || (m[3][3] - 1.0).abs() > 1e-9 {
        return Err(p.error("`to_uv`: a projective uv transform is not supported (expected an affine one)"));
    }
    Ok([[m[0][0], m[0][1], m[0][3]], [m[1][0], m[1][1], m[1][3]]])
}

/// The niebla JSON of a `<texture>` element.
pub(super) fn convert_texture<'a>(c: &mut Converter<'a>, node: &'a Node) -> Result<Value, SceneError> {
    let p = Props::new(node)?;
    let t = p.plugin_type()?;
    let to_uv = match p.transform("to_uv")? {
        Some(m) => Some(to_uv_rows(&p, &m)?),
        None => None,
    };
    let out = match t {
        "bitmap" => {
            let (file, _) = c.file(&p, "filename")?;
            let filter = choice(&p, "filter_type", &["bilinear", "nearest"])?;
            let wrap = choice(&p, "wrap_mode", &["repeat", "mirror", "clamp"])?;
            let raw = p.boolean("raw")?.unwrap_or(false);
            // Mitsuba's lookup at T(uv) reads row v' * height from the top;
            // niebla's at (u', v') reads row (1 - v') * height: v' -> 1 - v'.
            let [r0, r1] = to_uv.unwrap_or([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
            let flipped = [r0, [0.0 - r1[0], 0.0 - r1[1], 1.0 - r1[2]]];
            p.harmless(&["format", "accel"], "ignored (niebla stores textures as 32-bit floats)", &mut c.notes);
            json!({"type": "bitmap", "file": file, "filter": filter, "wrap": wrap, "raw": raw, "to_uv": flipped})
        }
        "checkerboard" => {
            // Mitsuba's color0 where frac(u) > 1/2 and frac(v) > 1/2 agree:
            // niebla's cells of half a unit (scale 2), color0 on even cells.
            let color0 = p.color("color0")?.unwrap_or([0.4; 3]);
            let color1 = p.color("color1")?.unwrap_or([0.2; 3]);
            let mut out = json!({"type": "checkerboard", "color0": color_json(color0), "color1": color_json(color1),
                                 "scale": [2.0, 2.0]});
            if let Some(rows) = to_uv {
                out["to_uv"] = json!(rows);
            }
            out
        }
        _ => return Err(p.error("not supported (expected bitmap or checkerboard)")),
    };
    p.finish()?;
    Ok(out)
}
