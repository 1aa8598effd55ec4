//! `<medium>` (`homogeneous`, `heterogeneous`), its `<phase>` (`isotropic`,
//! `hg`, `rayleigh`, `blendphase`, `tabphase`) and `<volume>` (`constvolume`,
//! `gridvolume`) into niebla media.
//!
//! Placement of a `gridvolume` (Mitsuba 3): its `to_world` maps the unit
//! cube `[0, 1]^3` to the world; the box stored in the `.vol` file is used
//! only with `use_grid_bbox` (then `to_world` applies after it). niebla's
//! `vol` source fills the file's box, so the importer reads the file's
//! header and gives the medium the `to_world` that maps that box where
//! Mitsuba puts the grid.

use std::io::Read;
use std::path::Path;

use serde_json::{json, Map, Value};

use super::convert::{color_json, Converter};
use super::props::{Props, Rgb3};
use super::transform::{is_axis_aligned, mul, point, to_json, Mat4, IDENTITY};
use super::xml::Node;
use crate::scene::SceneError;

/// A medium property: a constant color, or a grid.
enum Field<'a> {
    Constant(Rgb3),
    Grid(&'a Node),
}

/// Reads property `name` of a medium: a color, or a `<volume>` (a
/// `constvolume` becomes its constant).
fn field<'a>(c: &Converter<'a>, p: &Props<'a>, name: &str, default: f64) -> Result<Field<'a>, SceneError> {
    if let Some(v) = p.plugin_named(name) {
        let v = c.resolve(v, "volume")?;
        let vp = Props::new(v)?;
        return match vp.plugin_type()? {
            "constvolume" => {
                let value = vp.color("value")?.unwrap_or([1.0; 3]);
                vp.harmless(&["to_world"], "a constant volume has no placement", &mut Vec::new());
                vp.finish()?;
                Ok(Field::Constant(value))
            }
            "gridvolume" => Ok(Field::Grid(v)),
            _ => Err(vp.error("not supported (expected constvolume or gridvolume)")),
        };
    }
    Ok(Field::Constant(p.color(name)?.unwrap_or([default; 3])))
}

/// The niebla JSON of a `<medium>` element.
pub(super) fn convert_medium<'a>(c: &mut Converter<'a>, node: &'a Node) -> Result<Value, SceneError> {
    let p = Props::new(node)?;
    let t = p.plugin_type()?;
    if t != "homogeneous" && t != "heterogeneous" {
        return Err(p.error("not supported (expected homogeneous or heterogeneous)"));
    }
    let sigma_t = field(c, &p, "sigma_t", 1.0)?;
    let albedo = field(c, &p, "albedo", 0.75)?;
    let scale = p.float_or("scale", 1.0)?;
    let phases = p.plugins("phase");
    let mut phase_nodes: Vec<&Node> = phases;
    for r in p.unnamed_refs() {
        if c.target_tag(r) == Some("phase") {
            phase_nodes.push(r);
        } else {
            return Err(r.loc.error(format!("{}: expected a reference to a <phase> here", r.describe())));
        }
    }
    if phase_nodes.len() > 1 {
        return Err(phase_nodes[1].loc.error("a medium has one phase function"));
    }
    let phase = match phase_nodes.first() {
        Some(ph) => convert_phase(c, c.resolve(ph, "phase")?)?,
        None => json!({"type": "isotropic"}),
    };
    let spectral = p.boolean("has_spectral_extinction")?;
    if spectral == Some(false) {
        if let Field::Constant(s) = sigma_t {
            if !(s[0] == s[1] && s[1] == s[2]) {
                c.notes.push(format!(
                    "{}: {}: has_spectral_extinction false with a colored sigma_t: Mitsuba then uses only one \
                     channel of it, niebla all three",
                    node.loc.at(),
                    p.what()
                ));
            }
        }
    }
    p.harmless(&["sample_emitters"], "ignored (niebla always samples emitters)", &mut c.notes);
    let mut out = Map::new();
    let mut density_to_world = None;
    let per_unit = match sigma_t {
        Field::Constant(s) => {
            if let Field::Grid(g) = albedo {
                return Err(g.loc.error(format!(
                    "{}: `albedo` as a gridvolume needs `sigma_t` as a gridvolume too (niebla's albedo grids \
                     belong to grid media, which the sigma_t grid bounds)",
                    p.what()
                )));
            }
            out.insert("type".into(), json!("homogeneous"));
            s
        }
        Field::Grid(g) => {
            let (density, to_world) = grid_source(c, g, "sigma_t")?;
            out.insert("type".into(), json!("grid"));
            out.insert("density".into(), density);
            if let Some(m) = to_world {
                out.insert("to_world".into(), to_json(&m));
            }
            density_to_world = Some(to_world.unwrap_or(IDENTITY));
            [1.0; 3]
        }
    };
    match albedo {
        Field::Constant(albedo) => {
            if albedo.iter().all(|a| (0.0..=1.0).contains(a)) && per_unit.iter().all(|s| *s >= 0.0) && scale >= 0.0 {
                // sigma_s = sigma_t scale albedo and sigma_a = sigma_t scale -
                // sigma_s, in f64, written as the f32 values niebla keeps. A scene
                // that niebla's bench converter wrote (sigma_t = sigma_a + sigma_s,
                // albedo = sigma_s / sigma_t of niebla's own f32 coefficients) reads
                // back to those coefficients bit for bit.
                let st = per_unit.map(|s| s * scale);
                let ss: Rgb3 = std::array::from_fn(|i| st[i] * albedo[i]);
                let sa: Rgb3 = std::array::from_fn(|i| st[i] - ss[i]);
                out.insert("sigma_a".into(), color_f32_json(sa));
                out.insert("sigma_s".into(), color_f32_json(ss));
            } else {
                // Out of range: niebla's own checks name the field.
                out.insert("sigma_t".into(), color_json(per_unit));
                out.insert("albedo".into(), color_json(albedo));
                if scale != 1.0 {
                    out.insert("scale".into(), json!(scale));
                }
            }
        }
        Field::Grid(g) => {
            // Mitsuba: albedo(x) = the albedo volume at x, placed by its own
            // to_world (clamped outside its box, as niebla's albedo grids).
            let (source, to_world) = grid_source(c, g, "albedo")?;
            out.insert("sigma_t".into(), color_json(per_unit));
            out.insert("albedo_grid".into(), source);
            let place = to_world.unwrap_or(IDENTITY);
            if Some(place) != density_to_world {
                out.insert("albedo_to_world".into(), to_json(&place));
            }
            if scale != 1.0 {
                out.insert("scale".into(), json!(scale));
            }
        }
    }
    out.insert("phase".into(), phase);
    p.finish()?;
    Ok(Value::Object(out))
}

