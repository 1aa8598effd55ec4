//! `<sensor type="perspective">` (with its film, filter and sampler) and
//! `<integrator>` into niebla's `camera` and `render`.

use serde_json::{json, Map, Value};

use super::convert::Converter;
use super::props::Props;
use super::transform::{det3, dot, norm, point, vector, Form, IDENTITY};
use super::xml::Node;
use crate::scene::SceneError;

/// The camera JSON, the `render` object without its integrator, and the
/// sensor's medium (name and where it was given), if any.
#[allow(clippy::type_complexity)]
pub(super) fn convert_sensor<'a>(
    c: &mut Converter<'a>,
    node: &'a Node,
) -> Result<(Value, Map<String, Value>, Option<(String, String)>), SceneError> {
    let p = Props::new(node)?;
    if p.plugin_type()? != "perspective" {
        return Err(p.error("not supported (niebla's camera is Mitsuba's `perspective`)"));
    }
    let (m, form) = p.transform_form("to_world")?.unwrap_or((IDENTITY, Form::Matrix));
    let (left, up, dir) = (vector(&m, [1.0, 0.0, 0.0]), vector(&m, [0.0, 1.0, 0.0]), vector(&m, [0.0, 0.0, 1.0]));
    let (nl, nu, nd) = (norm(left), norm(up), norm(dir));
    let orthogonal = [dot(left, up) / (nl * nu), dot(left, dir) / (nl * nd), dot(up, dir) / (nu * nd)]
        .iter()
        .all(|c| c.abs() < 1e-5);
    if !orthogonal || (nl / nd - 1.0).abs() > 1e-5 || (nu / nd - 1.0).abs() > 1e-5 {
        return Err(
            p.error("to_world must be a rotation and translation (a look_at), without shear or non-uniform scale")
        );
    }
    if det3(&m) < 0.0 {
        return Err(p.error(
            "to_world mirrors the image (negative determinant, e.g. <scale x=\"-1\"/>); niebla's camera cannot flip",
        ));
    }
    let position = point(&m, [0.0; 3]);
    let dir = dir.map(|x| x / nd);
    let target = [position[0] + dir[0], position[1] + dir[1], position[2] + dir[2]];

    let film_node = p.plugins("film").into_iter().next();
    let (width, height) = match film_node {
        Some(f) => film(c, f)?,
        None => (768, 576),
    };
    let aspect = width as f64 / height as f64;
    let fov = p.float_or("fov", 0.0)?;
    if p.has("focal_length") {
        return Err(p.error("`focal_length` is not supported; give `fov` in degrees"));
    }
    if !(fov > 0.0 && fov < 180.0) {
        return Err(p.error(format!("`fov` must be in (0, 180) degrees, got {fov}")));
    }
    let axis = p.string("fov_axis")?.unwrap_or("x");
    let tan_half = (0.5 * fov.to_radians()).tan();
    let tan_half_y = match axis {
        "x" => tan_half / aspect,
        "y" => tan_half,
        "diagonal" => tan_half / (1.0 + aspect * aspect).sqrt(),
        "smaller" if aspect < 1.0 => tan_half / aspect,
        "smaller" => tan_half,
        "larger" if aspect > 1.0 => tan_half / aspect,
        "larger" => tan_half,
        other => return Err(p.error(format!("`fov_axis` \"{other}\": expected x, y, diagonal, smaller or larger"))),
    };
    let fov_y = if axis == "y" { fov } else { 2.0 * tan_half_y.atan().to_degrees() };
    for (name, default) in [("near_clip", 0.01), ("far_clip", 10000.0)] {
        if let Some(v) = p.float(name)? {
            if v != default {
                c.notes.push(format!(
                    "{}: <sensor> `{name}` = {v}: niebla's camera does not clip (geometry at any distance is seen)",
                    node.loc.at()
                ));
            }
        }
    }
    for name in ["principal_point_offset_x", "principal_point_offset_y"] {
        if p.float_or(name, 0.0)? != 0.0 {
            return Err(p.error(format!("`{name}` other than 0 is not supported")));
        }
    }
    let mut render = Map::new();
    match p.plugins("sampler").into_iter().next() {
        Some(s) => sampler(c, s, &mut render)?,
        None => {
            render.insert("spp".into(), json!(4));
            render.insert("sampler".into(), json!("independent"));
        }
    }
    let mut medium = None;
    let mut media: Vec<&Node> = p.plugins("medium");
    if let Some(m) = p.plugin_named("medium") {
        media.push(m);
    }
    for r in p.unnamed_refs() {
        match c.target_tag(r) {
            Some("medium") => media.push(r),
            _ => return Err(r.loc.error(format!("{}: a <sensor> takes only a medium by reference", r.describe()))),
        }
    }
    if media.len() > 1 {
        return Err(p.error("more than one medium"));
    }
    if let Some(m) = media.first() {
        medium = Some((c.medium(m)?, m.loc.at()));
    }
    p.harmless(&["srf"], "ignored", &mut c.notes);
    p.finish()?;
    let up = up.map(|x| x / nu);
    // A lone <lookat> is niebla's own camera description: its numbers as
    // written (the same camera; niebla then builds the frame in f32 exactly
    // as from a JSON scene).
    let (position, target, up) = match form {
        Form::LookAt { origin, target, up } => (origin, target, up),
        _ => (position, target, up),
    };
    let camera = json!({
        "type": "perspective", "position": position, "target": target, "up": up,
        "fov_y": fov_y, "width": width, "height": height,
    });
    Ok((camera, render, medium))
}

