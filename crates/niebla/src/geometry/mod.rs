//! Shapes and ray intersection.
//!
//! Shapes are a closed set (`Shape` enum) so intersection is a `match`, not a
//! virtual call. Normals returned by intersections are geometric and point
//! outward (for the rectangle: along its local +z).

mod aabb_box;
mod rectangle;
mod sphere;
mod transform;

pub use aabb_box::AxisAlignedBox;
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
}

impl Shape {
    /// Nearest intersection with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        match self {
            Shape::Sphere(s) => s.intersect(ray, t_min, t_max),
            Shape::Box(b) => b.intersect(ray, t_min, t_max),
            Shape::Rectangle(r) => r.intersect(ray, t_min, t_max),
        }
    }

    /// Parameter of the nearest intersection with `t` in `(t_min, t_max)`,
    /// without the hit record (see [`Shape::surface_at`]); `inv` is the
    /// reciprocal of the ray's direction.
    #[inline]
    pub fn hit_t(&self, ray: &Ray, inv: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        match self {
            Shape::Sphere(s) => s.hit_t(ray, t_min, t_max),
            Shape::Box(b) => b.hit_t(ray, inv, t_min, t_max),
            Shape::Rectangle(r) => r.hit_t(ray, t_min, t_max),
        }
    }

    /// The hit record of an intersection at `t` found by [`Shape::hit_t`]
    /// (the same record [`Shape::intersect`] returns).
    #[inline]
    pub fn surface_at(&self, ray: &Ray, t: f32) -> SurfaceHit {
        match self {
            Shape::Sphere(s) => s.surface_at(ray, t),
            Shape::Box(b) => b.surface_at(ray, t),
            Shape::Rectangle(r) => r.surface_at(ray, t),
        }
    }

    /// True for shapes that enclose a volume (and so can hold a medium).
    pub fn is_closed(&self) -> bool {
        !matches!(self, Shape::Rectangle(_))
    }

    /// True when `p` lies strictly inside a closed shape (false for open shapes).
    pub fn contains(&self, p: Vec3) -> bool {
        match self {
            Shape::Sphere(s) => (p - s.center).length_squared() < s.radius * s.radius,
            Shape::Box(b) => p.cmpgt(b.min).all() && p.cmplt(b.max).all(),
            Shape::Rectangle(_) => false,
        }
    }

    /// Enclosed volume (0 for open shapes), used to find the innermost container.
    pub fn volume(&self) -> f32 {
        match self {
            Shape::Sphere(s) => 4.0 / 3.0 * crate::math::PI * s.radius.powi(3),
            Shape::Box(b) => (b.max - b.min).element_product(),
            Shape::Rectangle(_) => 0.0,
        }
    }

    /// World-space bounding box `(min, max)`.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        match self {
            Shape::Sphere(s) => (s.center - Vec3::splat(s.radius), s.center + Vec3::splat(s.radius)),
            Shape::Box(b) => (b.min, b.max),
            Shape::Rectangle(r) => r.bounds(),
        }
    }
}
