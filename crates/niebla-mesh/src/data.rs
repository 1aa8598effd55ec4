//! [`MeshData`]: an indexed triangle mesh with optional per-vertex normals
//! and texture coordinates, and its validation.

use crate::MeshError;

/// An indexed triangle mesh in the file's (object) space.
///
/// Conventions (those of pbrt-v4 and Mitsuba 3):
/// - **Units**: positions are in whatever length unit the scene uses; no
///   scaling is applied by the readers.
/// - **Winding**: a triangle `[a, b, c]` whose corners are seen in
///   counter-clockwise order from outside has the outward face normal
///   `(p_b - p_a) x (p_c - p_a)` (right-hand rule). Meshes that bound a
///   medium should be closed and consistently wound; see
///   [`MeshData::closedness`].
/// - **Texture coordinates**: `(u, v)` with the origin at the *bottom-left*
///   of the image, `v` pointing up (OBJ's and PLY's convention, also
///   pbrt's and Mitsuba's); stored as read, not flipped or wrapped.
/// - **Normals**: shading normals as read (not renormalized); the geometric
///   normal always comes from the winding.
///
/// Every [`MeshData`] built by this crate has passed [`MeshData::from_arrays`]:
/// indices in range, finite values, attribute counts equal to the vertex
/// count. The fields are public for reading; code that changes them should
/// rebuild through [`MeshData::from_arrays`] to keep those guarantees.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeshData {
    /// Vertex positions `[x, y, z]`, in scene length units.
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex shading normals `[nx, ny, nz]` (same count as
    /// `positions`), or `None` when the file has none.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Per-vertex texture coordinates `[u, v]` (same count as `positions`),
    /// origin bottom-left, or `None` when the file has none.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Triangles as three 0-based indices into `positions`, counter-clockwise
    /// seen from the side the face normal points to.
    pub indices: Vec<[u32; 3]>,
}

