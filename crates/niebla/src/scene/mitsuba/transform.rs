//! Mitsuba transforms: `<transform>` with `translate`, `rotate`, `scale`,
//! `matrix` and `lookat` children, each applied after the ones before it
//! (`M = op * M`), as 4x4 row-major matrices in f64 acting on column vectors.

use super::props::numbers;
use super::xml::Node;
use crate::scene::SceneError;

/// A row-major 4x4 affine matrix acting on column vectors `[x, y, z, 1]`.
pub(super) type Mat4 = [[f64; 4]; 4];

/// The identity.
pub(super) const IDENTITY: Mat4 =
    [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];

/// `a * b`.
pub(super) fn mul(a: &Mat4, b: &Mat4) -> Mat4 {
    let mut m = [[0.0; 4]; 4];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

/// The image of point `p`.
pub(super) fn point(m: &Mat4, p: [f64; 3]) -> [f64; 3] {
    let r = |i: usize| m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3];
    [r(0), r(1), r(2)]
}

/// The image of vector `v` (no translation).
pub(super) fn vector(m: &Mat4, v: [f64; 3]) -> [f64; 3] {
    let r = |i: usize| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2];
    [r(0), r(1), r(2)]
}

/// Determinant of the upper 3x3.
pub(super) fn det3(m: &Mat4) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Whether `m` is exactly the identity.
pub(super) fn is_identity(m: &Mat4) -> bool {
    *m == IDENTITY
}

/// Whether the upper 3x3 is diagonal (an axis-aligned scale) with a positive
/// diagonal, and the last row is `[0, 0, 0, 1]`.
pub(super) fn is_axis_aligned(m: &Mat4) -> bool {
    (0..3).all(|i| (0..3).all(|j| (i == j) == (m[i][j] != 0.0)) && m[i][i] > 0.0) && m[3] == [0.0, 0.0, 0.0, 1.0]
}

pub(super) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(super) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

pub(super) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = norm(a);
    (n > 0.0 && n.is_finite()).then(|| a.map(|x| x / n))
}

/// The matrix as niebla's JSON transform `{"matrix": [[...] x4]}`.
pub(super) fn to_json(m: &Mat4) -> serde_json::Value {
    serde_json::json!({ "matrix": m.iter().map(|r| r.to_vec()).collect::<Vec<_>>() })
}

/// What a `<transform>` also says beyond its matrix, so that the importer can
/// hand niebla the numbers as written (niebla composes its own transforms in
/// f32; a matrix composed here in f64 and rounded would differ in the last
/// bit, which decorrelates random decisions in a render).
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Form {
    /// A single `<lookat>`: origin, target and up as written.
    LookAt {
        /// The eye position.
        origin: [f64; 3],
        /// The point looked at.
        target: [f64; 3],
        /// The up vector (not normalized).
        up: [f64; 3],
    },
    /// At most one each of `<scale>`, `<rotate>` about +x, +y, +z and
    /// `<translate>`, in that order: niebla's own transform object
    /// (`scale`, `rotate_x`, `rotate_y`, `rotate_z`, `translate`).
    Components(serde_json::Value),
    /// Anything else: only the matrix describes it.
    Matrix,
}

/// Reads a `<transform>` element: its matrix and its [`Form`].
pub(super) fn read_transform_form(node: &Node) -> Result<(Mat4, Form), SceneError> {
    node.check_attrs(&["name"])?;
    let mut m = IDENTITY;
    for op in &node.children {
        let step = read_op(op)?;
        m = mul(&step, &m);
    }
    if m.iter().flatten().any(|x| !x.is_finite()) {
        return Err(node.loc.error("<transform>: the matrix is not finite"));
    }
    Ok((m, form(node)?))
}

