//! Sequences: frame patterns in file names and keyframed cameras and lights.
//!
//! A scene file describes one frame or, with a frame number, any frame of a
//! sequence. Two things change with the frame, both optional keys of the
//! description, applied to the JSON value before it is deserialized (so the
//! usual parser checks the frame's values and old scenes keep their meaning):
//!
//! - **Frame patterns** in every `file` field: a run of `#` is the frame
//!   number zero-padded to the run's length (`smoke.####.vdb` is
//!   `smoke.0007.vdb` at frame 7); `{frame}` is the number as is and
//!   `{frame:0N}` zero-padded to `N` digits. Without a frame number the
//!   names are used as written.
//! - **Keyframes**: the camera and each light may hold `"keyframes": [{"frame":
//!   F, FIELD: VALUE, ...}, ...]` with strictly increasing frames. Each
//!   animatable field a keyframe sets is interpolated linearly in the frame
//!   number between the keyframes that set it and held constant before the
//!   first and after the last of them; fields no keyframe sets keep the
//!   object's own value. Without a frame number the keyframes are checked
//!   but not applied.

use serde_json::{Map, Value};

use super::SceneError;
use crate::params::describe;

/// A frame number of a sequence.
pub type FrameNumber = u32;

/// Whether `name` holds a frame pattern (`#`, `{frame}` or `{frame:0N}`).
pub fn has_frame_pattern(name: &str) -> bool {
    name.contains('#') || name.contains("{frame")
}

/// `name` with its frame patterns replaced by `frame`: a run of `n` `#` by
/// the number zero-padded to `n` digits, `{frame}` by the number,
/// `{frame:0N}` by the number zero-padded to `N` digits (1 to 10). A number
/// wider than its padding is written whole. Errors describe a malformed
/// `{frame...}`.
///
/// ```
/// use niebla::scene::frames::substitute_frame;
/// assert_eq!(substitute_frame("smoke.####.vdb", 7).unwrap(), "smoke.0007.vdb");
/// assert_eq!(substitute_frame("f{frame}_{frame:03}.exr", 12).unwrap(), "f12_012.exr");
/// assert!(substitute_frame("f{frame:4}.exr", 1).is_err());
/// ```
pub fn substitute_frame(name: &str, frame: FrameNumber) -> Result<String, String> {
    let mut out = String::with_capacity(name.len() + 4);
    let mut rest = name;
    while let Some(c) = rest.chars().next() {
        if c == '#' {
            let run = rest.len() - rest.trim_start_matches('#').len();
            out.push_str(&format!("{frame:0run$}"));
            rest = &rest[run..];
        } else if let Some(after) = rest.strip_prefix("{frame") {
            let Some(close) = after.find('}') else {
                return Err(format!("`{rest}`: unclosed `{{frame`; expected {{frame}} or {{frame:0N}}"));
            };
            let spec = &after[..close];
            let width = match spec.strip_prefix(":0") {
                None if spec.is_empty() => 0,
                Some(digits) if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) => {
                    match digits.parse::<usize>() {
                        Ok(w @ 1..=10) => w,
                        _ => return Err(format!("`{{frame{spec}}}`: the width must be 1 to 10 digits")),
                    }
                }
                _ => {
                    return Err(format!(
                        "`{{frame{spec}}}`: expected {{frame}} or {{frame:0N}} (zero-padded to N digits)"
                    ))
                }
            };
            out.push_str(&format!("{frame:0width$}"));
            rest = &after[close + 1..];
        } else {
            out.push(c);
            rest = &rest[c.len_utf8()..];
        }
    }
    Ok(out)
}

/// Every `file` field of a scene value: its JSON path and its name.
pub fn file_fields(value: &Value) -> Vec<(String, String)> {
    let mut found = Vec::new();
    visit_files(value, "", &mut |path, name| found.push((path.to_string(), name.to_string())));
    found
}

fn visit_files(value: &Value, path: &str, f: &mut impl FnMut(&str, &str)) {
    match value {
        Value::Object(map) => {
            for (key, v) in map {
                let p = if path.is_empty() { key.clone() } else { format!("{path}.{key}") };
                match v {
                    Value::String(s) if key == "file" => f(&p, s),
                    _ => visit_files(v, &p, f),
                }
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                visit_files(v, &format!("{path}[{i}]"), f);
            }
        }
        _ => {}
    }
}