/// `x` rounded to f32, as the shortest decimal that reads back (through
/// f64, as niebla's JSON reader does) to that f32.
fn f32_json(x: f64) -> Value {
    let f = x as f32;
    match format!("{f}").parse::<f64>() {
        Ok(d) if d as f32 == f => json!(d),
        _ => json!(f as f64),
    }
}

/// A color of f32 values (see [`f32_json`]): one number when gray.
fn color_f32_json(c: Rgb3) -> Value {
    let c = c.map(|x| x as f32 as f64);
    if c[0] == c[1] && c[1] == c[2] {
        f32_json(c[0])
    } else {
        json!(c.map(f32_json))
    }
}

/// The bounding box and channel count in a `.vol` header (48 bytes).
fn vol_header(path: &Path) -> Result<([f64; 3], [f64; 3], i32), String> {
    let mut head = [0u8; 48];
    let mut f = std::fs::File::open(path).map_err(|e| e.to_string())?;
    f.read_exact(&mut head).map_err(|_| "shorter than a .vol header (48 bytes)".to_string())?;
    if &head[..3] != b"VOL" || head[3] != 3 {
        return Err("not a Mitsuba .vol file of version 3".into());
    }
    let i32_at = |o: usize| i32::from_le_bytes([head[o], head[o + 1], head[o + 2], head[o + 3]]);
    let f32_at = |o: usize| f32::from_le_bytes([head[o], head[o + 1], head[o + 2], head[o + 3]]) as f64;
    let channels = i32_at(20);
    let lo = [f32_at(24), f32_at(28), f32_at(32)];
    let hi = [f32_at(36), f32_at(40), f32_at(44)];
    Ok((lo, hi, channels))
}

