//! Triangle meshes: shared mesh data with its own hierarchy (object space),
//! and instances placing one mesh in the world by a transform.
//!
//! Conventions: triangles wind counter-clockwise seen from outside, so the
//! geometric normal `(p1 - p0) x (p2 - p0)` points outward (pbrt-v4 and
//! Mitsuba 3 agree); vertex normals, when given, are oriented to agree with
//! the geometric normal (kept as written under Mitsuba 3's rule,
//! [`TriangleMesh::keeps_backside_ns`]); without uv coordinates a hit's uv is its barycentric
//! `(b1, b2)` (Mitsuba 3's convention).

use std::sync::Arc;

use glam::Affine3A;

use super::bvh::Bvh;
use super::triangle::{intersect_triangle, TriangleHit, WatertightRay};
use super::{AxisAlignedBox, PrimitiveHit, SurfaceHit, Transform};
use crate::math::{Ray, Vec2, Vec3};

/// A triangle mesh in its own (object) space, ready for intersection.
#[derive(Clone, Debug)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals (smooth shading), if the mesh has them.
    pub normals: Option<Vec<Vec3>>,
    /// Vertex uv coordinates, if the mesh has them (kept for textures; a hit
    /// interpolates them with [`TriangleMesh::uv_at`]).
    pub uvs: Option<Vec<Vec2>>,
    /// Vertex indices of the non-degenerate triangles, in the order of the
    /// hierarchy's leaves.
    pub triangles: Vec<[u32; 3]>,
    /// Triangles left out because they have no area (repeated or collinear vertices).
    pub degenerate: usize,
    /// True when every triangle's corners 1 and 2 were swapped from the
    /// file's order to turn the mesh inside out (`flip_normals`): the uv and
    /// dp/du of a mesh without uvs then still follow the file's order, as
    /// Mitsuba 3's `flip_normals`, which keeps the winding and negates the
    /// normal. Default false (set by the scene builder).
    pub winding_flipped: bool,
    /// True when a hit whose `wo` lies behind the interpolated normal but in
    /// front of the triangle keeps the shading normal (Mitsuba 3's rule,
    /// `"shading_normal_backside": "mitsuba"`; see
    /// [`SurfaceHit::backside_ns`]), and interpolated normals that point
    /// against the winding are kept as written instead of being turned to
    /// the geometric normal's side (Mitsuba 3 keeps them too). Default
    /// false (set by the scene builder).
    pub keeps_backside_ns: bool,
    /// The corners of each triangle of `triangles`, copied so that a leaf's
    /// triangles are read from contiguous memory without the indirection
    /// through the vertex list (36 bytes per triangle).
    corners: Vec<[Vec3; 3]>,
    /// The hierarchy over `triangles` (its order is the identity).
    bvh: Bvh,
}

/// Why mesh data cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshDataError {
    /// A vertex index points past the vertex list.
    #[error("indices[{triangle}][{corner}]: vertex index {index} out of range (the mesh has {vertices} vertices)")]
    IndexOutOfRange {
        /// Triangle number.
        triangle: usize,
        /// Corner 0..3.
        corner: usize,
        /// The index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// More triangles than one hierarchy holds.
    #[error("{count} triangles; a mesh holds at most {max}")]
    TooManyTriangles {
        /// Triangles given.
        count: usize,
        /// [`super::bvh::MAX_PRIMITIVES`].
        max: usize,
    },
    /// Per-vertex attributes whose count differs from the positions'.
    #[error("{field}: has {got} entries, expected one per vertex ({expected})")]
    CountMismatch {
        /// `normals` or `uvs`.
        field: &'static str,
        /// Entries given.
        got: usize,
        /// Vertices.
        expected: usize,
    },
}