/// The [`Form`] of a `<transform>` whose operations all read (see `read_op`).
fn form(node: &Node) -> Result<Form, SceneError> {
    if let [op] = node.children.as_slice() {
        if op.tag == "lookat" {
            return Ok(Form::LookAt {
                origin: three(op, "origin")?,
                target: three(op, "target")?,
                up: three(op, "up")?,
            });
        }
    }
    // Stages in niebla's order: scale 0, rotate x 1, y 2, z 3, translate 4.
    let mut out = serde_json::Map::new();
    let mut last = None;
    for op in &node.children {
        let (stage, key, value) = match op.tag.as_str() {
            "scale" => {
                let s = xyz(op, 1.0, true)?;
                let v = if s[0] == s[1] && s[1] == s[2] { serde_json::json!(s[0]) } else { serde_json::json!(s) };
                (0, "scale", v)
            }
            "rotate" => {
                let a = xyz(op, 0.0, false)?;
                let angle = one_number(op, "angle", op.required("angle")?)?;
                // Unit axes only: Mitsuba does not normalize the axis.
                match a {
                    [1.0, 0.0, 0.0] => (1, "rotate_x", serde_json::json!(angle)),
                    [0.0, 1.0, 0.0] => (2, "rotate_y", serde_json::json!(angle)),
                    [0.0, 0.0, 1.0] => (3, "rotate_z", serde_json::json!(angle)),
                    _ => return Ok(Form::Matrix),
                }
            }
            "translate" => (4, "translate", serde_json::json!(xyz(op, 0.0, false)?)),
            _ => return Ok(Form::Matrix),
        };
        if last.is_some_and(|l| stage <= l) {
            return Ok(Form::Matrix);
        }
        last = Some(stage);
        out.insert(key.into(), value);
    }
    Ok(Form::Components(serde_json::Value::Object(out)))
}

/// `x`, `y`, `z` attributes (each defaulting to `default`) or `value="x, y, z"`.
fn xyz(op: &Node, default: f64, uniform_value: bool) -> Result<[f64; 3], SceneError> {
    if let Some(v) = op.attr("value") {
        if op.attr("x").is_some() || op.attr("y").is_some() || op.attr("z").is_some() {
            return Err(op.loc.error(format!("<{}>: give `value` or `x`/`y`/`z`, not both", op.tag)));
        }
        let n = numbers(v).map_err(|m| op.loc.error(format!("<{}>: {m}", op.tag)))?;
        return match n.len() {
            1 if uniform_value => Ok([n[0]; 3]),
            3 => Ok([n[0], n[1], n[2]]),
            k => Err(op.loc.error(format!("<{}>: `value` has {k} numbers, expected 3", op.tag))),
        };
    }
    let mut out = [default; 3];
    for (i, a) in ["x", "y", "z"].iter().enumerate() {
        if let Some(v) = op.attr(a) {
            out[i] = one_number(op, a, v)?;
        }
    }
    Ok(out)
}

fn one_number(op: &Node, name: &str, v: &str) -> Result<f64, SceneError> {
    match numbers(v) {
        Ok(n) if n.len() == 1 => Ok(n[0]),
        _ => Err(op.loc.error(format!("<{}>: `{name}` is \"{v}\", expected one number", op.tag))),
    }
}

fn three(op: &Node, name: &str) -> Result<[f64; 3], SceneError> {
    let v = op.required(name)?;
    match numbers(v) {
        Ok(n) if n.len() == 3 => Ok([n[0], n[1], n[2]]),
        _ => Err(op.loc.error(format!("<{}>: `{name}` is \"{v}\", expected 3 numbers", op.tag))),
    }
}

