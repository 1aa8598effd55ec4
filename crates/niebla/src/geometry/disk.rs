use super::{SurfaceHit, Transform};
use crate::math::{Ray, Vec2, Vec3, PI};

/// The unit disk `x^2 + y^2 <= 1` in the local xy plane at `z = 0` with
/// normal +z (Mitsuba 3's `disk`), placed by an affine `to_world` transform
/// (a non-uniform scale makes it an ellipse).
#[derive(Clone, Copy, Debug)]
pub struct Disk {
    /// Local-to-world placement.
    pub transform: Transform,
    /// World-space unit normal (local +z).
    pub normal: Vec3,
}

impl Disk {
    /// A disk placed by `transform`.
    pub fn new(transform: Transform) -> Disk {
        Disk { transform, normal: transform.normal_to_world(Vec3::Z) }
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
        if q.x * q.x + q.y * q.y > 1.0 {
            return None;
        }
        Some(t)
    }

    /// The hit record at parameter `t` of an intersection found by [`Disk::hit_t`].
    #[inline]
    pub fn surface_at(&self, ray: &Ray, t: f32) -> SurfaceHit {
        SurfaceHit { t, p: ray.at(t), n: self.normal, ns: self.normal, backside_ns: false }
    }

    /// World-space bounding box (exact for the ellipse: per axis, the
    /// half-extent is the length of the row of the two in-plane axes).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let c = self.transform.point_to_world(Vec3::ZERO);
        let ex = self.transform.vector_to_world(Vec3::X);
        let ey = self.transform.vector_to_world(Vec3::Y);
        let half = Vec3::new(ex.x.hypot(ey.x), ex.y.hypot(ey.y), ex.z.hypot(ey.z));
        (c - half, c + half)
    }

    /// World-space area, `pi |e_x x e_y|`.
    pub fn area(&self) -> f32 {
        let ex = self.transform.vector_to_world(Vec3::X);
        let ey = self.transform.vector_to_world(Vec3::Y);
        PI * ex.cross(ey).length()
    }

    /// A point uniformly distributed by area for `u` in [0, 1)^2 (the
    /// concentric map of the square onto the unit disk, then the affine
    /// placement, which keeps uniform points uniform).
    #[inline]
    pub fn sample_point(&self, u: Vec2) -> Vec3 {
        let p = crate::sampling::sample_uniform_disk_concentric(u);
        self.transform.point_to_world(Vec3::new(p.x, p.y, 0.0))
    }

    /// Mitsuba's texture coordinates of a world point on the disk: the
    /// local radius and the azimuth over `2 pi` in [0, 1).
    pub fn uv(&self, p: Vec3) -> Vec2 {
        let q = self.transform.to_local.transform_point3(p);
        let v = q.y.atan2(q.x) * (0.5 / PI);
        Vec2::new(q.x.hypot(q.y), if v < 0.0 { v + 1.0 } else { v })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaled_disk_hits_inside_the_circle_only() {
        // Radius 2 at z = 1, facing +z.
        let t = Transform::from_components(Vec3::splat(2.0), Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0)).unwrap();
        let d = Disk::new(t);
        assert!((d.normal - Vec3::Z).length() < 1e-6);
        assert!((d.area() - 4.0 * PI).abs() < 1e-4);
        let hit = d.intersect(&Ray::new(Vec3::new(1.9, 0.0, 5.0), -Vec3::Z), 0.0, f32::INFINITY).unwrap();
        assert!((hit.t - 4.0).abs() < 1e-5);
        // (1.5, 1.5) is inside the bounding square, outside the circle.
        assert!(d.intersect(&Ray::new(Vec3::new(1.5, 1.5, 5.0), -Vec3::Z), 0.0, f32::INFINITY).is_none());
        let (lo, hi) = d.bounds();
        assert!((lo - Vec3::new(-2.0, -2.0, 1.0)).length() < 1e-5 && (hi - Vec3::new(2.0, 2.0, 1.0)).length() < 1e-5);
    }

    #[test]
    fn tilted_disk_bounds_contain_its_samples_and_are_tight() {
        let t = Transform::from_components(Vec3::new(1.0, 3.0, 1.0), Vec3::new(30.0, 50.0, 10.0), Vec3::ONE).unwrap();
        let d = Disk::new(t);
        let (lo, hi) = d.bounds();
        let (mut slo, mut shi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for i in 0..64 {
            for j in 0..64 {
                let p = d.sample_point(Vec2::new((i as f32 + 0.5) / 64.0, (j as f32 + 0.5) / 64.0));
                assert!(p.cmpge(lo - 1e-5).all() && p.cmple(hi + 1e-5).all());
                assert!(d.transform.to_local.transform_point3(p).z.abs() < 1e-5);
                slo = slo.min(p);
                shi = shi.max(p);
            }
        }
        // The samples reach within 2% of the box's extent on every axis.
        assert!(((shi - slo) - (hi - lo)).abs().max_element() < 0.02 * (hi - lo).max_element());
    }
}
