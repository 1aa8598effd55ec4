//! The emitting surface of a mesh area light: a placed triangle mesh with a
//! discrete distribution over its triangles by world-space area, so that a
//! point is drawn uniformly by area over the whole mesh (pbrt-v4 section
//! 6.5.4 triangle sampling; Mitsuba 3's `Mesh::sample_position`).
//!
//! Normal convention. The emitting side of a point is that of the mesh's
//! shading normal there (the interpolated vertex normal when the mesh has
//! vertex normals, else the geometric normal `(p1 - p0) x (p2 - p0)`;
//! `flip_normals` negates both), as Mitsuba 3 decides it, for light sampling
//! and for a ray that hits the mesh alike. The power a surface element
//! `dA` sends into `dw` is `L |cos theta_g| dA dw` with the *geometric*
//! normal (the projected area of the triangle, whatever its vertex normals
//! say), so the area-to-solid-angle conversion of light sampling uses the
//! geometric normal's cosine: a point sampled by area and a ray that finds
//! the same point by hitting it then estimate the same integral, the
//! radiance `L` over the directions that see the emitting side.
//! (Mitsuba 3.9 puts the shading normal's cosine in its emitter-sampling
//! density instead, which its hits do not share.)

use crate::geometry::{MeshInstance, SurfaceHit};
use crate::math::{Ray, Vec2, Vec3};

/// A mesh that emits: its instance and the area distribution over its triangles.
#[derive(Clone)]
pub struct MeshLight {
    /// The placed mesh (world space through its transform).
    pub instance: MeshInstance,
    /// Cumulative world-space area fractions, one per triangle, the last 1.
    cdf: Vec<f32>,
    /// Total world-space area, m^2.
    area: f32,
}

impl MeshLight {
    /// The light's surface for `instance`; `None` when its total world-space
    /// area is not positive and finite (no triangle, or all degenerate).
    pub fn new(instance: MeshInstance) -> Option<MeshLight> {
        let mesh = &*instance.mesh;
        let mut sums = Vec::with_capacity(mesh.triangle_count());
        let mut total = 0.0f64;
        for prim in 0..mesh.triangle_count() as u32 {
            total += triangle_area(&instance, prim) as f64;
            sums.push(total);
        }
        if !(total > 0.0) || !total.is_finite() {
            return None;
        }
        let cdf = sums.into_iter().map(|s| (s / total) as f32).collect::<Vec<_>>();
        Some(MeshLight { instance, cdf, area: total as f32 })
    }

    /// Total world-space area, m^2.
    #[inline]
    pub fn area(&self) -> f32 {
        self.area
    }

    /// Probability of choosing triangle `prim` (its share of the area).
    #[inline]
    pub fn triangle_pmf(&self, prim: u32) -> f32 {
        let i = prim as usize;
        self.cdf[i] - if i == 0 { 0.0 } else { self.cdf[i - 1] }
    }

    /// A point uniformly distributed by area (density `1 / area`), its
    /// front-side (shading) normal and its unit geometric normal (see the
    /// module docs): `u.x` chooses the triangle by area and is reused,
    /// rescaled, with `u.y` for the point inside it.
    pub fn sample_area(&self, u: Vec2) -> (Vec3, Vec3, Vec3) {
        let n = self.cdf.len();
        let prim = self.cdf.partition_point(|&c| c <= u.x).min(n - 1);
        let lo = if prim == 0 { 0.0 } else { self.cdf[prim - 1] };
        let width = self.cdf[prim] - lo;
        let ux = if width > 0.0 { ((u.x - lo) / width).clamp(0.0, 1.0 - f32::EPSILON / 2.0) } else { 0.5 };
        // Uniform barycentrics (pbrt-v4 section 6.5.4 with the corners
        // relabelled): b2 = 1 - sqrt(u1), b1 = u2 sqrt(u1).
        let su = ux.sqrt();
        let (b1, b2) = (u.y * su, 1.0 - su);
        let s = self.instance.surface_point(prim as u32, b1, b2);
        (s.p, s.ns, s.n)
    }