fn read_op(op: &Node) -> Result<Mat4, SceneError> {
    match op.tag.as_str() {
        "translate" => {
            op.check_attrs(&["x", "y", "z", "value"])?;
            let t = xyz(op, 0.0, false)?;
            let mut m = IDENTITY;
            for i in 0..3 {
                m[i][3] = t[i];
            }
            Ok(m)
        }
        "scale" => {
            op.check_attrs(&["x", "y", "z", "value"])?;
            let s = xyz(op, 1.0, true)?;
            if s.contains(&0.0) {
                return Err(op.loc.error("<scale>: a scale factor is zero (the transform would not be invertible)"));
            }
            let mut m = IDENTITY;
            for i in 0..3 {
                m[i][i] = s[i];
            }
            Ok(m)
        }
        "rotate" => {
            op.check_attrs(&["x", "y", "z", "value", "angle"])?;
            // Mitsuba 3.9.1 uses the axis as written, not normalized (a
            // non-unit axis gives a matrix that also scales and shears).
            let axis = xyz(op, 0.0, false)?;
            if axis == [0.0; 3] {
                return Err(op.loc.error("<rotate>: the axis is zero"));
            }
            let angle = one_number(op, "angle", op.required("angle")?)?;
            Ok(rotation(axis, angle))
        }
        "matrix" => {
            op.check_attrs(&["value"])?;
            let n = numbers(op.required("value")?).map_err(|m| op.loc.error(format!("<matrix>: {m}")))?;
            let mut m = IDENTITY;
            match n.len() {
                16 => {
                    for i in 0..4 {
                        for j in 0..4 {
                            m[i][j] = n[4 * i + j];
                        }
                    }
                }
                9 => {
                    for i in 0..3 {
                        for j in 0..3 {
                            m[i][j] = n[3 * i + j];
                        }
                    }
                }
                k => return Err(op.loc.error(format!("<matrix>: {k} numbers, expected 16 (4x4) or 9 (3x3)"))),
            }
            if m[3] != [0.0, 0.0, 0.0, 1.0] {
                return Err(op
                    .loc
                    .error("<matrix>: the last row must be 0 0 0 1 (a projective matrix is not a placement)"));
            }
            if det3(&m) == 0.0 {
                return Err(op.loc.error("<matrix>: singular (its 3x3 part has determinant 0)"));
            }
            Ok(m)
        }
        "lookat" => {
            op.check_attrs(&["origin", "target", "up"])?;
            let origin = three(op, "origin")?;
            let target = three(op, "target")?;
            let up = three(op, "up")?;
            look_at(origin, target, up).ok_or_else(|| {
                op.loc.error("<lookat>: degenerate (target equals origin, or up is parallel to the view direction)")
            })
        }
        other => Err(op.loc.error(format!(
            "<transform>: unknown operation <{other}> (expected translate, rotate, scale, matrix or lookat)"
        ))),
    }
}

/// Rotation by `angle` degrees about `axis`, right-handed (Mitsuba's
/// `Transform4f::rotate`, Rodrigues' formula with the axis as given: a
/// rotation for a unit axis).
pub(super) fn rotation(axis: [f64; 3], angle: f64) -> Mat4 {
    let (s, c) = angle.to_radians().sin_cos();
    let [x, y, z] = axis;
    let t = 1.0 - c;
    [
        [x * x * t + c, x * y * t - z * s, x * z * t + y * s, 0.0],
        [x * y * t + z * s, y * y * t + c, y * z * t - x * s, 0.0],
        [x * z * t - y * s, y * z * t + x * s, z * z * t + c, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// Mitsuba's `look_at`: columns `left = normalize(up x dir)`, `dir x left`,
/// `dir = normalize(target - origin)`, and `origin`.
pub(super) fn look_at(origin: [f64; 3], target: [f64; 3], up: [f64; 3]) -> Option<Mat4> {
    let dir = normalize([target[0] - origin[0], target[1] - origin[1], target[2] - origin[2]])?;
    let left = normalize(cross(up, dir))?;
    let new_up = cross(dir, left);
    let mut m = IDENTITY;
    for i in 0..3 {
        m[i][0] = left[i];
        m[i][1] = new_up[i];
        m[i][2] = dir[i];
        m[i][3] = origin[i];
    }
    Some(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_about_z_turns_x_into_y() {
        let m = rotation([0.0, 0.0, 1.0], 90.0);
        let p = point(&m, [1.0, 0.0, 0.0]);
        assert!((p[0]).abs() < 1e-15 && (p[1] - 1.0).abs() < 1e-15, "{p:?}");
    }

    #[test]
    fn look_at_maps_z_to_the_view_direction() {
        let m = look_at([1.0, 2.0, 3.0], [1.0, 2.0, 0.0], [0.0, 1.0, 0.0]).unwrap();
        assert_eq!(vector(&m, [0.0, 0.0, 1.0]), [0.0, 0.0, -1.0]);
        assert_eq!(point(&m, [0.0; 3]), [1.0, 2.0, 3.0]);
        // Left of a camera looking down -z with y up is -x.
        assert_eq!(vector(&m, [1.0, 0.0, 0.0]), [-1.0, 0.0, 0.0]);
    }
}
