//! Building the `mesh` shapes of a scene: reading the file (or the inline
//! arrays), charging the memory budget before reading, turning the mesh
//! inside out or flat where asked, checking that a mesh bounding a medium is
//! closed, and sharing one mesh between shapes that read the same file with
//! the same options (instances under different `to_world`).

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use niebla_mesh::MeshData;

use super::desc::{MeshDesc, ShadingBacksideDesc};
use super::SceneError;
use crate::geometry::{MeshInstance, Transform, TriangleMesh};
use crate::limits::MemoryBudget;
use crate::math::{Vec2, Vec3};

/// What makes two mesh shapes share their mesh: the file, the OBJ object
/// and the two options that change the data.
type MeshKey = (PathBuf, Option<String>, bool, bool, bool, bool);

/// A loaded mesh and whether it is closed (checked once per mesh).
#[derive(Clone)]
struct Loaded {
    mesh: Arc<TriangleMesh>,
    closedness: niebla_mesh::Closedness,
    /// The bytes charged to the memory budget for it.
    bytes: u64,
}

/// The meshes of the scene builds sharing a [`super::SceneCache`], shared
/// by key: within one build by every shape naming the same key, across
/// builds (the frames of a sequence) while the next build still uses them.
#[derive(Default)]
pub(super) struct MeshLoader {
    cache: HashMap<MeshKey, Loaded>,
    /// Keys used (and charged to the budget) by the build in progress.
    used: HashSet<MeshKey>,
}

impl MeshLoader {
    /// Number of files held.
    pub(super) fn len(&self) -> usize {
        self.cache.len()
    }

    /// Ends a build: files it did not use are dropped.
    pub(super) fn finish_build(&mut self) {
        let used = std::mem::take(&mut self.used);
        self.cache.retain(|key, _| used.contains(key));
    }

    /// The instance of mesh shape `desc` at JSON path `path` (placed by
    /// `transform`); `bounds_medium` when it has an `interior` or `exterior`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn instance(
        &mut self,
        desc: &MeshDesc,
        transform: Transform,
        bounds_medium: bool,
        path: &str,
        source: &str,
        base_dir: &Path,
        budget: &mut MemoryBudget,
    ) -> Result<MeshInstance, SceneError> {
        let err = |field: &str, message: String| SceneError::new(source, field, message);
        let loaded = match &desc.file {
            Some(file) => {
                let full = base_dir.join(file);
                let key = (
                    full.clone(),
                    desc.object.clone(),
                    desc.flip_normals,
                    desc.face_normals,
                    desc.flip_tex_coords,
                    desc.compute_normals,
                );
                let field = format!("{path}.file");
                match self.cache.get(&key) {
                    Some(l) => {
                        if self.used.insert(key) {
                            budget.charge(l.bytes).map_err(|why| err(&field, format!("mesh {file:?} {why}")))?;
                        }
                        l.clone()
                    }
                    None => {
                        let estimate =
                            niebla_mesh::estimate_mesh_bytes(&full).map_err(|e| err(&field, e.to_string()))?;
                        budget.charge(estimate).map_err(|why| err(&field, format!("mesh {file:?} {why}")))?;
                        let options =
                            niebla_mesh::MeshReadOptions { object: desc.object.clone(), ..Default::default() };
                        let data = niebla_mesh::read_mesh(&full, &options).map_err(|e| err(&field, e.to_string()))?;
                        let l = load(data, desc, estimate).map_err(|m| err(&field, format!("{file}: {m}")))?;
                        self.used.insert(key.clone());
                        self.cache.insert(key, l.clone());
                        l
                    }
                }
            }
            None => {
                let positions = desc.positions.clone().unwrap_or_default();
                let indices = desc.indices.clone().unwrap_or_default();
                let bytes = TriangleMesh::memory_estimate(
                    positions.len(),
                    indices.len(),
                    desc.normals.is_some(),
                    desc.uvs.is_some(),
                ) as u64;
                budget.charge(bytes).map_err(|why| err(path, format!("inline mesh {why}")))?;
                let data = MeshData::from_arrays(positions, indices, desc.normals.clone(), desc.uvs.clone())
                    .map_err(|e| inline_error(e, path, source))?;
                load(data, desc, bytes).map_err(|m| err(path, m))?
            }
        };
        let c = loaded.closedness;
        if bounds_medium && !c.is_closed() && !desc.allow_open {
            let what = desc.file.as_ref().map_or(String::new(), |f| format!("{f}: "));
            return Err(err(
                path,
                format!(
                    "{what}a mesh that bounds a medium (interior/exterior) must be closed, but this one has {} open \
                     (boundary) edges, {} non-manifold edges and {} inconsistently wound edges; close it, or \
                     set \"allow_open\": true to let it act as a one-sided boundary like a rectangle",
                    c.boundary_edges, c.non_manifold_edges, c.inconsistent_edges
                ),
            ));
        }
        Ok(MeshInstance::new(loaded.mesh, transform, c.is_closed()))
    }
}