    /// The first point of the mesh along `ray` with `t` in `(t_min, t_max)`,
    /// with its normals (`ns` decides the emitting side, `n` is the
    /// geometric normal of the area-to-solid-angle conversion).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        let hit = self.instance.hit(ray, t_min, t_max)?;
        Some(self.instance.surface_at(ray, &hit))
    }
}

/// A summary (triangle count, vertex normals, world area and bounds), not the
/// mesh data, which `niebla info` would otherwise print in full.
impl std::fmt::Debug for MeshLight {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mesh = &*self.instance.mesh;
        let (lo, hi) = self.instance.bounds();
        f.debug_struct("MeshLight")
            .field("triangles", &mesh.triangle_count())
            .field("vertex_normals", &mesh.normals.is_some())
            .field("flip_normals", &mesh.winding_flipped)
            .field("area", &self.area)
            .field("bounds", &(lo.to_array(), hi.to_array()))
            .finish()
    }
}

/// World-space area of triangle `prim` of `instance`.
fn triangle_area(instance: &MeshInstance, prim: u32) -> f32 {
    let [a, b, c] = instance.mesh.corners(prim).map(|p| instance.transform.point_to_world(p));
    0.5 * (b - a).cross(c - a).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Transform, TriangleMesh};
    use crate::sampling::PixelSampler;
    use std::sync::Arc;

    /// Two triangles in z = 0: a unit right triangle (area 1/2) and one of
    /// area 3/2 beside it, scaled by 2 in x (areas 1 and 3).
    fn two_triangles() -> MeshLight {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::new(2.0, 1.0, 0.0),
        ];
        let mesh = TriangleMesh::new(positions, vec![[0, 1, 2], [3, 4, 5]], None, None).unwrap();
        let t = Transform::from_components(Vec3::new(2.0, 1.0, 1.0), Vec3::ZERO, Vec3::ZERO).unwrap();
        MeshLight::new(MeshInstance::new(Arc::new(mesh), t, false)).unwrap()
    }

    #[test]
    fn triangles_are_chosen_by_world_area() {
        let light = two_triangles();
        assert!((light.area() - 4.0).abs() < 1e-6);
        assert!((light.triangle_pmf(0) - 0.25).abs() < 1e-6);
        assert!((light.triangle_pmf(1) - 0.75).abs() < 1e-6);
        // Frequencies of 200k samples: binomial se of the fraction 0.25 is
        // 9.7e-4, so 5 se is 0.005.
        let mut rng = PixelSampler::from_key(3);
        let n = 200_000;
        let mut first = 0;
        let mut left = 0;
        for _ in 0..n {
            let (p, normal, geometric) = light.sample_area(rng.next_2d());
            assert!(p.z.abs() < 1e-6 && (normal - Vec3::Z).length() < 1e-6 && normal == geometric);
            if p.x < 3.0 {
                first += 1;
                // Uniform in the first triangle (x in [0, 2], y <= 1 - x/2):
                // half of its area has x < 2 - sqrt(2).
                if p.x < 2.0 - 2f32.sqrt() {
                    left += 1;
                }
            }
        }
        let f = first as f32 / n as f32;
        assert!((f - 0.25).abs() < 0.005, "fraction on the first triangle {f}");
        // Half of the first triangle's samples: se 0.5/sqrt(50000) = 2.2e-3.
        let h = left as f32 / first as f32;
        assert!((h - 0.5).abs() < 0.011, "fraction left of the median line {h}");
    }

    #[test]
    fn a_mesh_without_area_has_no_light() {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let mesh = TriangleMesh::new(positions, vec![[0, 1, 2]], None, None).unwrap();
        let t = Transform::from_components(Vec3::ONE, Vec3::ZERO, Vec3::ZERO).unwrap();
        assert!(MeshLight::new(MeshInstance::new(Arc::new(mesh), t, false)).is_none());
    }
}
