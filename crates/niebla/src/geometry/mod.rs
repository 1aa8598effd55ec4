//! Shapes and ray intersection.
//!
//! Shapes are a closed set (`Shape` enum) so intersection is a `match`, not a
//! virtual call. Normals returned by intersections are geometric and point
//! outward (for the rectangle and the disk: along their local +z; for a mesh: by the
//! right-hand rule of its counter-clockwise winding). Meshes carry their own
//! hierarchy ([`bvh`]) and are intersected watertight ([`triangle`]).

mod aabb_box;
pub mod bvh;
mod disk;
pub mod mesh;
mod motion;
mod rectangle;
mod sphere;
mod transform;
pub mod triangle;

pub use aabb_box::AxisAlignedBox;
pub use bvh::Bvh;
pub use disk::Disk;
pub use mesh::{MeshDataError, MeshInstance, TriangleMesh};
pub use motion::{box_at, sphere_at, Motion, MotionError, MovingShape, Pose, TransformMotion};
pub use rectangle::Rectangle;
pub use sphere::Sphere;
pub use transform::Transform;

use crate::math::{Ray, Vec3};

/// A ray-surface intersection in world space.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    /// Distance along the ray.
    pub t: f32,
    /// Hit point.
    pub p: Vec3,
    /// Unit outward geometric normal.
    pub n: Vec3,
    /// Unit shading normal: interpolated vertex normals of a smooth mesh,
    /// on the geometric normal's side (as written on a mesh that keeps its
    /// normals, [`TriangleMesh::keeps_backside_ns`]); `n` itself for every
    /// other shape.
    pub ns: Vec3,
    /// True where the mesh keeps its shading normal for a `wo` (the hit's
    /// `-ray.d`) on the other side of `ns` than of `n` (Mitsuba 3's rule,
    /// a mesh's `"shading_normal_backside": "mitsuba"`): the BSDF is then
    /// evaluated about `ns` with `wo` behind it, and one-sided BSDFs give
    /// zero ([`crate::world::Scene::surface_bsdf`]). False for every other
    /// hit.
    pub backside_ns: bool,
}

impl SurfaceHit {
    /// The normal a BSDF at this hit is evaluated about, seen from unit
    /// `wo` (pointing away from the surface): the shading normal, unless
    /// `wo` lies on its other side than on the geometric normal's, where a
    /// smooth normal would shade a face seen from behind and the geometric
    /// normal is used instead, unless the hit keeps `ns`
    /// ([`SurfaceHit::backside_ns`], Mitsuba 3's rule).
    #[inline]
    pub fn shading_normal(&self, wo: Vec3) -> Vec3 {
        if (wo.dot(self.ns) > 0.0) == (wo.dot(self.n) > 0.0) || self.backside_ns {
            self.ns
        } else {
            self.n
        }
    }

    /// Whether unit direction `w` lies on the same side of the shading
    /// normal `ns_used` as of the geometric normal: a direction for which
    /// they disagree is refused by the BSDF, so that smooth shading never
    /// lets light pass through a surface that geometry says is closed
    /// (light leaks; the remedy of Veach 1997, section 5.3, and Mitsuba 3).
    #[inline]
    pub fn sides_agree(&self, ns_used: Vec3, w: Vec3) -> bool {
        (w.dot(ns_used) > 0.0) == (w.dot(self.n) > 0.0)
    }
}

/// The nearest hit of a ray on one shape, before its hit record is made:
/// the ray parameter, and for meshes the triangle and its barycentric
/// weights of the second and third vertex (zero for other shapes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimitiveHit {
    /// Ray parameter.
    pub t: f32,
    /// Triangle index (meshes) or 0.
    pub prim: u32,
    /// Barycentric weight of the triangle's second vertex.
    pub b1: f32,
    /// Barycentric weight of the triangle's third vertex.
    pub b2: f32,
}

impl PrimitiveHit {
    /// A hit at `t` on a shape without primitives.
    #[inline]
    pub fn at(t: f32) -> PrimitiveHit {
        PrimitiveHit { t, prim: 0, b1: 0.0, b2: 0.0 }
    }
}

/// A closed set of shapes (world space).
#[derive(Clone, Debug)]
pub enum Shape {
    /// A sphere.
    Sphere(Sphere),
    /// An axis-aligned box.
    Box(AxisAlignedBox),
    /// A parallelogram (transformed unit square).
    Rectangle(Rectangle),
    /// An ellipse (transformed unit disk).
    Disk(Disk),
    /// A triangle mesh placed by a transform.
    Mesh(MeshInstance),
    /// One of the above moving during the shutter: intersected in its pose
    /// at the ray's [`Ray::time`].
    Moving(Box<MovingShape>),
}

