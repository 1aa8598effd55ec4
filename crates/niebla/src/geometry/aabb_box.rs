use super::SurfaceHit;
use crate::math::{Ray, Vec3};

/// An axis-aligned box `[min, max]` (world space).
#[derive(Clone, Copy, Debug)]
pub struct AxisAlignedBox {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner (each component greater than `min`'s).
    pub max: Vec3,
}

impl AxisAlignedBox {
    /// Parametric range `(t_near, t_far)` where the ray's line is inside the box
    /// (slab test); `t_near > t_far` when it misses.
    #[inline]
    pub fn slab_range(&self, ray: &Ray) -> (f32, f32) {
        self.slab_range_inv(ray, ray.d.recip())
    }

    /// [`AxisAlignedBox::slab_range`] with the direction's reciprocal given.
    #[inline]
    pub fn slab_range_inv(&self, ray: &Ray, inv: Vec3) -> (f32, f32) {
        let t_lo = (self.min - ray.o) * inv;
        let t_hi = (self.max - ray.o) * inv;
        // NaN (0 * inf) from a ray in a face plane: treat the axis as unbounded.
        let near = t_lo.min(t_hi);
        let far = t_lo.max(t_hi);
        let pick = |v: f32, fallback: f32| if v.is_nan() { fallback } else { v };
        let t_near =
            pick(near.x, f32::NEG_INFINITY).max(pick(near.y, f32::NEG_INFINITY)).max(pick(near.z, f32::NEG_INFINITY));
        let t_far = pick(far.x, f32::INFINITY).min(pick(far.y, f32::INFINITY)).min(pick(far.z, f32::INFINITY));
        (t_near, t_far)
    }

    /// Nearest intersection in `(t_min, t_max)`; the normal is the outward face normal.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        let t = self.hit_t(ray, ray.d.recip(), t_min, t_max)?;
        Some(self.surface_at(ray, t))
    }

    /// Parameter of the nearest intersection in `(t_min, t_max)`, given the
    /// reciprocal `inv` of the ray's direction.
    #[inline]
    pub fn hit_t(&self, ray: &Ray, inv: Vec3, t_min: f32, t_max: f32) -> Option<f32> {
        let (t_near, t_far) = self.slab_range_inv(ray, inv);
        if t_near > t_far {
            return None;
        }
        if t_near > t_min && t_near < t_max {
            Some(t_near)
        } else if t_far > t_min && t_far < t_max {
            Some(t_far)
        } else {
            None
        }
    }

    /// The hit record at parameter `t` of an intersection found by [`AxisAlignedBox::hit_t`].
    #[inline]
    pub fn surface_at(&self, ray: &Ray, t: f32) -> SurfaceHit {
        let p = ray.at(t);
        let n = self.face_normal(p);
        SurfaceHit { t, p, n, ns: n, backside_ns: false }
    }

    /// Outward normal of the face nearest to `p`.
    fn face_normal(&self, p: Vec3) -> Vec3 {
        let size = (self.max - self.min).max(Vec3::splat(1e-30));
        let d_lo = (p - self.min) / size;
        let d_hi = (self.max - p) / size;
        let mut best = (d_lo.x.abs(), -Vec3::X);
        for (d, n) in [
            (d_hi.x.abs(), Vec3::X),
            (d_lo.y.abs(), -Vec3::Y),
            (d_hi.y.abs(), Vec3::Y),
            (d_lo.z.abs(), -Vec3::Z),
            (d_hi.z.abs(), Vec3::Z),
        ] {
            if d < best.0 {
                best = (d, n);
            }
        }
        best.1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_entry_exit_and_normals() {
        let b = AxisAlignedBox { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
        let r = Ray::new(Vec3::new(0.2, 0.1, -5.0), Vec3::Z);
        let h = b.intersect(&r, 0.0, f32::INFINITY).unwrap();
        assert!((h.t - 4.0).abs() < 1e-5);
        assert_eq!(h.n, -Vec3::Z);
        let h2 = b.intersect(&r, h.t + 1e-4, f32::INFINITY).unwrap();
        assert!((h2.t - 6.0).abs() < 1e-5);
        assert_eq!(h2.n, Vec3::Z);
        // A ray exactly in a face plane, parallel to it, must not produce NaN.
        let grazing = Ray::new(Vec3::new(-5.0, 1.0, 0.0), Vec3::X);
        if let Some(h) = b.intersect(&grazing, 0.0, f32::INFINITY) {
            assert!(h.t.is_finite());
        }
    }
}
