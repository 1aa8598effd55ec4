//! Wavefront OBJ reader, through the `tobj` crate (triangulated, one index
//! shared by position, normal and uv), with a line-numbered pre-scan for
//! the faults whose `tobj` errors would not say where they are.
//!
//! What is read: `v` (with an optional `w` that divides x, y, z, or an
//! optional r g b colour, ignored), `vt` (u and v; a 1-component `vt` is an
//! error), `vn`, and `f` faces of any vertex count with 1-based or negative
//! (relative) indices, triangulated as fans. Points and two-vertex faces
//! and `l` polylines are skipped; materials (`mtllib`, `usemtl`) are
//! ignored. `o` and `g` both start a named object (tobj's behaviour);
//! faces before any of them belong to `unnamed_object`.
//!
//! Vertices are numbered in order of first use by the faces (unreferenced
//! `v` lines are dropped): a vertex used with two different normal or uv
//! indices becomes two vertices at the same position.
//!
//! **Partial attributes**: when some face corners have a uv (or normal)
//! index and others do not, or when merged objects differ, uvs (or
//! normals) are dropped for the whole mesh; positions and triangles are
//! unaffected.

use std::path::Path;

use crate::{MeshData, MeshError};

/// Reads an OBJ file: every object merged into one mesh (`object: None`),
/// or only the objects and groups of the given name. See the module
/// documentation for what is read.
pub fn read_obj(path: impl AsRef<Path>, object: Option<&str>) -> Result<MeshData, MeshError> {
    let path = path.as_ref();
    let data = crate::read_file(path)?;
    parse_obj(&data, path, object)
}

/// Parses OBJ text already in memory; `path` is only used in error
/// messages. Bytes that are not UTF-8 are replaced by U+FFFD (harmless in
/// names and comments, an error in numbers); a UTF-8 byte order mark is
/// skipped; UTF-16 text is an error.
///
/// ```
/// use std::path::Path;
/// let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n";
/// let err = niebla_mesh::parse_obj(obj, Path::new("bad.obj"), None).unwrap_err();
/// assert_eq!(
///     err.to_string(),
///     "bad.obj: line 4: face vertex \"4\" refers to position 4 but the file has 3 positions"
/// );
/// ```
pub fn parse_obj(data: &[u8], path: &Path, object: Option<&str>) -> Result<MeshData, MeshError> {
    if data.starts_with(&[0xFE, 0xFF]) || data.starts_with(&[0xFF, 0xFE]) {
        return Err(parse_error(path, 1, "UTF-16 text (byte order mark); OBJ files must be ASCII or UTF-8".into()));
    }
    // Bytes that are not UTF-8 (Latin-1 object or material names) become
    // U+FFFD; a UTF-8 byte order mark is dropped (tobj would read it as part
    // of the first keyword and silently skip that line).
    let text = String::from_utf8_lossy(data);
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let rewrite_needed = check_structure(text, path)?;
    let rewritten;
    let tobj_text = if rewrite_needed {
        rewritten = rewrite(text);
        rewritten.as_str()
    } else {
        text
    };
    match load(tobj_text, path, object) {
        // tobj's errors and non-finite values say neither line nor value:
        // look for the first malformed v, vt or vn line and report it instead.
        Err(e @ (MeshError::Parse { .. } | MeshError::Invalid { .. })) => {
            Err(diagnose_values(text, path).err().unwrap_or(e))
        }
        other => other,
    }
}