impl Shape {
    /// Nearest intersection with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        match self {
            Shape::Sphere(s) => s.intersect(ray, t_min, t_max),
            Shape::Box(b) => b.intersect(ray, t_min, t_max),
            Shape::Rectangle(r) => r.intersect(ray, t_min, t_max),
            Shape::Disk(d) => d.intersect(ray, t_min, t_max),
            Shape::Mesh(m) => m.hit(ray, t_min, t_max).map(|h| m.surface_at(ray, &h)),
            Shape::Moving(m) => m.hit_t(ray, ray.d.recip(), t_min, t_max).map(|h| m.surface_at(ray, &h)),
        }
    }

    /// The nearest intersection with `t` in `(t_min, t_max)`, without the
    /// hit record (see [`Shape::surface_at`]); `inv` is the reciprocal of
    /// the ray's direction.
    #[inline]
    pub fn hit_t(&self, ray: &Ray, inv: Vec3, t_min: f32, t_max: f32) -> Option<PrimitiveHit> {
        match self {
            Shape::Sphere(s) => s.hit_t(ray, t_min, t_max).map(PrimitiveHit::at),
            Shape::Box(b) => b.hit_t(ray, inv, t_min, t_max).map(PrimitiveHit::at),
            Shape::Rectangle(r) => r.hit_t(ray, t_min, t_max).map(PrimitiveHit::at),
            Shape::Disk(d) => d.hit_t(ray, t_min, t_max).map(PrimitiveHit::at),
            Shape::Mesh(m) => m.hit(ray, t_min, t_max),
            Shape::Moving(m) => m.hit_t(ray, inv, t_min, t_max),
        }
    }

    /// Whether the shape is hit anywhere with `t` in `(t_min, t_max)` (for
    /// meshes an any-hit query that stops at the first triangle found).
    #[inline]
    pub fn occludes(&self, ray: &Ray, inv: Vec3, t_min: f32, t_max: f32) -> bool {
        match self {
            Shape::Mesh(m) => m.occluded(ray, t_min, t_max),
            Shape::Moving(m) => m.occludes(ray, inv, t_min, t_max),
            _ => self.hit_t(ray, inv, t_min, t_max).is_some(),
        }
    }

    /// The hit record of an intersection found by [`Shape::hit_t`] (the same
    /// record [`Shape::intersect`] returns).
    #[inline]
    pub fn surface_at(&self, ray: &Ray, hit: &PrimitiveHit) -> SurfaceHit {
        match self {
            Shape::Sphere(s) => s.surface_at(ray, hit.t),
            Shape::Box(b) => b.surface_at(ray, hit.t),
            Shape::Rectangle(r) => r.surface_at(ray, hit.t),
            Shape::Disk(d) => d.surface_at(ray, hit.t),
            Shape::Mesh(m) => m.surface_at(ray, hit),
            Shape::Moving(m) => m.surface_at(ray, hit),
        }
    }

    /// Texture coordinates of a hit found on this shape (the conventions of
    /// [`crate::texture`]): interpolated vertex uvs on meshes (else the
    /// barycentric `(b1, b2)`), azimuth and polar angle on spheres
    /// (about their [`Sphere::rotation`]), the
    /// local square on rectangles, the face's coordinates on boxes; a moving
    /// shape's in its pose at `time`, the time of the ray that found the hit.
    pub fn uv(&self, surface: &SurfaceHit, local: &PrimitiveHit, time: f32) -> crate::math::Vec2 {
        use crate::math::Vec2;
        match self {
            Shape::Sphere(s) => s.uv(surface.p),
            Shape::Rectangle(r) => {
                let q = r.transform.to_local.transform_point3(surface.p);
                Vec2::new(0.5 * (q.x + 1.0), 0.5 * (q.y + 1.0))
            }
            Shape::Disk(d) => d.uv(surface.p),
            Shape::Box(b) => {
                let f = (surface.p - b.min) / (b.max - b.min);
                let n = surface.n;
                if n.x != 0.0 {
                    Vec2::new(f.z, f.y)
                } else if n.y != 0.0 {
                    Vec2::new(f.x, f.z)
                } else {
                    Vec2::new(f.x, f.y)
                }
            }
            Shape::Mesh(m) => m.mesh.uv_at(local.prim, local.b1, local.b2),
            Shape::Moving(m) => m.uv(surface, local, time),
        }
    }

    /// Mitsuba 3's `dp/du` at a hit found on this shape (world space, not
    /// normalized; see [`Shape::uv`] for each shape's `u`): the tangent of
    /// anisotropic roughness with `"tangent_frame": "dpdu"`. Sphere: see
    /// [`Sphere::dpdu`] (zero at the poles); rectangle:
    /// twice the placement's local x axis; disk: the placement of the local
    /// radial direction `(cos phi, sin phi, 0)` (`(1, 0, 0)` at the
    /// center); box: the axis its face's `u` runs along, times the box's
    /// extent on it; mesh: from the triangle's uvs, else its edge `p1 -
    /// p0` (see [`MeshInstance::dpdu`]); a moving shape's
    /// in its pose at `time`.
    pub fn dpdu(&self, surface: &SurfaceHit, local: &PrimitiveHit, time: f32) -> Vec3 {
        match self {
            Shape::Sphere(s) => s.dpdu(surface.p),
            Shape::Rectangle(r) => r.transform.vector_to_world(Vec3::X) * 2.0,
            Shape::Disk(d) => {
                let q = d.transform.to_local.transform_point3(surface.p);
                let r = q.x.hypot(q.y);
                let (c, s) = if r > 0.0 { (q.x / r, q.y / r) } else { (1.0, 0.0) };
                d.transform.vector_to_world(Vec3::new(c, s, 0.0))
            }
            Shape::Box(b) => {
                let e = b.max - b.min;
                if surface.n.x != 0.0 {
                    Vec3::new(0.0, 0.0, e.z)
                } else {
                    Vec3::new(e.x, 0.0, 0.0)
                }
            }
            Shape::Mesh(m) => m.dpdu(local, surface.n),
            Shape::Moving(m) => m.dpdu(surface, local, time),
        }
    }

    /// True for shapes that enclose a volume (and so can hold a medium).
    pub fn is_closed(&self) -> bool {
        match self {
            Shape::Rectangle(_) | Shape::Disk(_) => false,
            Shape::Mesh(m) => m.closed,
            Shape::Moving(m) => m.at_zero.is_closed(),
            _ => true,
        }
    }

    /// True when a ray that crossed the shape's surface at a point with
    /// outward normal `n`, going on along `d`, cannot meet the surface
    /// again: a convex closed shape left outward (`d . n > 0`), or a flat
    /// one. Meshes answer `false`.
    #[inline]
    pub fn is_left_for_good(&self, n: Vec3, d: Vec3) -> bool {
        match self {
            Shape::Sphere(_) | Shape::Box(_) => d.dot(n) > 0.0,
            Shape::Rectangle(_) | Shape::Disk(_) => true,
            // A mesh may be re-entered; a moving shape never bounds a medium.
            Shape::Mesh(_) | Shape::Moving(_) => false,
        }
    }

    /// True for a mesh that keeps its shading normal everywhere (Mitsuba
    /// 3's rule, [`TriangleMesh::keeps_backside_ns`]): a path leaves its
    /// hits along any direction its BSDF samples about the shading normal,
    /// also one that crosses the triangle's plane against the sampled lobe
    /// (a reflection that leaves the geometric side, a transmission that
    /// stays on it), and the medium it then travels in is the one on the
    /// direction's geometric side. False for every other shape.
    #[inline]
    pub fn keeps_shading_normal(&self) -> bool {
        match self {
            Shape::Mesh(m) => m.mesh.keeps_backside_ns,
            Shape::Moving(m) => m.at_zero.keeps_shading_normal(),
            Shape::Sphere(_) | Shape::Box(_) | Shape::Rectangle(_) | Shape::Disk(_) => false,
        }
    }

    /// True when `p` lies strictly inside a closed shape (false for open
    /// shapes); a moving shape in its pose at time 0.
    pub fn contains(&self, p: Vec3) -> bool {
        match self {
            Shape::Sphere(s) => (p - s.center).length_squared() < s.radius * s.radius,
            Shape::Box(b) => p.cmpgt(b.min).all() && p.cmplt(b.max).all(),
            Shape::Rectangle(_) | Shape::Disk(_) => false,
            Shape::Mesh(m) => m.contains(p),
            Shape::Moving(m) => m.at_zero.contains(p),
        }
    }

    /// Enclosed volume (0 for open shapes), used to find the innermost
    /// container; a moving shape's at time 0.
    pub fn volume(&self) -> f32 {
        match self {
            Shape::Sphere(s) => 4.0 / 3.0 * crate::math::PI * s.radius.powi(3),
            Shape::Box(b) => (b.max - b.min).element_product(),
            Shape::Rectangle(_) | Shape::Disk(_) => 0.0,
            Shape::Mesh(m) => m.volume(),
            Shape::Moving(m) => m.at_zero.volume(),
        }
    }

    /// World-space bounding box `(min, max)`; a moving shape's holds all it
    /// sweeps while the shutter is open.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            Shape::Sphere(s) => (s.center - Vec3::splat(s.radius), s.center + Vec3::splat(s.radius)),
            Shape::Box(b) => (b.min, b.max),
            Shape::Rectangle(r) => r.bounds(),
            Shape::Disk(d) => d.bounds(),
            Shape::Mesh(m) => m.bounds(),
            Shape::Moving(m) => m.bounds(),
        }
    }
}
