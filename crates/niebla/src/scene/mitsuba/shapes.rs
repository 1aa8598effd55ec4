//! `<shape>`: `sphere`, `cube`, `rectangle`, `disk`, `obj`, `ply` (with their
//! `to_world`, bsdf, `interior`/`exterior` media and an `area` emitter) into
//! niebla shapes, or into an area light for an emitting shape (an `obj`,
//! `ply` or `cube` becomes a mesh light).

use serde_json::{json, Map, Value};

use super::convert::{color_json, Converter};
use super::props::Props;
use super::transform::{
    dot, is_axis_aligned, is_identity, mul, norm, point, rotation, to_json, vector, Form, Mat4, IDENTITY,
};
use super::xml::Node;
use crate::scene::SceneError;

/// The unit cube `[-1, 1]^3` as 8 corners (corner `i` has x, y, z from bits 0, 1, 2).
fn cube_positions() -> Vec<[f64; 3]> {
    (0..8).map(|i| [bit(i, 0), bit(i, 1), bit(i, 2)]).collect()
}

fn bit(i: u32, b: u32) -> f64 {
    if i >> b & 1 == 1 {
        1.0
    } else {
        -1.0
    }
}

/// Its 12 triangles, counter-clockwise seen from outside.
const CUBE_TRIANGLES: [[u32; 3]; 12] = [
    [0, 4, 6],
    [0, 6, 2],
    [1, 3, 7],
    [1, 7, 5],
    [0, 1, 5],
    [0, 5, 4],
    [2, 6, 7],
    [2, 7, 3],
    [0, 2, 3],
    [0, 3, 1],
    [4, 5, 7],
    [4, 7, 6],
];