impl TriangleMesh {
    /// Builds a mesh from object-space vertex data and triangles, skipping
    /// (and counting) triangles without area or with a non-finite corner,
    /// and builds its hierarchy. Normals are normalized (zero-length or
    /// non-finite ones are replaced by the face normal at hit time). Files
    /// and inline arrays are checked with their locations before this, by
    /// `niebla_mesh::MeshData::from_arrays`; this only refuses what would
    /// make the mesh unusable.
    pub fn new(
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
        normals: Option<Vec<Vec3>>,
        uvs: Option<Vec<Vec2>>,
    ) -> Result<TriangleMesh, MeshDataError> {
        let nv = positions.len();
        if triangles.len() > super::bvh::MAX_PRIMITIVES {
            return Err(MeshDataError::TooManyTriangles { count: triangles.len(), max: super::bvh::MAX_PRIMITIVES });
        }
        if let Some(n) = &normals {
            if n.len() != nv {
                return Err(MeshDataError::CountMismatch { field: "normals", got: n.len(), expected: nv });
            }
        }
        if let Some(uv) = &uvs {
            if uv.len() != nv {
                return Err(MeshDataError::CountMismatch { field: "uvs", got: uv.len(), expected: nv });
            }
        }
        for (t, tri) in triangles.iter().enumerate() {
            for (corner, &index) in tri.iter().enumerate() {
                if index as usize >= nv {
                    return Err(MeshDataError::IndexOutOfRange { triangle: t, corner, index, vertices: nv });
                }
            }
        }
        let normals = normals.map(|n| n.into_iter().map(|v| v.normalize_or_zero()).collect());
        // normalize_or_zero maps non-finite vectors to zero as well.
        let total = triangles.len();
        let kept: Vec<[u32; 3]> = triangles
            .into_iter()
            .filter(|t| {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                let n = (b - a).cross(c - a);
                t[0] != t[1] && t[1] != t[2] && t[0] != t[2] && n.length_squared() > 0.0 && n.is_finite()
            })
            .collect();
        let degenerate = total - kept.len();
        let boxes: Vec<AxisAlignedBox> = kept
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                AxisAlignedBox { min: a.min(b).min(c), max: a.max(b).max(c) }
            })
            .collect();
        let bvh = Bvh::build(&boxes);
        drop(boxes);
        // Store the triangles in leaf order so a leaf reads them contiguously.
        let triangles: Vec<[u32; 3]> = bvh.order.iter().map(|&i| kept[i as usize]).collect();
        drop(kept);
        let mut bvh = bvh;
        bvh.order = (0..triangles.len() as u32).collect();
        let corners = triangles.iter().map(|t| t.map(|i| positions[i as usize])).collect();
        Ok(TriangleMesh {
            positions,
            normals,
            uvs,
            triangles,
            degenerate,
            winding_flipped: false,
            keeps_backside_ns: false,
            corners,
            bvh,
        })
    }

    /// uv of barycentric point `(b1, b2)` of triangle `prim`: interpolated
    /// vertex uvs, else `(b1, b2)` itself (Mitsuba 3's convention), taken in
    /// the file's corner order (`(b2, b1)` when `winding_flipped`).
    pub fn uv_at(&self, prim: u32, b1: f32, b2: f32) -> Vec2 {
        match &self.uvs {
            Some(uvs) => {
                let [a, b, c] = self.triangles[prim as usize].map(|i| uvs[i as usize]);
                a * (1.0 - b1 - b2) + b * b1 + c * b2
            }
            None if self.winding_flipped => Vec2::new(b2, b1),
            None => Vec2::new(b1, b2),
        }
    }

    /// Number of (non-degenerate) triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Bytes held: vertices, attributes, triangles and the hierarchy.
    pub fn memory_bytes(&self) -> usize {
        self.positions.len() * 12
            + self.normals.as_ref().map_or(0, |n| n.len() * 12)
            + self.uvs.as_ref().map_or(0, |u| u.len() * 8)
            + self.triangles.len() * (12 + 36)
            + self.bvh.memory_bytes()
    }

    /// Bytes a mesh of `vertices` vertices (with normals and uvs when the
    /// flags say so) and `triangles` triangles needs, hierarchy and build
    /// included: an upper bound for `--max-memory` before loading.
    pub fn memory_estimate(vertices: usize, triangles: usize, normals: bool, uvs: bool) -> usize {
        vertices * (12 + if normals { 12 } else { 0 } + if uvs { 8 } else { 0 })
            + triangles * (12 + 36 + 12 + 24)
            + Bvh::memory_estimate(triangles)
    }

    /// Object-space box of the mesh (`None` without triangles).
    pub fn bounds(&self) -> Option<AxisAlignedBox> {
        self.bvh.bounds()
    }

    /// The corners of triangle `prim`.
    #[inline]
    pub fn corners(&self, prim: u32) -> [Vec3; 3] {
        self.corners[prim as usize]
    }

    /// Nearest hit of an object-space ray (direction of any length; `t` in
    /// its units) with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<PrimitiveHit> {
        let w = WatertightRay::new(ray);
        let mut best: Option<(u32, TriangleHit)> = None;
        self.bvh.closest(ray, t_min, t_max, |prim, t_closest| {
            let [a, b, c] = self.corners(prim);
            let h = intersect_triangle(&w, a, b, c, t_min, t_closest)?;
            best = Some((prim, h));
            Some(h.t)
        })?;
        best.map(|(prim, h)| PrimitiveHit { t: h.t, prim, b1: h.b1, b2: h.b2 })
    }

    /// Whether any triangle is hit with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        let w = WatertightRay::new(ray);
        self.bvh.any(ray, t_min, t_max, |prim, t_max| {
            let [a, b, c] = self.corners(prim);
            intersect_triangle(&w, a, b, c, t_min, t_max).is_some()
        })
    }

    /// Number of triangles an object-space ray crosses with `t > 0`.
    fn crossings(&self, ray: &Ray) -> usize {
        let w = WatertightRay::new(ray);
        let mut count = 0;
        // `any` with a visitor that never stops visits every reachable leaf.
        self.bvh.any(ray, 0.0, f32::INFINITY, |prim, _| {
            let [a, b, c] = self.corners(prim);
            count += intersect_triangle(&w, a, b, c, 0.0, f32::INFINITY).is_some() as usize;
            false
        });
        count
    }

    /// Whether object-space point `p` is inside the (closed) mesh: the parity
    /// of crossings along three fixed skew directions, by majority (a ray
    /// through an edge may count a crossing twice).
    pub fn contains(&self, p: Vec3) -> bool {
        const DIRECTIONS: [Vec3; 3] = [
            Vec3::new(0.5773, 0.5774, 0.5775),
            Vec3::new(-0.2673, 0.5345, -0.8018),
            Vec3::new(0.8729, -0.2182, 0.4364),
        ];
        let inside = DIRECTIONS.iter().filter(|&&d| self.crossings(&Ray::new(p, d)) % 2 == 1).count();
        inside >= 2
    }

    /// Enclosed volume (object space) by the divergence theorem; meaningful
    /// for closed meshes.
    pub fn volume(&self) -> f32 {
        let v: f64 = self
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| self.positions[i as usize].as_dvec3());
                a.dot(b.cross(c))
            })
            .sum();
        (v / 6.0).abs() as f32
    }
}

