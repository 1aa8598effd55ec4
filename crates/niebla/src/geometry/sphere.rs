use super::SurfaceHit;
use crate::math::{Ray, Vec3};

/// A sphere given by its center and radius (world space).
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Center.
    pub center: Vec3,
    /// Radius (> 0).
    pub radius: f32,
}

impl Sphere {
    /// Nearest intersection in `(t_min, t_max)`; the normal points outward.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        let t = self.hit_t(ray, t_min, t_max)?;
        Some(self.surface_at(ray, t))
    }

    /// Parameter of the nearest intersection in `(t_min, t_max)`.
    #[inline]
    pub fn hit_t(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        // Numerically robust quadratic (pbrt-v4 section 6.8.1 idea: compute the
        // discriminant from the closest-approach vector).
        let oc = ray.o - self.center;
        let b = oc.dot(ray.d);
        let closest = oc - b * ray.d;
        let disc = self.radius * self.radius - closest.length_squared();
        if disc < 0.0 {
            return None;
        }
        let root = disc.sqrt();
        let q = if b > 0.0 { -b - root } else { -b + root };
        let (mut t0, mut t1) = (q, if q != 0.0 { (oc.length_squared() - self.radius * self.radius) / q } else { q });
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        if t0 > t_min && t0 < t_max {
            Some(t0)
        } else if t1 > t_min && t1 < t_max {
            Some(t1)
        } else {
            None
        }
    }

    /// The hit record at parameter `t` of an intersection found by [`Sphere::hit_t`].
    #[inline]
    pub fn surface_at(&self, ray: &Ray, t: f32) -> SurfaceHit {
        let p = ray.at(t);
        let n = (p - self.center) / self.radius;
        let n = n.normalize();
        SurfaceHit { t, p, n, ns: n, backside_ns: false }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_hits_front_then_back() {
        let s = Sphere { center: Vec3::new(0.0, 0.0, 5.0), radius: 1.0 };
        let r = Ray::new(Vec3::ZERO, Vec3::Z);
        let h = s.intersect(&r, 0.0, f32::INFINITY).unwrap();
        assert!((h.t - 4.0).abs() < 1e-5);
        assert!((h.n - (-Vec3::Z)).length() < 1e-5);
        let h2 = s.intersect(&r, h.t + 1e-3, f32::INFINITY).unwrap();
        assert!((h2.t - 6.0).abs() < 1e-5);
        assert!(s.intersect(&r, 0.0, 3.9).is_none());
        let miss = Ray::new(Vec3::new(1.01, 0.0, 0.0), Vec3::Z);
        assert!(s.intersect(&miss, 0.0, f32::INFINITY).is_none());
    }
}