/// `<film type="hdrfilm">`: its size; the filter and output options are noted.
fn film(c: &mut Converter, node: &Node) -> Result<(u32, u32), SceneError> {
    let p = Props::new(node)?;
    let t = p.plugin_type()?;
    if t != "hdrfilm" && t != "specfilm" {
        return Err(p.error("not supported (expected hdrfilm)"));
    }
    let size = |name: &str, default: i64| -> Result<u32, SceneError> {
        let v = p.integer(name)?.unwrap_or(default);
        u32::try_from(v)
            .ok()
            .filter(|v| (1..=16384).contains(v))
            .ok_or_else(|| p.error(format!("`{name}` must be 1 to 16384, got {v}")))
    };
    let (w, h) = (size("width", 768)?, size("height", 576)?);
    for name in ["crop_offset_x", "crop_offset_y", "crop_width", "crop_height"] {
        if p.has(name) {
            return Err(p.error(format!("`{name}`: crop windows are not supported")));
        }
    }
    match p.plugins("rfilter").into_iter().next() {
        Some(f) => {
            let fp = Props::new(f)?;
            let ft = fp.plugin_type()?;
            if ft != "box" {
                c.notes.push(format!(
                    "{}: <rfilter type=\"{ft}\">: niebla averages each pixel's samples with a box filter",
                    f.loc.at()
                ));
                fp.harmless(&["radius", "stddev", "B", "C", "lobes"], "filter parameter ignored", &mut c.notes);
            }
            fp.finish()?;
        }
        None => c.notes.push(format!(
            "{}: <film>: no <rfilter>: Mitsuba's default is a Gaussian; niebla averages each pixel with a box filter",
            node.loc.at()
        )),
    }
    p.harmless(
        &[
            "pixel_format",
            "component_format",
            "file_format",
            "banner",
            "sample_border",
            "compensate",
            "high_quality_edges",
        ],
        "output option ignored (niebla writes RGB EXR/PNG)",
        &mut c.notes,
    );
    p.finish()?;
    Ok((w, h))
}

/// `<sampler>`: `sample_count` and `seed` into `render.spp` and `render.seed`.
fn sampler(c: &mut Converter, node: &Node, render: &mut Map<String, Value>) -> Result<(), SceneError> {
    let p = Props::new(node)?;
    let t = p.plugin_type()?;
    match t {
        "independent" => {
            render.insert("sampler".into(), json!("independent"));
        }
        "stratified" | "multijitter" | "orthogonal" | "ldsampler" | "sobol" => c.notes.push(format!(
            "{}: <sampler type=\"{t}\">: niebla uses its own default sampler (unbiased either way)",
            node.loc.at()
        )),
        _ => return Err(p.error("not supported")),
    }
    let spp = p.integer("sample_count")?.unwrap_or(4);
    if !(1..=u32::MAX as i64).contains(&spp) {
        return Err(p.error(format!("`sample_count` must be at least 1, got {spp}")));
    }
    render.insert("spp".into(), json!(spp));
    let seed = p.integer("seed")?.unwrap_or(0);
    if seed < 0 {
        return Err(p.error(format!("`seed` must be >= 0, got {seed}")));
    }
    render.insert("seed".into(), json!(seed));
    p.harmless(&["jitter", "strength", "randomize", "scramble_seed"], "ignored", &mut c.notes);
    p.finish()
}

/// `<integrator>`: `volpath`, `volpathmis`, `path` (niebla's `volpath` with
/// `max_depth` one less: Mitsuba counts path segments, niebla scattering
/// events) or `moment` around one of them. No integrator is Mitsuba's
/// default, `path` with unlimited depth.
pub(super) fn convert_integrator(c: &mut Converter, node: Option<&Node>) -> Result<Value, SceneError> {
    let Some(node) = node else { return Ok(json!({"type": "volpath"})) };
    let p = Props::new(node)?;
    let t = p.plugin_type()?;
    match t {
        "moment" => {
            let inner = p.plugins("integrator");
            if inner.len() != 1 {
                return Err(p.error(format!("expected one nested <integrator>, found {}", inner.len())));
            }
            c.notes.push(format!(
                "{}: <integrator type=\"moment\">: niebla renders its inner integrator only",
                node.loc.at()
            ));
            p.finish()?;
            convert_integrator(c, Some(inner[0]))
        }
        "volpath" | "volpathmis" | "path" => {
            let depth = p.integer("max_depth")?.unwrap_or(-1);
            let out = match depth {
                -1 => json!({"type": "volpath"}),
                d if d >= 2 => json!({"type": "volpath", "max_depth": d - 1}),
                d => return Err(p.error(format!("`max_depth` {d}: niebla's volpath needs max_depth >= 2 (or -1)"))),
            };
            if p.boolean("hide_emitters")?.unwrap_or(false) {
                return Err(p.error("`hide_emitters` true is not supported"));
            }
            p.harmless(&["rr_depth"], "niebla applies its own Russian roulette (unbiased either way)", &mut c.notes);
            p.finish()?;
            if t == "path" {
                c.notes.push(format!(
                    "{}: <integrator type=\"path\">: rendered by niebla's volpath (Mitsuba's path ignores media)",
                    node.loc.at()
                ));
            }
            Ok(out)
        }
        _ => Err(p.error("not supported (expected volpath, volpathmis, path or moment)")),
    }
}