/// The JSON paths of what changes from frame to frame in a scene value:
/// `file` fields with a frame pattern and `keyframes` lists. Empty for a
/// still scene.
pub fn animated_fields(value: &Value) -> Vec<String> {
    let mut paths: Vec<String> =
        file_fields(value).into_iter().filter(|(_, name)| has_frame_pattern(name)).map(|(p, _)| p).collect();
    for (path, object) in animatable_objects(value) {
        if object.contains_key("keyframes") {
            paths.push(format!("{path}.keyframes"));
        }
    }
    paths
}

/// The kinds of value a keyframe may set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FieldKind {
    /// `[x, y, z]`.
    Vec3,
    /// A number.
    Number,
    /// A number (gray) or `[r, g, b]`.
    Color,
}

/// The fields keyframes may animate on an object of `kind` (`camera` or
/// `light`) with type tag `tag`; `None` for unknown tags (the parser reports them).
fn animatable(kind: &str, tag: &str) -> Option<&'static [(&'static str, FieldKind)]> {
    use FieldKind::*;
    Some(match (kind, tag) {
        ("camera", "perspective") => &[("position", Vec3), ("target", Vec3), ("up", Vec3), ("fov_y", Number)],
        ("light", "point") => &[("position", Vec3), ("intensity", Color)],
        ("light", "spot") => &[("position", Vec3), ("target", Vec3), ("direction", Vec3), ("intensity", Color)],
        ("light", "directional") => &[("direction", Vec3), ("irradiance", Color)],
        ("light", "constant") | ("light", "area") => &[("radiance", Color)],
        ("light", "envmap") => &[("scale", Number)],
        _ => return None,
    })
}

/// The objects that may hold keyframes: (JSON path, object).
fn animatable_objects(value: &Value) -> Vec<(String, &Map<String, Value>)> {
    let mut out = Vec::new();
    if let Some(Value::Object(camera)) = value.get("camera") {
        out.push(("camera".to_string(), camera));
    }
    if let Some(Value::Array(lights)) = value.get("lights") {
        for (i, l) in lights.iter().enumerate() {
            if let Value::Object(light) = l {
                out.push((format!("lights[{i}]"), light));
            }
        }
    }
    out
}