/// `ray` mapped into the object space of `transform` (the direction is not
/// renormalized, so ray parameters are the same in both spaces).
#[inline]
fn ray_to_object(transform: &Transform, ray: &Ray) -> Ray {
    Ray::at_time(transform.to_local.transform_point3(ray.o), transform.to_local.transform_vector3(ray.d), ray.time)
}

/// A mesh placed in the world: shared mesh data and its object-to-world transform.
#[derive(Clone, Debug)]
pub struct MeshInstance {
    /// The mesh (shared between instances).
    pub mesh: Arc<TriangleMesh>,
    /// Object to world.
    pub transform: Transform,
    /// Whether the transform is the identity (rays need no mapping).
    identity: bool,
    /// Whether the mesh encloses a volume (checked closed, or declared so).
    pub closed: bool,
    /// World box.
    world_bounds: AxisAlignedBox,
}

impl MeshInstance {
    /// Places `mesh` by `transform`; `closed` says whether it may bound a medium.
    pub fn new(mesh: Arc<TriangleMesh>, transform: Transform, closed: bool) -> MeshInstance {
        let identity = transform.to_world == Affine3A::IDENTITY;
        let world_bounds = match mesh.bounds() {
            Some(b) => {
                let mut lo = Vec3::splat(f32::INFINITY);
                let mut hi = Vec3::splat(f32::NEG_INFINITY);
                for i in 0..8 {
                    let c = Vec3::new(
                        if i & 1 == 0 { b.min.x } else { b.max.x },
                        if i & 2 == 0 { b.min.y } else { b.max.y },
                        if i & 4 == 0 { b.min.z } else { b.max.z },
                    );
                    let w = transform.point_to_world(c);
                    lo = lo.min(w);
                    hi = hi.max(w);
                }
                AxisAlignedBox { min: lo, max: hi }
            }
            None => AxisAlignedBox { min: Vec3::ZERO, max: Vec3::ZERO },
        };
        MeshInstance { mesh, transform, identity, closed, world_bounds }
    }