/// A `gridvolume` for property `what` (`sigma_t`: one channel; `albedo`: one
/// or three) as niebla's `vol` source and the transform that places the
/// file's box where Mitsuba puts the grid (`None` when it is already there).
fn grid_source(c: &mut Converter, node: &Node, what: &str) -> Result<(Value, Option<Mat4>), SceneError> {
    let p = Props::new(node)?;
    let (file, full) = c.file(&p, "filename")?;
    if !file.ends_with(".vol") {
        return Err(p.error(format!("\"{file}\": only .vol grids are read by the importer")));
    }
    let (lo, hi, channels) = vol_header(&full).map_err(|e| p.error(format!("\"{file}\": {e}")))?;
    let allowed: &[i32] = if what == "albedo" { &[1, 3] } else { &[1] };
    if !allowed.contains(&channels) {
        return Err(p.error(if what == "albedo" {
            format!("\"{file}\" has {channels} channels: an albedo grid has 1 or 3 (RGB)")
        } else {
            format!(
                "\"{file}\" has {channels} channels: niebla's grid media scale one density channel by a \
                 constant sigma_t, so a `{what}` grid must have one channel (per-channel extinction grids are \
                 not supported)"
            )
        }));
    }
    if !(0..3).all(|i| hi[i] > lo[i]) {
        return Err(p.error(format!("\"{file}\": its bounding box {lo:?} to {hi:?} is empty")));
    }
    match p.string("filter_type")?.unwrap_or("trilinear") {
        "trilinear" => {}
        other => {
            return Err(p.error(format!("filter_type \"{other}\" is not supported (niebla interpolates trilinearly)")))
        }
    }
    match p.string("wrap_mode")?.unwrap_or("clamp") {
        "clamp" => {}
        other => return Err(p.error(format!("wrap_mode \"{other}\" is not supported (niebla clamps)"))),
    }
    let use_bbox = p.boolean("use_grid_bbox")?.unwrap_or(false);
    let m = p.transform("to_world")?.unwrap_or(IDENTITY);
    p.harmless(&["raw", "accel", "max_value"], "ignored", &mut c.notes);
    p.finish()?;
    // `box_of`: [0,1]^3 -> the file's box.
    let mut box_of = IDENTITY;
    for i in 0..3 {
        box_of[i][i] = hi[i] - lo[i];
        box_of[i][3] = lo[i];
    }
    let density = json!({"type": "vol", "file": file});
    if use_bbox {
        return Ok((density, (m != IDENTITY).then_some(m)));
    }
    // Mitsuba's box is m([0,1]^3). When it is axis-aligned and equals the
    // file's box within the precision of f32 text, no transform is needed.
    if is_axis_aligned(&m) {
        let (a, b) = (point(&m, [0.0; 3]), point(&m, [1.0; 3]));
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-6 * x.abs().max(y.abs()).max(1e-30);
        if (0..3).all(|i| close(a[i], lo[i]) && close(b[i], hi[i])) {
            return Ok((density, None));
        }
    }
    // to_world = m * box_of^-1.
    let mut inv = IDENTITY;
    for i in 0..3 {
        inv[i][i] = 1.0 / (hi[i] - lo[i]);
        inv[i][3] = -lo[i] / (hi[i] - lo[i]);
    }
    Ok((density, Some(mul(&m, &inv))))
}

/// The niebla JSON of a `<phase>` element.
fn convert_phase(c: &mut Converter, node: &Node) -> Result<Value, SceneError> {
    let p = Props::new(node)?;
    let out = match p.plugin_type()? {
        "isotropic" => json!({"type": "isotropic"}),
        "hg" => json!({"type": "hg", "g": p.float_or("g", 0.8)?}),
        "rayleigh" => json!({"type": "rayleigh"}),
        "blendphase" => {
            let w = p.float_or("weight", 0.5)?;
            if !(0.0..=1.0).contains(&w) {
                return Err(p.error(format!("`weight` must be in [0, 1], got {w}")));
            }
            let mut inner = p.plugins("phase");
            inner.extend(p.unnamed_refs());
            if inner.len() != 2 {
                return Err(p.error(format!("expected two nested phase functions, found {}", inner.len())));
            }
            let mut gs = [0.0; 2];
            for (k, n) in inner.iter().enumerate() {
                let n = c.resolve(n, "phase")?;
                let v = convert_phase(c, n)?;
                gs[k] = match v["type"].as_str() {
                    Some("isotropic") => 0.0,
                    Some("hg") => v["g"].as_f64().unwrap_or(0.0),
                    _ => {
                        return Err(n.loc.error(format!(
                            "{}: inside a blendphase only isotropic and hg are supported (niebla's double_hg)",
                            n.describe()
                        )))
                    }
                };
            }
            // Mitsuba: (1 - weight) * first + weight * second; niebla: w * HG(g1) + (1 - w) * HG(g2).
            json!({"type": "double_hg", "w": 1.0 - w, "g1": gs[0], "g2": gs[1]})
        }
        "tabphase" => {
            // Mitsuba 3: values at cosines regularly spaced from -1 (first,
            // backward) to 1 (last, forward), linear in between, normalized.
            let text =
                p.string("values")?.ok_or_else(|| p.error("missing property `values` (a list of phase values)"))?;
            let mut values = Vec::new();
            for token in text.split([',', ' ', '\t', '\n', '\r']).filter(|t| !t.is_empty()) {
                let v: f64 = token.parse().map_err(|_| {
                    p.error(format!("`values`: {token:?} is not a number (expected a comma-separated list)"))
                })?;
                values.push(v);
            }
            let n = values.len();
            if n < 2 {
                return Err(p.error(format!("`values` holds {n} numbers: expected at least 2")));
            }
            let mu: Vec<f64> =
                (0..n).map(|i| if i + 1 == n { 1.0 } else { -1.0 + 2.0 * i as f64 / (n - 1) as f64 }).collect();
            crate::phase::Tabulated::from_cosines(&mu, &values).map_err(|e| p.error(format!("`values`: {e}")))?;
            json!({"type": "tabulated", "mu": mu, "p": values})
        }
        _ => return Err(p.error("not supported (expected isotropic, hg, rayleigh, blendphase or tabphase)")),
    };
    p.finish()?;
    Ok(out)
}