/// Mitsuba 3's own `cube` mesh (its `src/shapes/cube.cpp`): the cube
/// `[-1, 1]^3` as 24 vertices, 4 per face, with the face's outward normal
/// and uvs `(0, 1), (1, 1), (1, 0), (0, 0)`, and 2 triangles per face
/// (local vertices `0 1 2` and `3 0 2`), faces in the order -y, +y, +x, +z,
/// -x, -z. A face's vertex with uv `(u, v)` sits at
/// `n + (2u - 1) a_u + (2v - 1) a_v` with the face's axes `a_u`, `a_v`
/// below, so that `dp/du = 2 a_u` on every face. Returns positions,
/// normals, uvs and triangles.
#[allow(clippy::type_complexity)]
pub(super) fn mitsuba_cube() -> (Vec<[f64; 3]>, Vec<[f64; 3]>, Vec<[f64; 2]>, Vec<[u32; 3]>) {
    // (normal, a_u, a_v) per face, read off Mitsuba's vertex table.
    const FACES: [[[f64; 3]; 3]; 6] = [
        [[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]],
        [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]],
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]],
        [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
        [[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        [[0.0, 0.0, -1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]],
    ];
    const UVS: [[f64; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let (mut positions, mut normals, mut uvs, mut triangles) = (vec![], vec![], vec![], vec![]);
    for (f, [n, au, av]) in FACES.iter().enumerate() {
        for uv in UVS {
            let (su, sv) = (2.0 * uv[0] - 1.0, 2.0 * uv[1] - 1.0);
            positions.push([0, 1, 2].map(|i| n[i] + su * au[i] + sv * av[i]));
            normals.push(*n);
            uvs.push(uv);
        }
        let o = 4 * f as u32;
        triangles.push([o, o + 1, o + 2]);
        triangles.push([o + 3, o, o + 2]);
    }
    (positions, normals, uvs, triangles)
}

/// True when a converted bsdf (or a side of its `twosided`) has an
/// anisotropic roughness (`alpha_u` other than `alpha_v`).
fn anisotropic(bsdf: &Value) -> bool {
    match bsdf.get("bsdf") {
        Some(Value::Array(sides)) => sides.iter().any(anisotropic),
        Some(side @ Value::Object(_)) => anisotropic(side),
        _ => bsdf.get("alpha_u").is_some() && bsdf.get("alpha_u") != bsdf.get("alpha_v"),
    }
}

/// Converts one `<shape>` and appends it to the scene's shapes (or lights).
pub(super) fn convert_shape<'a>(c: &mut Converter<'a>, node: &'a Node) -> Result<(), SceneError> {
    let p = Props::new(node)?;
    let t = p.plugin_type()?;
    let (m, form) = p.transform_form("to_world")?.unwrap_or((IDENTITY, Form::Matrix));
    // niebla's own transform object where the XML spells one (the numbers as
    // written, composed by niebla in f32 as from a JSON scene), else the matrix.
    let to_world = |m: &Mat4| match &form {
        Form::Components(c) => c.clone(),
        _ => to_json(m),
    };
    let flip = p.boolean("flip_normals")?.unwrap_or(false);
    let mut shape = Map::new();
    // Mitsuba's flip_tex_coords (default true for OBJ, false for PLY).
    let mut flip_tex_coords = false;
    // An obj or ply file read by the importer (its full path).
    let mut mesh_file = None;
    match t {
        "sphere" => {
            let center = p.vec3("center")?.unwrap_or([0.0; 3]);
            let radius = p.float_or("radius", 1.0)?;
            if flip {
                return Err(p.error("`flip_normals` on a sphere is not supported"));
            }
            let s = uniform_scale(&m).ok_or_else(|| {
                p.error(
                    "to_world of a sphere must be a uniform scale, rotation and translation (niebla has no ellipsoids)",
                )
            })?;
            if !(radius > 0.0) {
                return Err(p.error(format!("`radius` must be > 0, got {radius}")));
            }
            shape.insert("type".into(), json!("sphere"));
            shape.insert("center".into(), json!(point(&m, center)));
            // Mitsuba keeps the rotation of the sphere's to_world: it turns
            // the uvs and dp/du (niebla's "rotation"; the surface is the same).
            // Written as niebla's angles where the XML spells them in niebla's
            // order (niebla then composes them in f32, as from a JSON scene),
            // else as the matrix.
            match sphere_components(&form) {
                Some((scale, angles)) => {
                    shape.insert("radius".into(), json!(radius * scale));
                    if angles.iter().any(|a| *a != 0.0) {
                        let keys = ["rotate_x", "rotate_y", "rotate_z"];
                        let rotation: Map<String, Value> = keys
                            .iter()
                            .zip(angles)
                            .filter(|(_, a)| *a != 0.0)
                            .map(|(k, a)| ((*k).to_string(), json!(a)))
                            .collect();
                        shape.insert("rotation".into(), Value::Object(rotation));
                    }
                }
                None => {
                    shape.insert("radius".into(), json!(radius * s));
                    let r = |i: usize, j: usize| m[i][j] / s;
                    if (0..3).any(|i| (0..3).any(|j| (r(i, j) - if i == j { 1.0 } else { 0.0 }).abs() > 1e-6)) {
                        let rows: Vec<[f64; 3]> = (0..3).map(|i| [r(i, 0), r(i, 1), r(i, 2)]).collect();
                        shape.insert("rotation".into(), json!({ "matrix": rows }));
                    }
                }
            }
        }
        // Its geometry depends on the bsdf (below).
        "cube" => {}
        "rectangle" | "disk" => {
            // Flipping the normal of [-1, 1]^2 (or of the unit disk) is a half
            // turn about x: the same set, facing -z.
            let m = if flip { mul(&m, &rotation([1.0, 0.0, 0.0], 180.0)) } else { m };
            shape.insert("type".into(), json!(t));
            if !is_identity(&m) {
                shape.insert("to_world".into(), if flip { to_json(&m) } else { to_world(&m) });
            }
        }
        "obj" | "ply" => {
            let (file, full) = c.file(&p, "filename")?;
            mesh_file = Some(full);
            shape.insert("type".into(), json!("mesh"));
            shape.insert("file".into(), json!(file));
            if !is_identity(&m) {
                shape.insert("to_world".into(), to_world(&m));
            }
            if flip {
                shape.insert("flip_normals".into(), json!(true));
            }
            if p.boolean("face_normals")?.unwrap_or(false) {
                shape.insert("face_normals".into(), json!(true));
            } else {
                // Vertex normals (if the file has them) shade as in Mitsuba 3:
                // about the shading normal also where `wo` lies behind it.
                shape.insert("shading_normal_backside".into(), json!("mitsuba"));
                // A file without normals gets Mitsuba's angle-weighted ones.
                shape.insert("compute_normals".into(), json!(true));
            }
            flip_tex_coords = p.boolean("flip_tex_coords")?.unwrap_or(t == "obj");
        }
        _ => return Err(p.error("not supported")),
    }

    // Media, surface and emitter.
    let mut media = Map::new();
    for side in ["interior", "exterior"] {
        if let Some(mnode) = p.plugin_named(side) {
            let name = c.medium(mnode)?;
            media.insert(side.into(), json!(name));
        }
    }
    let mut bsdfs = p.plugins("bsdf");
    let mut emitters = p.plugins("emitter");
    for r in p.unnamed_refs() {
        match c.target_tag(r) {
            Some("bsdf") => bsdfs.push(r),
            Some("emitter") => emitters.push(r),
            _ => return Err(r.loc.error(format!("{}: expected a reference to a <bsdf> here", r.describe()))),
        }
    }
    if bsdfs.len() > 1 {
        return Err(bsdfs[1].loc.error(format!("{}: a shape has one bsdf", bsdfs[1].describe())));
    }
    let bsdf = match bsdfs.first() {
        Some(b) => {
            let b = c.resolve(b, "bsdf")?;
            super::bsdfs::convert_bsdf(c, b)?
        }
        // Mitsuba's default surface.
        None => json!({"type": "diffuse", "reflectance": 0.5}),
    };
    if t == "cube" {
        // Mitsuba's own mesh where the surface reads its uvs or dp/du, else
        // a box (axis-aligned, not flipped) or 12 triangles: the same surface
        // in fewer primitives.
        if anisotropic(&bsdf) || super::textures::has_texture(&bsdf) {
            let (positions, normals, uvs, triangles) = mitsuba_cube();
            shape.insert("type".into(), json!("mesh"));
            shape.insert("positions".into(), json!(positions));
            shape.insert("normals".into(), json!(normals));
            shape.insert("uvs".into(), json!(uvs));
            shape.insert("indices".into(), json!(triangles));
            shape.insert("to_world".into(), to_json(&m));
            if flip {
                shape.insert("flip_normals".into(), json!(true));
            }
        } else if is_axis_aligned(&m) && !flip && emitters.is_empty() {
            shape.insert("type".into(), json!("box"));
            shape.insert("min".into(), json!(point(&m, [-1.0; 3])));
            shape.insert("max".into(), json!(point(&m, [1.0; 3])));
        } else {
            shape.insert("type".into(), json!("mesh"));
            shape.insert("positions".into(), json!(cube_positions()));
            shape.insert("indices".into(), json!(CUBE_TRIANGLES));
            shape.insert("to_world".into(), to_json(&m));
            if flip {
                shape.insert("flip_normals".into(), json!(true));
            }
        }
    }
    // Anisotropic roughness follows Mitsuba's dp/du ("tangent_frame":
    // "dpdu"); niebla's shapes have Mitsuba's uv parameterization, and so its
    // dp/du (a sphere's turned by its "rotation").
    if anisotropic(&bsdf) {
        shape.insert("tangent_frame".into(), json!("dpdu"));
    }
    if flip_tex_coords && super::textures::has_texture(&bsdf) {
        shape.insert("flip_tex_coords".into(), json!(true));
    }
    p.finish()?;
    if emitters.len() > 1 {
        return Err(emitters[1].loc.error("a shape has at most one emitter"));
    }
    if let Some(e) = emitters.first() {
        let e = c.resolve(e, "emitter")?;
        let ep = Props::new(e)?;
        if ep.plugin_type()? != "area" {
            return Err(ep.error("not supported inside a shape (expected area)"));
        }
        let radiance = ep.color("radiance")?.unwrap_or([1.0; 3]);
        ep.finish()?;
        if !matches!(shape.get("type").and_then(Value::as_str), Some("rectangle" | "disk" | "sphere" | "mesh")) {
            return Err(p.error("an area emitter on this shape is not supported"));
        }
        // The surface's options do not apply to a light (nor a sphere's uv
        // rotation: a light's radiance is uniform).
        shape.remove("tangent_frame");
        shape.remove("flip_tex_coords");
        shape.remove("rotation");
        if let Some(full) = &mesh_file {
            check_emitting_mesh(&p, full, &m)?;
        }
        let black = bsdf == json!({"type": "diffuse", "reflectance": 0.0});
        if !black {
            c.notes.push(format!(
                "{}: {}: niebla's area lights absorb what reaches them; the surface's bsdf is not used",
                node.loc.at(),
                p.what()
            ));
        }
        for (side, name) in &media {
            c.notes.push(format!(
                "{}: {}: `{side}` medium \"{}\" of an area light: niebla takes the medium around a light from the \
                 shapes containing it",
                node.loc.at(),
                p.what(),
                name.as_str().unwrap_or("")
            ));
        }
        c.lights.push(json!({"type": "area", "shape": Value::Object(shape), "radiance": color_json(radiance)}));
        return Ok(());
    }
    shape.extend(media);
    shape.insert("bsdf".into(), bsdf);
    c.shapes.push(Value::Object(shape));
    Ok(())
}

/// Files larger than this (estimated bytes in memory) are not read by the
/// importer's area check; the scene builder still refuses them without area.
const EMITTING_MESH_CHECK_BYTES: u64 = 256 << 20;

/// An error at the shape's line when the emitting mesh file `full` cannot be
/// read or has no area once placed by `m` (Mitsuba 3 would sample nothing).
fn check_emitting_mesh(p: &Props, full: &std::path::Path, m: &Mat4) -> Result<(), SceneError> {
    let options = niebla_mesh::MeshReadOptions { object: None, max_bytes: Some(EMITTING_MESH_CHECK_BYTES) };
    let data = match niebla_mesh::read_mesh(full, &options) {
        Ok(data) => data,
        Err(niebla_mesh::MeshError::TooLarge { .. }) => return Ok(()),
        Err(e) => return Err(p.error(format!("the emitting mesh cannot be read: {e}"))),
    };
    let world = |i: u32| point(m, data.positions[i as usize].map(f64::from));
    let area: f64 = data
        .indices
        .iter()
        .map(|&[a, b, c]| {
            let (a, b, c) = (world(a), world(b), world(c));
            let (e1, e2) = ([0, 1, 2].map(|k| b[k] - a[k]), [0, 1, 2].map(|k| c[k] - a[k]));
            let cross = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
            0.5 * norm(cross)
        })
        .filter(|a| a.is_finite())
        .sum();
    if !(area > 0.0) {
        return Err(p.error(format!(
            "an area emitter needs a mesh with a positive area; {} has {} triangles, all without area once placed \
             by to_world",
            full.display(),
            data.indices.len()
        )));
    }
    Ok(())
}

/// A sphere's `to_world` spelled in niebla's order (`<scale>` with one
/// positive factor, `<rotate>` about x, y, z, `<translate>`; each optional):
/// the scale factor and the three angles (degrees, 0 where absent), as
/// written.
fn sphere_components(form: &Form) -> Option<(f64, [f64; 3])> {
    let Form::Components(Value::Object(c)) = form else { return None };
    let scale = match c.get("scale") {
        None => 1.0,
        Some(v) => v.as_f64().filter(|s| *s > 0.0)?,
    };
    let angle = |k: &str| c.get(k).map_or(Some(0.0), Value::as_f64);
    Some((scale, [angle("rotate_x")?, angle("rotate_y")?, angle("rotate_z")?]))
}

/// `s` when the 3x3 part of `m` is `s` times a rotation (within 1e-6 relative).
fn uniform_scale(m: &Mat4) -> Option<f64> {
    let cols = [vector(m, [1.0, 0.0, 0.0]), vector(m, [0.0, 1.0, 0.0]), vector(m, [0.0, 0.0, 1.0])];
    let s = norm(cols[0]);
    let ok = cols.iter().all(|c| (norm(*c) / s - 1.0).abs() < 1e-6)
        && (dot(cols[0], cols[1]) / (s * s)).abs() < 1e-6
        && (dot(cols[0], cols[2]) / (s * s)).abs() < 1e-6
        && (dot(cols[1], cols[2]) / (s * s)).abs() < 1e-6
        && super::transform::det3(m) > 0.0;
    ok.then_some(s)
}
