use super::{SurfaceHit, Transform};
use crate::math::{Ray, Vec3};

/// The unit square `[-1, 1]^2` in the local xy plane with normal +z (Mitsuba's
/// convention), placed by an affine `to_world` transform.
#[derive(Clone, Copy, Debug)]
pub struct Rectangle {
    /// Local-to-world placement.
    pub transform: Transform,
    /// World-space unit normal (local +z).
    pub normal: Vec3,
}

impl Rectangle {
    /// A rectangle placed by `transform`.
    pub fn new(transform: Transform) -> Rectangle {
        Rectangle { transform, normal: transform.normal_to_world(Vec3::Z) }
    }

    /// Nearest intersection in `(t_min, t_max)`; the normal is local +z in world space.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        let t = self.hit_t(ray, t_min, t_max)?;
        Some(self.surface_at(ray, t))
    }

    /// Parameter of the intersection if it lies in `(t_min, t_max)`.
    #[inline]
    pub fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let (t, q) = self.transform.local_plane_crossing(ray, t_min, t_max)?;
        if q.x.abs() > 1.0 || q.y.abs() > 1.0 {
            return None;
        }
        Some(t)
    }

    /// The hit record at parameter `t` of an intersection found by [`Rectangle::hit_t`].
    #[inline]
    pub fn surface_at(&self, ray: &Ray, t: f32) -> SurfaceHit {
        SurfaceHit { t, p: ray.at(t), n: self.normal, ns: self.normal, backside_ns: false }
    }

    /// World-space bounding box.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
            let p = self.transform.point_to_world(Vec3::new(x, y, 0.0));
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo, hi)
    }

    /// World-space area.
    pub fn area(&self) -> f32 {
        let ex = self.transform.vector_to_world(Vec3::X);
        let ey = self.transform.vector_to_world(Vec3::Y);
        4.0 * ex.cross(ey).length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotated_floor_rectangle_faces_up() {
        let t = Transform::from_components(Vec3::splat(10.0), Vec3::new(-90.0, 0.0, 0.0), Vec3::ZERO).unwrap();
        let r = Rectangle::new(t);
        assert!((r.normal - Vec3::Y).length() < 1e-5);
        let ray = Ray::new(Vec3::new(3.0, 2.0, 4.0), -Vec3::Y);
        let h = r.intersect(&ray, 0.0, f32::INFINITY).unwrap();
        assert!((h.t - 2.0).abs() < 1e-5);
        assert!((r.area() - 400.0).abs() < 1e-2);
        let outside = Ray::new(Vec3::new(11.0, 2.0, 0.0), -Vec3::Y);
        assert!(r.intersect(&outside, 0.0, f32::INFINITY).is_none());
    }
}