/// Reads structurally checked text with tobj and assembles the mesh.
fn load(text: &str, path: &Path, object: Option<&str>) -> Result<MeshData, MeshError> {
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let mut reader = std::io::Cursor::new(text.as_bytes());
    let (models, _materials) = tobj::load_obj_buf(&mut reader, &options, |_| Err(tobj::LoadError::OpenFileFailed))
        .map_err(|e| MeshError::Parse {
            path: path.to_path_buf(),
            location: "OBJ".into(),
            what: format!("{e} (reported by tobj)"),
        })?;

    let mut available: Vec<String> = Vec::new();
    let mut merged = MeshData::default();
    let mut matched = false;
    for model in models {
        let m = model.mesh;
        if m.indices.is_empty() {
            continue;
        }
        if !available.contains(&model.name) {
            available.push(model.name.clone());
        }
        if object.is_some_and(|o| o != model.name) {
            continue;
        }
        let n = m.positions.len() / 3;
        if merged.positions.len().checked_add(n).is_none_or(|t| u32::try_from(t).is_err()) {
            return Err(MeshError::Invalid {
                origin: path.display().to_string(),
                what: format!("more than {} vertices", u32::MAX),
            });
        }
        let positions: Vec<[f32; 3]> = m.positions.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let normals =
            (m.normals.len() == 3 * n).then(|| m.normals.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect());
        let uvs = (m.texcoords.len() == 2 * n).then(|| m.texcoords.chunks_exact(2).map(|c| [c[0], c[1]]).collect());
        let indices = m.indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let part = MeshData { positions, normals, uvs, indices };
        if matched {
            merged.append(part);
        } else {
            merged = part;
            matched = true;
        }
    }
    if let (Some(name), false) = (object, matched) {
        return Err(MeshError::ObjectNotFound { path: path.to_path_buf(), name: name.into(), available });
    }
    if merged.indices.is_empty() {
        return Err(MeshError::Invalid {
            origin: path.display().to_string(),
            what: "no triangles (faces with fewer than 3 vertices are skipped)".into(),
        });
    }
    MeshData::from_arrays(merged.positions, merged.indices, merged.normals, merged.uvs)
        .map_err(|e| e.with_origin(path.display().to_string()))
}

fn parse_error(path: &Path, line: usize, what: String) -> MeshError {
    MeshError::Parse { path: path.to_path_buf(), location: format!("line {line}"), what }
}

/// Checks, before tobj reads the text, what tobj would get wrong or panic
/// on: face indices that are not integers, 0, or out of range (tobj's index
/// arithmetic can overflow on huge ones), and faces without vertices. One
/// pass counts `v`, `vt`, `vn` lines, checks relative (negative) indices
/// against the counts so far and remembers the largest positive ones (tobj
/// resolves those after reading everything); only when something is wrong
/// does a second pass find the first offending line.
///
/// Returns whether the text must be rewritten before tobj reads it
/// ([`rewrite`]): polylines of three or more vertices (tobj would make them
/// faces), `usemtl` lines without a name (tobj fails on them; materials are
/// ignored anyway), vertex colours given for some vertices only (tobj would
/// fail with "face color out of bounds").
fn check_structure(text: &str, path: &Path) -> Result<bool, MeshError> {
    let mut counts = [0usize; 3];
    let mut largest = [0usize; 3];
    let (mut colored, mut rewrite_needed, mut faulty) = (0usize, false, false);
    for line in text.split('\n') {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                counts[0] += 1;
                if words.count() == 6 {
                    colored += 1;
                }
            }
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some(kw @ ("f" | "l")) => {
                let mut corners = 0;
                for token in words {
                    corners += 1;
                    match check_face_vertex(token, counts, None) {
                        Ok(max) => (0..3).for_each(|k| largest[k] = largest[k].max(max[k])),
                        Err(_) => faulty = true,
                    }
                }
                faulty |= corners == 0;
                rewrite_needed |= kw == "l" && corners >= 3;
            }
            Some("usemtl") => rewrite_needed |= unnamed_usemtl(line),
            _ => {}
        }
    }
    if faulty || (0..3).any(|k| largest[k] > counts[k]) {
        return Err(first_face_error(text, path, counts));
    }
    Ok(rewrite_needed || (colored > 0 && colored < counts[0]))
}

/// The first face or polyline line with a bad index or no vertices, given
/// the file's total `v`, `vt`, `vn` counts.
fn first_face_error(text: &str, path: &Path, total: [usize; 3]) -> MeshError {
    let mut counts = [0usize; 3];
    for (i, line) in text.split('\n').enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => counts[0] += 1,
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some(kw @ ("f" | "l")) => {
                let mut corners = 0;
                for token in words {
                    corners += 1;
                    if let Err(what) = check_face_vertex(token, counts, Some(total)) {
                        return parse_error(path, i + 1, what);
                    }
                }
                if corners == 0 {
                    let what = if kw == "f" { "face" } else { "polyline" };
                    return parse_error(path, i + 1, format!("{what} without vertices"));
                }
            }
            _ => {}
        }
    }
    MeshError::Parse { path: path.to_path_buf(), location: "OBJ".into(), what: "bad face index".into() }
}