impl MeshData {
    /// Checks and assembles a mesh: every index below the vertex count,
    /// every position, normal and uv finite, `normals` and `uvs` (when
    /// given) with one entry per vertex. The error names the first offending
    /// element, e.g. `indices[12][2]: vertex index 907 out of range (the mesh
    /// has 800 vertices)`, with origin `"mesh arrays"` (replace it with
    /// [`MeshError::with_origin`]). Degenerate triangles are accepted (see
    /// [`MeshData::degenerate_triangles`]).
    pub fn from_arrays(
        positions: Vec<[f32; 3]>,
        indices: Vec<[u32; 3]>,
        normals: Option<Vec<[f32; 3]>>,
        uvs: Option<Vec<[f32; 2]>>,
    ) -> Result<MeshData, MeshError> {
        let invalid = |what: String| MeshError::Invalid { origin: "mesh arrays".into(), what };
        let n = positions.len();
        if u32::try_from(n).is_err() {
            return Err(invalid(format!("{n} vertices; at most {} can be indexed by u32", u32::MAX)));
        }
        for (i, p) in positions.iter().enumerate() {
            if let Some(k) = p.iter().position(|c| !c.is_finite()) {
                return Err(invalid(format!("positions[{i}][{k}]: {} is not a finite number", p[k])));
            }
        }
        if let Some(normals) = &normals {
            if normals.len() != n {
                return Err(invalid(format!("{} normals for {n} vertices (need one per vertex)", normals.len())));
            }
            for (i, v) in normals.iter().enumerate() {
                if let Some(k) = v.iter().position(|c| !c.is_finite()) {
                    return Err(invalid(format!("normals[{i}][{k}]: {} is not a finite number", v[k])));
                }
            }
        }
        if let Some(uvs) = &uvs {
            if uvs.len() != n {
                return Err(invalid(format!("{} uvs for {n} vertices (need one per vertex)", uvs.len())));
            }
            for (i, v) in uvs.iter().enumerate() {
                if let Some(k) = v.iter().position(|c| !c.is_finite()) {
                    return Err(invalid(format!("uvs[{i}][{k}]: {} is not a finite number", v[k])));
                }
            }
        }
        for (t, tri) in indices.iter().enumerate() {
            for (k, &i) in tri.iter().enumerate() {
                if i as usize >= n {
                    return Err(invalid(format!(
                        "indices[{t}][{k}]: vertex index {i} out of range (the mesh has {n} vertices)"
                    )));
                }
            }
        }
        Ok(MeshData { positions, normals, uvs, indices })
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles, degenerate ones included.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// Whether triangle `t` (an index into `indices`) is degenerate: two of
    /// its indices are equal or its area is exactly zero (the cross product
    /// of two edges, computed in `f64` from the `f32` positions, is the zero
    /// vector). Renderers skip these triangles; readers keep them.
    /// Panics if `t >= self.triangle_count()`.
    pub fn is_degenerate(&self, t: usize) -> bool {
        let [a, b, c] = self.indices[t];
        if a == b || b == c || a == c {
            return true;
        }
        let p = |i: u32| self.positions[i as usize].map(f64::from);
        let (pa, pb, pc) = (p(a), p(b), p(c));
        let e1 = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
        let e2 = [pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]];
        let cross = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]];
        cross == [0.0; 3]
    }

    /// Number of degenerate triangles ([`MeshData::is_degenerate`]), which a
    /// renderer skips and reports.
    pub fn degenerate_triangles(&self) -> usize {
        (0..self.indices.len()).filter(|&t| self.is_degenerate(t)).count()
    }

    /// Axis-aligned bounds `(min, max)` of the vertices referenced by at
    /// least one triangle, or `None` for a mesh without triangles.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let mut it = self.indices.iter().flatten();
        let first = self.positions[*it.next()? as usize];
        let (mut lo, mut hi) = (first, first);
        for &i in it {
            let p = self.positions[i as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        Some((lo, hi))
    }

    /// Bytes the mesh's arrays occupy in memory: 12 per position, 12 per
    /// normal, 8 per uv and 12 per triangle (capacity slack not counted).
    pub fn memory_bytes(&self) -> u64 {
        let n = self.positions.len() as u64;
        let per_vertex = 12 + if self.normals.is_some() { 12 } else { 0 } + if self.uvs.is_some() { 8 } else { 0 };
        n * per_vertex + 12 * self.indices.len() as u64
    }

    /// The same mesh with its vertices renumbered in order of first use in
    /// `indices` (triangle by triangle, corner by corner) and unreferenced
    /// vertices dropped. This is the order the OBJ reader returns; the
    /// generators of this crate return meshes already in this order, so
    /// that they read back identical from every format.
    pub fn renumbered_by_first_use(&self) -> MeshData {
        let mut new_of_old = vec![u32::MAX; self.positions.len()];
        let mut order: Vec<u32> = Vec::new();
        let indices = self
            .indices
            .iter()
            .map(|tri| {
                tri.map(|i| {
                    let slot = &mut new_of_old[i as usize];
                    if *slot == u32::MAX {
                        *slot = order.len() as u32;
                        order.push(i);
                    }
                    *slot
                })
            })
            .collect();
        let pick3 = |v: &Vec<[f32; 3]>| order.iter().map(|&i| v[i as usize]).collect();
        MeshData {
            positions: pick3(&self.positions),
            normals: self.normals.as_ref().map(pick3),
            uvs: self.uvs.as_ref().map(|v| order.iter().map(|&i| v[i as usize]).collect()),
            indices,
        }
    }

    /// Appends `other`'s vertices and triangles (its indices offset by this
    /// mesh's vertex count). An attribute is kept only when both meshes have
    /// it (or this one is empty and `other` has it); otherwise it is dropped.
    /// The caller checks that the total vertex count fits in `u32`.
    pub(crate) fn append(&mut self, other: MeshData) {
        let first = self.positions.is_empty() && self.indices.is_empty();
        let offset = self.positions.len() as u32;
        self.normals = match (first, self.normals.take(), other.normals) {
            (true, _, theirs) => theirs,
            (false, Some(mut mine), Some(theirs)) => {
                mine.extend(theirs);
                Some(mine)
            }
            _ => None,
        };
        self.uvs = match (first, self.uvs.take(), other.uvs) {
            (true, _, theirs) => theirs,
            (false, Some(mut mine), Some(theirs)) => {
                mine.extend(theirs);
                Some(mine)
            }
            _ => None,
        };
        self.positions.extend(other.positions);
        self.indices.extend(other.indices.into_iter().map(|t| t.map(|i| i + offset)));
    }
}