    /// The world ray in object space (the direction is not renormalized, so
    /// ray parameters are the same in both spaces).
    #[inline]
    fn to_object(&self, ray: &Ray) -> Ray {
        if self.identity {
            *ray
        } else {
            ray_to_object(&self.transform, ray)
        }
    }

    /// Nearest hit with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn hit(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<PrimitiveHit> {
        self.mesh.intersect(&self.to_object(ray), t_min, t_max)
    }

    /// Whether any triangle is hit with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.mesh.occluded(&self.to_object(ray), t_min, t_max)
    }

    /// [`MeshInstance::hit`] with the mesh placed by `pose` instead of its
    /// own transform (a moving instance at a ray's time).
    #[inline]
    pub fn hit_posed(&self, pose: &Transform, ray: &Ray, t_min: f32, t_max: f32) -> Option<PrimitiveHit> {
        self.mesh.intersect(&ray_to_object(pose, ray), t_min, t_max)
    }

    /// [`MeshInstance::occluded`] with the mesh placed by `pose`.
    #[inline]
    pub fn occluded_posed(&self, pose: &Transform, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        self.mesh.occluded(&ray_to_object(pose, ray), t_min, t_max)
    }

    /// The hit record of `hit` (found by [`MeshInstance::hit`] on `ray`):
    /// the point interpolated on the triangle, the outward geometric normal,
    /// the shading normal interpolated from the vertex normals (turned to the
    /// geometric normal's side unless the mesh keeps its shading normal,
    /// [`TriangleMesh::keeps_backside_ns`]; the geometric one without vertex
    /// normals).
    #[inline]
    pub fn surface_at(&self, ray: &Ray, hit: &PrimitiveHit) -> SurfaceHit {
        let s = self.surface_by(if self.identity { None } else { Some(&self.transform) }, hit);
        self.mark_backside(s, ray)
    }

    /// `s` with [`SurfaceHit::backside_ns`] set where this mesh keeps the
    /// shading normal and `-ray.d` lies on its other side than on `n`'s.
    #[inline]
    fn mark_backside(&self, mut s: SurfaceHit, ray: &Ray) -> SurfaceHit {
        if self.mesh.keeps_backside_ns {
            let wo = -ray.d;
            s.backside_ns = (wo.dot(s.ns) > 0.0) != (wo.dot(s.n) > 0.0);
        }
        s
    }

    /// The point of triangle `prim` at barycentrics `(b1, b2)` (weights of
    /// its second and third corners) with its geometric and shading normals,
    /// as [`MeshInstance::surface_at`] gives them for a hit there (`t` 0,
    /// not marked [`SurfaceHit::backside_ns`]).
    #[inline]
    pub fn surface_point(&self, prim: u32, b1: f32, b2: f32) -> SurfaceHit {
        let hit = PrimitiveHit { t: 0.0, prim, b1, b2 };
        self.surface_by(if self.identity { None } else { Some(&self.transform) }, &hit)
    }

    /// [`MeshInstance::surface_at`] of a hit found by [`MeshInstance::hit_posed`] with `pose`.
    #[inline]
    pub fn surface_at_posed(&self, pose: &Transform, ray: &Ray, hit: &PrimitiveHit) -> SurfaceHit {
        self.mark_backside(self.surface_by(Some(pose), hit), ray)
    }

    /// The hit record with the mesh placed by `pose` (`None`: the identity).
    #[inline]
    fn surface_by(&self, pose: Option<&Transform>, hit: &PrimitiveHit) -> SurfaceHit {
        let mesh = &*self.mesh;
        let tri = mesh.triangles[hit.prim as usize];
        let [a, b, c] = tri.map(|i| mesh.positions[i as usize]);
        let b0 = 1.0 - hit.b1 - hit.b2;
        let p_obj = a * b0 + b * hit.b1 + c * hit.b2;
        let ng_obj = (b - a).cross(c - a);
        let (p, n) = match pose {
            None => (p_obj, ng_obj.normalize()),
            Some(t) => (t.point_to_world(p_obj), t.normal_to_world(ng_obj)),
        };
        let ns = match &mesh.normals {
            Some(normals) => {
                let [na, nb, nc] = tri.map(|i| normals[i as usize]);
                let s = na * b0 + nb * hit.b1 + nc * hit.b2;
                if s.length_squared() > 0.0 {
                    let s = match pose {
                        None => s.normalize(),
                        Some(t) => t.normal_to_world(s),
                    };
                    // Turned to the geometric normal's side, unless the
                    // mesh keeps its normals as written (Mitsuba 3).
                    if s.dot(n) < 0.0 && !mesh.keeps_backside_ns {
                        -s
                    } else {
                        s
                    }
                } else {
                    n
                }
            }
            None => n,
        };
        SurfaceHit { t: hit.t, p, n, ns, backside_ns: false }
    }

    /// Mitsuba 3's `dp/du` (world space, not normalized) at `hit` on this
    /// instance: from the triangle's vertex uvs, `(duv1.v dp0 - duv0.v dp1) /
    /// det` with `dp0 = p1 - p0`, `dp1 = p2 - p0`, `duv0 = uv1 - uv0`, `duv1 =
    /// uv2 - uv0`, `det = duv0.u duv1.v - duv0.v duv1.u`; without uvs the uv
    /// is the barycentric `(b1, b2)`, so `dp/du = p1 - p0` in the file's
    /// corner order (Mitsuba 3.9.1, also with `flip_normals`); where `det` is
    /// 0 the x axis of `coordinate_system(n)` of the world geometric normal
    /// `n` ([`crate::math::Frame::from_z`]; the same axis for `-n`).
    pub fn dpdu(&self, hit: &PrimitiveHit, n: Vec3) -> Vec3 {
        self.dpdu_by(&self.transform, hit, n)
    }

    /// [`MeshInstance::dpdu`] with the mesh placed by `pose`.
    pub fn dpdu_by(&self, pose: &Transform, hit: &PrimitiveHit, n: Vec3) -> Vec3 {
        let mesh = &*self.mesh;
        let fallback = || crate::math::Frame::from_z(n).x;
        let tri = mesh.triangles[hit.prim as usize];
        let [p0, p1, p2] = tri.map(|i| mesh.positions[i as usize]);
        let Some(uvs) = &mesh.uvs else {
            let edge = if mesh.winding_flipped { p2 - p0 } else { p1 - p0 };
            return pose.vector_to_world(edge);
        };
        let [uv0, uv1, uv2] = tri.map(|i| uvs[i as usize]);
        let (dp0, dp1) = (p1 - p0, p2 - p0);
        let (duv0, duv1) = (uv1 - uv0, uv2 - uv0);
        let det = duv0.x * duv1.y - duv0.y * duv1.x;
        if det == 0.0 || !det.is_finite() {
            return fallback();
        }
        pose.vector_to_world((dp0 * duv1.y - dp1 * duv0.y) / det)
    }

    /// World box.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        (self.world_bounds.min, self.world_bounds.max)
    }

    /// Whether world point `p` is inside (false unless closed).
    pub fn contains(&self, p: Vec3) -> bool {
        self.closed && self.mesh.contains(self.transform.to_local.transform_point3(p))
    }

    /// Enclosed world volume (0 unless closed).
    pub fn volume(&self) -> f32 {
        if !self.closed {
            return 0.0;
        }
        self.mesh.volume() * self.transform.to_world.matrix3.determinant().abs()
    }
}