/// An inline mesh's error at the JSON path of the offending array element
/// (the message of [`MeshData::from_arrays`] starts with it, e.g.
/// `indices[3][1]: ...`).
fn inline_error(e: niebla_mesh::MeshError, path: &str, source: &str) -> SceneError {
    let text = match &e {
        niebla_mesh::MeshError::Invalid { what, .. } => what.clone(),
        other => other.to_string(),
    };
    match text.split_once(": ") {
        Some((field, message)) if field.ends_with(']') => {
            SceneError::new(source, format!("{path}.{field}"), message.to_string())
        }
        _ => SceneError::new(source, path, text),
    }
}

/// Vertex normals from the triangles around each vertex, weighted by the
/// triangle's angle at the vertex (Thuermer and Wuethrich 1998), the winding's
/// unit normal `(p1 - p0) x (p2 - p0)` of each triangle with area; a vertex
/// without any gets `(1, 0, 0)` (Mitsuba 3's `recompute_vertex_normals`).
fn angle_weighted_normals(positions: &[[f32; 3]], indices: &[[u32; 3]]) -> Vec<[f32; 3]> {
    use glam::DVec3;
    let p = |i: u32| DVec3::from(positions[i as usize].map(f64::from));
    let mut sums = vec![DVec3::ZERO; positions.len()];
    for tri in indices {
        let v = tri.map(p);
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        if !(n.length_squared() > 0.0) || !n.is_finite() {
            continue;
        }
        let n = n.normalize();
        for j in 0..3 {
            let (a, b) = ((v[(j + 1) % 3] - v[j]).normalize(), (v[(j + 2) % 3] - v[j]).normalize());
            let angle = a.dot(b).clamp(-1.0, 1.0).acos();
            sums[tri[j] as usize] += n * angle;
        }
    }
    sums.into_iter()
        .map(|s| if s.length_squared() > 0.0 { s.normalize().as_vec3().to_array() } else { [1.0, 0.0, 0.0] })
        .collect()
}

/// The renderer's mesh from checked mesh data, with the shape's options.
fn load(mut data: MeshData, desc: &MeshDesc, bytes: u64) -> Result<Loaded, String> {
    if desc.face_normals {
        data.normals = None;
    } else if desc.compute_normals && data.normals.is_none() {
        data.normals = Some(angle_weighted_normals(&data.positions, &data.indices));
    }
    if desc.flip_tex_coords {
        if let Some(uvs) = &mut data.uvs {
            for uv in uvs.iter_mut() {
                uv[1] = 1.0 - uv[1];
            }
        }
    }
    if desc.flip_normals {
        for t in &mut data.indices {
            t.swap(1, 2);
        }
        if let Some(normals) = &mut data.normals {
            for n in normals.iter_mut() {
                *n = n.map(|c| -c);
            }
        }
    }
    if data.indices.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    let closedness = data.closedness();
    let MeshData { positions, normals, uvs, indices } = data;
    let mut mesh = TriangleMesh::new(
        positions.into_iter().map(Vec3::from).collect(),
        indices,
        normals.map(|n| n.into_iter().map(Vec3::from).collect()),
        uvs.map(|u| u.into_iter().map(Vec2::from).collect()),
    )
    .map_err(|e| e.to_string())?;
    mesh.winding_flipped = desc.flip_normals;
    mesh.keeps_backside_ns = desc.shading_normal_backside == ShadingBacksideDesc::Mitsuba;
    if mesh.triangle_count() == 0 {
        return Err(format!("all {} triangles are degenerate (no area)", mesh.degenerate));
    }
    Ok(Loaded { mesh: Arc::new(mesh), closedness, bytes })
}