/// One keyframe read: its frame and the fields it sets (as written).
struct Keyframe {
    frame: f64,
    fields: Vec<(&'static str, Value)>,
}

/// Reads and checks the `keyframes` list of the object at `path` of kind
/// `kind` (`camera` or `light`). Errors are (JSON path, message).
fn read_keyframes(
    path: &str,
    kind: &str,
    object: &Map<String, Value>,
) -> Result<Option<Vec<Keyframe>>, (String, String)> {
    let Some(list) = object.get("keyframes") else { return Ok(None) };
    let at = format!("{path}.keyframes");
    let tag = object.get("type").and_then(Value::as_str).unwrap_or("");
    let Some(fields) = animatable(kind, tag) else { return Ok(None) };
    let Value::Array(items) = list else {
        return Err((at, format!("expected a list of keyframe objects, got {}", describe(list))));
    };
    if items.is_empty() {
        return Err((at, "expected at least one keyframe".into()));
    }
    let names = fields.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ");
    let mut keyframes: Vec<Keyframe> = Vec::with_capacity(items.len());
    for (i, item) in items.iter().enumerate() {
        let at = format!("{at}[{i}]");
        let Value::Object(map) = item else {
            return Err((at, format!("expected a keyframe object {{\"frame\": N, ...}}, got {}", describe(item))));
        };
        let frame = match map.get("frame") {
            None => return Err((at, "missing field `frame` (the frame number of this keyframe)".into())),
            Some(v) => match v.as_f64() {
                Some(f) if f.is_finite() && f >= 0.0 => f,
                _ => return Err((format!("{at}.frame"), format!("expected a frame number >= 0, got {v}"))),
            },
        };
        if let Some(previous) = keyframes.last() {
            if frame <= previous.frame {
                return Err((
                    format!("{at}.frame"),
                    format!(
                        "keyframes must be in increasing frame order, but frame {frame} follows frame {}",
                        previous.frame
                    ),
                ));
            }
        }
        let mut set = Vec::new();
        for (key, v) in map {
            if key == "frame" {
                continue;
            }
            let Some(&(name, field_kind)) = fields.iter().find(|(n, _)| n == key) else {
                return Err((
                    format!("{at}.{key}"),
                    format!("unknown field `{key}`; a {tag} {kind}'s keyframes may set: frame, {names}"),
                ));
            };
            check_value(field_kind, v).map_err(|m| (format!("{at}.{key}"), m))?;
            if tag == "spot" {
                let other = if name == "target" {
                    Some("direction")
                } else if name == "direction" {
                    Some("target")
                } else {
                    None
                };
                if let Some(other) = other.filter(|o| object.contains_key(*o)) {
                    return Err((
                        format!("{at}.{key}"),
                        format!(
                            "this spot light aims by `{other}`; its keyframes must animate `{other}`, not `{name}`"
                        ),
                    ));
                }
            }
            set.push((name, v.clone()));
        }
        keyframes.push(Keyframe { frame, fields: set });
    }
    Ok(Some(keyframes))
}

/// Checks that `v` is a value of `kind` (finite numbers).
fn check_value(kind: FieldKind, v: &Value) -> Result<(), String> {
    let finite = |x: &Value| x.as_f64().is_some_and(f64::is_finite);
    let ok = match (kind, v) {
        (FieldKind::Number | FieldKind::Color, Value::Number(_)) => finite(v),
        (FieldKind::Vec3 | FieldKind::Color, Value::Array(a)) => a.len() == 3 && a.iter().all(finite),
        _ => false,
    };
    if ok {
        return Ok(());
    }
    Err(match kind {
        FieldKind::Vec3 => format!("expected [x, y, z] (3 finite numbers), got {v}"),
        FieldKind::Number => format!("expected a finite number, got {v}"),
        FieldKind::Color => format!("expected a number or [r, g, b] (finite), got {v}"),
    })
}

/// The components of a number or 3-vector value (a number repeated when
/// `width` is 3).
fn components(v: &Value, width: usize) -> Vec<f64> {
    match v {
        Value::Array(a) => a.iter().map(|x| x.as_f64().unwrap_or(0.0)).collect(),
        _ => vec![v.as_f64().unwrap_or(0.0); width],
    }
}

/// Linear interpolation `a (1 - t) + b t`, exact at both ends.
pub fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a * (1.0 - t) + b * t
}

/// The value of one field at `frame` from the (frame, value) pairs of the
/// keyframes that set it (in increasing frame order): linear between two
/// keyframes, held before the first and after the last.
fn interpolate(points: &[(f64, &Value)], frame: f64) -> Value {
    let (first, last) = (points[0], points[points.len() - 1]);
    if frame <= first.0 {
        return first.1.clone();
    }
    if frame >= last.0 {
        return last.1.clone();
    }
    let k = points.partition_point(|(f, _)| *f <= frame) - 1;
    let ((f0, v0), (f1, v1)) = (points[k], points[k + 1]);
    if frame == f0 {
        return v0.clone();
    }
    let t = (frame - f0) / (f1 - f0);
    if let (Value::Number(a), Value::Number(b)) = (v0, v1) {
        return Value::from(lerp(a.as_f64().unwrap_or(0.0), b.as_f64().unwrap_or(0.0), t));
    }
    let (a, b) = (components(v0, 3), components(v1, 3));
    Value::Array(a.iter().zip(&b).map(|(&a, &b)| Value::from(lerp(a, b, t))).collect())
}

/// The object `object` with `keyframes` removed and, at `frame`, each field
/// the keyframes set replaced by its interpolated value.
fn apply_keyframes(object: &mut Map<String, Value>, keyframes: &[Keyframe], frame: Option<f64>) {
    object.remove("keyframes");
    let Some(frame) = frame else { return };
    let mut names: Vec<&'static str> = keyframes.iter().flat_map(|k| k.fields.iter().map(|(n, _)| *n)).collect();
    names.sort_unstable();
    names.dedup();
    for name in names {
        let points: Vec<(f64, &Value)> = keyframes
            .iter()
            .filter_map(|k| k.fields.iter().find(|(n, _)| *n == name).map(|(_, v)| (k.frame, v)))
            .collect();
        object.insert(name.to_string(), interpolate(&points, frame));
    }
}