/// Checks one face vertex `v`, `v/vt`, `v//vn` or `v/vt/vn` as tobj parses
/// it: each index an integer (`isize`), not 0, a relative one within the
/// `so_far` counts, a positive one within `total` when given. Returns the
/// largest positive index of each kind (0 for none).
fn check_face_vertex(token: &str, so_far: [usize; 3], total: Option<[usize; 3]>) -> Result<[usize; 3], String> {
    const KIND: [&str; 3] = ["position", "texture coordinate", "normal"];
    if token.split('/').count() > 3 {
        return Err(format!("face vertex {token:?}: more than three /-separated indices"));
    }
    let mut largest = [0usize; 3];
    for (k, part) in token.split('/').enumerate() {
        if part.is_empty() {
            if k == 0 {
                return Err(format!("face vertex {token:?}: no position index"));
            }
            continue;
        }
        let Ok(x) = part.parse::<isize>() else {
            return Err(format!("face vertex {token:?}: {part:?} is not an integer"));
        };
        let plural = |n: usize| format!("{n} {}{}", KIND[k], if n == 1 { "" } else { "s" });
        if x == 0 {
            return Err(format!("face vertex {token:?}: index 0 (OBJ indices start at 1, negative ones count back)"));
        } else if x > 0 {
            let x = x as usize;
            if let Some(total) = total.filter(|t| x > t[k]) {
                return Err(format!(
                    "face vertex {token:?} refers to {} {x} but the file has {}",
                    KIND[k],
                    plural(total[k])
                ));
            }
            largest[k] = x;
        } else if x.unsigned_abs() > so_far[k] {
            return Err(format!(
                "face vertex {token:?}: relative {} index {x} but only {} {} this line",
                KIND[k],
                plural(so_far[k]),
                if so_far[k] == 1 { "precedes" } else { "precede" }
            ));
        }
    }
    Ok(largest)
}

/// The first malformed `v`, `vt` or `vn` line, if any: a missing or
/// non-numeric value, a non-finite one, `w = 0`, or a vertex with a value
/// count other than 3 (x y z), 4 (x y z w) or 6 (x y z r g b). Run only
/// after tobj or the validation failed, to say where.
fn diagnose_values(text: &str, path: &Path) -> Result<(), MeshError> {
    let numbers = |words: &[&str], n: usize, line: usize, what: &str| -> Result<(), MeshError> {
        if words.len() < n {
            return Err(parse_error(path, line, format!("{what}: expected {n} numbers, found {}", words.len())));
        }
        for w in &words[..n] {
            match w.parse::<f32>() {
                Ok(x) if x.is_finite() => {}
                Ok(_) => return Err(parse_error(path, line, format!("{what}: {w:?} is not a finite number"))),
                Err(_) => return Err(parse_error(path, line, format!("{what}: {w:?} is not a number"))),
            }
        }
        Ok(())
    };
    for (i, line) in text.split('\n').enumerate() {
        let line_no = i + 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.first().copied() {
            Some("v") => {
                let rest = &words[1..];
                numbers(rest, 3, line_no, "vertex position")?;
                match rest.len() {
                    3 => {}
                    4 => {
                        numbers(&rest[3..], 1, line_no, "vertex w")?;
                        if rest[3].parse::<f32>() == Ok(0.0) {
                            return Err(parse_error(path, line_no, "vertex w is 0".into()));
                        }
                    }
                    6 => numbers(&rest[3..], 3, line_no, "vertex colour")?,
                    k => {
                        return Err(parse_error(
                            path,
                            line_no,
                            format!("vertex with {k} values; expected x y z, x y z w or x y z r g b"),
                        ))
                    }
                }
            }
            Some("vt") => numbers(&words[1..], 2, line_no, "texture coordinate (u v)")?,
            Some("vn") => numbers(&words[1..], 3, line_no, "normal")?,
            _ => {}
        }
    }
    Ok(())
}

/// Whether tobj would reject this `usemtl` line for lacking a name (it
/// takes the name after the first space).
fn unnamed_usemtl(line: &str) -> bool {
    line.split_once(' ').is_none_or(|(_, name)| name.trim().is_empty())
}

/// The text with polylines and unnamed `usemtl` lines blanked and vertex
/// colours removed; line numbers are kept.
fn rewrite(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for (i, line) in text.split('\n').enumerate() {
        if i > 0 {
            out.push('\n');
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.first().copied() {
            Some("l") => {}
            Some("usemtl") if unnamed_usemtl(line) => {}
            Some("v") if words.len() == 7 => out.push_str(&words[..4].join(" ")),
            _ => out.push_str(line),
        }
    }
    out
}
