use super::SurfaceHit;
use crate::math::{Ray, Vec2, Vec3, INV_PI, PI};
use glam::Mat3;

/// A sphere given by its center and radius (world space), with an optional
/// orientation that turns its uv parameterization (and so `dp/du`) but not
/// its surface: Mitsuba 3 keeps the rotation of a sphere's `to_world`.
#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    /// Center.
    pub center: Vec3,
    /// Radius (> 0).
    pub radius: f32,
    /// Rotation from the sphere's local frame to world space (orthonormal,
    /// determinant +1): local `+z` is the uv pole, local `+x` the seam `u =
    /// 0`. `None`: the identity (the local frame is the world's).
    pub rotation: Option<Mat3>,
}

impl Sphere {
    /// An unturned sphere (uv pole along world `+z`).
    #[inline]
    pub const fn new(center: Vec3, radius: f32) -> Sphere {
        Sphere { center, radius, rotation: None }
    }

    /// The same sphere with its uv frame turned by `rotation` (local to
    /// world; see [`Sphere::rotation`]).
    #[inline]
    pub fn with_rotation(self, rotation: Option<Mat3>) -> Sphere {
        Sphere { rotation, ..self }
    }

    /// The hit point `p` (world space, on the surface) relative to the
    /// center, in the sphere's local frame (scene units).
    #[inline]
    fn local(&self, p: Vec3) -> Vec3 {
        let q = p - self.center;
        match &self.rotation {
            None => q,
            Some(r) => r.transpose() * q,
        }
    }

    /// Texture coordinates of a point `p` on the sphere (Mitsuba 3's): `u`
    /// the azimuth about the local `z` axis from local `+x` over `2 pi`, in
    /// `[0, 1)`; `v` the polar angle from local `+z` over `pi`.
    #[inline]
    pub fn uv(&self, p: Vec3) -> Vec2 {
        let n = self.local(p) / self.radius;
        let u = n.y.atan2(n.x).rem_euclid(2.0 * PI) * (0.5 * INV_PI);
        Vec2::new(u, n.z.clamp(-1.0, 1.0).acos() * INV_PI)
    }

    /// Mitsuba 3's `dp/du` at a point `p` on the sphere (world space, not
    /// normalized): `2 pi R (-q.y, q.x, 0)` with `q` the local offset from
    /// the center and `R` the rotation (zero at the poles).
    #[inline]
    pub fn dpdu(&self, p: Vec3) -> Vec3 {
        let q = self.local(p);
        let t = Vec3::new(-q.y, q.x, 0.0) * (2.0 * PI);
        match &self.rotation {
            None => t,
            Some(r) => *r * t,
        }
    }

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
        let s = Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0);
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

    /// A rotation turns the uv frame and nothing else: the same hits and
    /// normals, and at a point `p` the uv (and the turned dp/du) the
    /// unturned sphere has at `c + R^T (p - c)`; the identity and no
    /// rotation agree to the bit.
    #[test]
    fn rotation_turns_uv_and_dpdu_only() {
        let c = Vec3::new(0.3, -0.2, 0.5);
        let r = Mat3::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
        let plain = Sphere::new(c, 1.5);
        let turned = plain.with_rotation(Some(r));
        let same = plain.with_rotation(Some(Mat3::IDENTITY));
        for d in [Vec3::new(0.2, 0.3, -1.0), Vec3::new(-1.0, 0.1, 0.05), Vec3::new(0.3, -1.0, 0.4)] {
            let ray = Ray::new(c - d.normalize() * 4.0 + Vec3::new(0.1, 0.2, -0.1), d.normalize());
            let (a, b) = (plain.intersect(&ray, 0.0, 10.0).unwrap(), turned.intersect(&ray, 0.0, 10.0).unwrap());
            assert_eq!((a.t, a.p, a.n), (b.t, b.p, b.n));
            let back = c + r.transpose() * (b.p - c);
            assert!((turned.uv(b.p) - plain.uv(back)).length() < 1e-6);
            assert!((turned.dpdu(b.p) - r * plain.dpdu(back)).length() < 1e-5);
            assert_eq!((same.uv(a.p), same.dpdu(a.p)), (plain.uv(a.p), plain.dpdu(a.p)));
        }
    }
}