/// Makes the scene `value` the scene of `frame`: keyframes applied (at that
/// frame) and removed, frame patterns of `file` fields replaced. Without a
/// frame, keyframes are checked and removed and file names stay as written.
///
/// `check` deserializes and validates a scene value (the parser's own
/// step); it is run once per keyframe with that keyframe's values put in
/// its object, so that a value out of range is reported at its keyframe
/// (`camera.keyframes[2].fov_y`).
pub(super) fn resolve_frame(
    value: &mut Value,
    source: &str,
    frame: Option<FrameNumber>,
    check: &dyn Fn(Value) -> Result<(), SceneError>,
) -> Result<(), SceneError> {
    let err = |(path, message): (String, String)| SceneError::new(source, path, message);
    // Read every keyframe list first (errors name the keyframe).
    let mut lists: Vec<(String, Vec<Keyframe>)> = Vec::new();
    for (path, object) in animatable_objects(value) {
        let kind = if path == "camera" { "camera" } else { "light" };
        if let Some(list) = read_keyframes(&path, kind, object).map_err(err)? {
            lists.push((path, list));
        }
    }
    if !lists.is_empty() {
        // The still scene (keyframes removed), into which one keyframe's
        // values at a time are put and checked.
        let mut still = value.clone();
        for (path, _) in &lists {
            object_at(&mut still, path).remove("keyframes");
        }
        // Errors of the still scene are reported as they are.
        check(still.clone())?;
        for (path, list) in &lists {
            for (i, keyframe) in list.iter().enumerate() {
                let mut trial = still.clone();
                let object = object_at(&mut trial, path);
                for (name, v) in &keyframe.fields {
                    object.insert(name.to_string(), v.clone());
                }
                if let Err(mut e) = check(trial) {
                    let set = keyframe.fields.iter().find(|(name, _)| {
                        let field = format!("{path}.{name}");
                        e.path == field
                            || e.path.starts_with(&format!("{field}["))
                            || e.path.starts_with(&format!("{field}."))
                    });
                    match set {
                        Some((name, _)) => {
                            let tail = e.path[path.len() + name.len() + 1..].to_string();
                            e.path = format!("{path}.keyframes[{i}].{name}{tail}");
                        }
                        None => {
                            e.message = format!("with {path}.keyframes[{i}] (frame {}): {}", keyframe.frame, e.message)
                        }
                    }
                    return Err(e);
                }
            }
        }
        for (path, list) in &lists {
            let object = object_at(value, path);
            let motion = match frame {
                Some(f) if path == "camera" => keyframed_motion(object, list, f64::from(f)),
                _ => Vec::new(),
            };
            apply_keyframes(object, list, frame.map(f64::from));
            if !motion.is_empty() {
                let mut end = Map::new();
                for (name, base, one) in motion {
                    object.insert(name.to_string(), base);
                    end.insert(name.to_string(), one);
                }
                object.insert("motion".to_string(), Value::Object(end));
            }
        }
    }
    if let Some(frame) = frame {
        substitute_files(value, "", frame).map_err(err)?;
    }
    Ok(())
}

/// The motion blur of a keyframed camera at `frame`: when its shutter is
/// open over an interval (`shutter_open < shutter_close`, frames) and it
/// has no `motion` of its own, the camera moves on the straight line
/// between its keyframed poses at `frame + shutter_open` and `frame +
/// shutter_close`. Returns, per keyframed field of `position`, `target` and
/// `up`, the value at time 0 and at time 1 on that line (the camera's field
/// and its `motion` field); empty when nothing moves this way.
fn keyframed_motion(
    object: &Map<String, Value>,
    keyframes: &[Keyframe],
    frame: f64,
) -> Vec<(&'static str, Value, Value)> {
    let number = |key: &str| object.get(key).and_then(Value::as_f64).unwrap_or(0.0);
    let (open, close) = (number("shutter_open"), number("shutter_close"));
    if !(open < close) || object.contains_key("motion") {
        return Vec::new();
    }
    let mut at_open = object.clone();
    let mut at_close = object.clone();
    apply_keyframes(&mut at_open, keyframes, Some(frame + open));
    apply_keyframes(&mut at_close, keyframes, Some(frame + close));
    let mut out = Vec::new();
    for name in ["position", "target", "up"] {
        if !keyframes.iter().any(|k| k.fields.iter().any(|(n, _)| *n == name)) {
            continue;
        }
        let (Some(a), Some(b)) = (at_open.get(name), at_close.get(name)) else { continue };
        let (a, b) = (components(a, 3), components(b, 3));
        let slope: Vec<f64> = a.iter().zip(&b).map(|(a, b)| (b - a) / (close - open)).collect();
        let base: Vec<f64> = a.iter().zip(&slope).map(|(a, s)| a - s * open).collect();
        let one: Vec<f64> = base.iter().zip(&slope).map(|(b, s)| b + s).collect();
        let to_value = |v: Vec<f64>| Value::Array(v.into_iter().map(Value::from).collect());
        out.push((name, to_value(base), to_value(one)));
    }
    out
}

/// The object at `path` (`camera` or `lights[i]`), known to exist.
fn object_at<'a>(value: &'a mut Value, path: &str) -> &'a mut Map<String, Value> {
    let target = match path.strip_prefix("lights[").and_then(|s| s.strip_suffix(']')) {
        Some(i) => &mut value["lights"][i.parse::<usize>().unwrap_or(0)],
        None => &mut value["camera"],
    };
    match target {
        Value::Object(map) => map,
        _ => unreachable!("animatable_objects found an object at {path}"),
    }
}

/// Replaces the frame patterns of every `file` field under `value`.
fn substitute_files(value: &mut Value, path: &str, frame: FrameNumber) -> Result<(), (String, String)> {
    match value {
        Value::Object(map) => {
            for (key, v) in map.iter_mut() {
                let p = if path.is_empty() { key.clone() } else { format!("{path}.{key}") };
                match v {
                    Value::String(s) if key == "file" => {
                        if has_frame_pattern(s) {
                            *s = substitute_frame(s, frame).map_err(|m| (p, m))?;
                        }
                    }
                    _ => substitute_files(v, &p, frame)?,
                }
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter_mut().enumerate() {
                substitute_files(v, &format!("{path}[{i}]"), frame)?;
            }
        }
        _ => {}
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hashes_pad_to_their_run_and_braces_to_their_width() {
        assert_eq!(substitute_frame("a.#.vdb", 12).unwrap(), "a.12.vdb");
        assert_eq!(substitute_frame("dir_##/a.####.vdb", 3).unwrap(), "dir_03/a.0003.vdb");
        assert_eq!(substitute_frame("a.{frame}.vdb", 0).unwrap(), "a.0.vdb");
        assert_eq!(substitute_frame("a.{frame:05}.vdb", 42).unwrap(), "a.00042.vdb");
        assert_eq!(substitute_frame("a.{other}.vdb", 4).unwrap(), "a.{other}.vdb");
        assert_eq!(substitute_frame("é#", 5).unwrap(), "é5");
        for bad in ["a.{frame:4}.vdb", "a.{frame:0}.vdb", "a.{frame:011}.vdb", "a.{frame", "a.{frames}"] {
            assert!(substitute_frame(bad, 1).is_err(), "{bad}");
        }
    }

    #[test]
    fn interpolation_is_linear_and_held_outside() {
        let (a, b) = (Value::from(1.0), Value::from(3.0));
        let points = [(10.0, &a), (20.0, &b)];
        assert_eq!(interpolate(&points, 0.0), a);
        assert_eq!(interpolate(&points, 25.0), b);
        assert_eq!(interpolate(&points, 15.0).as_f64(), Some(2.0));
        let (c, d) = (Value::from(2.0), serde_json::json!([0.0, 4.0, 8.0]));
        assert_eq!(interpolate(&[(0.0, &c), (4.0, &d)], 1.0), serde_json::json!([1.5, 2.5, 3.5]));
    }
}
