//! Watertight ray/triangle intersection (Woop, Benthin and Wald 2013,
//! "Watertight Ray/Triangle Intersection", JCGT 2(1)).
//!
//! The ray is sheared so that it runs along +z from the origin; each vertex is
//! transformed once by the same shear, and the three 2D edge functions are
//! evaluated on the sheared vertices. Two triangles sharing an edge compute
//! that edge's function from the same two transformed vertices in the same
//! floating-point order, so the values are exact negatives of each other: a
//! ray through a shared edge or vertex hits at least one of the triangles, and
//! never slips between them. Edge values of exactly zero are recomputed in
//! `f64` (the paper's fallback). Both faces are hit (no back-face culling).

use crate::math::{Ray, Vec3};

/// A ray prepared for [`intersect_triangle`]: the permutation that makes the
/// dominant direction component `z`, and the shear coefficients.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    /// Ray origin.
    pub o: Vec3,
    /// Index of the dominant axis of the direction.
    kz: usize,
    /// The two other axes, ordered to keep the winding.
    kx: usize,
    ky: usize,
    /// Shear `d[kx] / d[kz]`, `d[ky] / d[kz]` and `1 / d[kz]`.
    sx: f32,
    sy: f32,
    sz: f32,
}

impl WatertightRay {
    /// Prepares `ray` (its direction need not be unit length; `t` is measured
    /// in units of the direction's length).
    #[inline]
    pub fn new(ray: &Ray) -> WatertightRay {
        let d = ray.d;
        let a = d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / d[kz];
        WatertightRay { o: ray.o, kz, kx, ky, sx: d[kx] * sz, sy: d[ky] * sz, sz }
    }
}

/// A hit on a triangle: the ray parameter and the barycentric weights of the
/// second and third vertex (the first's is `1 - b1 - b2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Barycentric weight of vertex 1.
    pub b1: f32,
    /// Barycentric weight of vertex 2.
    pub b2: f32,
}

/// Intersection of `ray` with the triangle `(p0, p1, p2)` with `t` in
/// `(t_min, t_max)`, either face; `None` for a miss or a degenerate triangle.
#[inline]
pub fn intersect_triangle(
    ray: &WatertightRay,
    p0: Vec3,
    p1: Vec3,
    p2: Vec3,
    t_min: f32,
    t_max: f32,
) -> Option<TriangleHit> {
    let (kx, ky, kz) = (ray.kx, ray.ky, ray.kz);
    let a = p0 - ray.o;
    let b = p1 - ray.o;
    let c = p2 - ray.o;
    let ax = a[kx] - ray.sx * a[kz];
    let ay = a[ky] - ray.sy * a[kz];
    let bx = b[kx] - ray.sx * b[kz];
    let by = b[ky] - ray.sy * b[kz];
    let cx = c[kx] - ray.sx * c[kz];
    let cy = c[ky] - ray.sy * c[kz];

    // Edge functions: e0 is opposite vertex 0 (its barycentric weight), etc.
    let mut e0 = cx * by - cy * bx;
    let mut e1 = ax * cy - ay * cx;
    let mut e2 = bx * ay - by * ax;
    if e0 == 0.0 || e1 == 0.0 || e2 == 0.0 {
        let (ax, ay, bx, by, cx, cy) = (ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64);
        e0 = (cx * by - cy * bx) as f32;
        e1 = (ax * cy - ay * cx) as f32;
        e2 = (bx * ay - by * ax) as f32;
    }
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let az = ray.sz * a[kz];
    let bz = ray.sz * b[kz];
    let cz = ray.sz * c[kz];
    let t_scaled = e0 * az + e1 * bz + e2 * cz;
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if !(t > t_min && t < t_max) {
        return None;
    }
    Some(TriangleHit { t, b1: e1 * inv_det, b2: e2 * inv_det })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_inside_with_barycentrics_and_misses_outside() {
        let (p0, p1, p2) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
        let ray = Ray::new(Vec3::new(0.25, 0.5, 2.0), Vec3::new(0.0, 0.0, -1.0));
        let h = intersect_triangle(&WatertightRay::new(&ray), p0, p1, p2, 0.0, f32::INFINITY).unwrap();
        assert!((h.t - 2.0).abs() < 1e-6);
        assert!((h.b1 - 0.25).abs() < 1e-6 && (h.b2 - 0.5).abs() < 1e-6);
        // From below (back face) too, and limited by t_max.
        let up = Ray::new(Vec3::new(0.25, 0.25, -1.0), Vec3::new(0.0, 0.0, 1.0));
        assert!(intersect_triangle(&WatertightRay::new(&up), p0, p1, p2, 0.0, 2.0).is_some());
        assert!(intersect_triangle(&WatertightRay::new(&up), p0, p1, p2, 0.0, 0.5).is_none());
        let miss = Ray::new(Vec3::new(0.8, 0.8, 1.0), Vec3::new(0.0, 0.0, -1.0));
        assert!(intersect_triangle(&WatertightRay::new(&miss), p0, p1, p2, 0.0, f32::INFINITY).is_none());
        // Degenerate (collinear) triangle: never hit.
        let flat = Vec3::new(2.0, 0.0, 0.0);
        assert!(intersect_triangle(&WatertightRay::new(&ray), p0, p1, flat, 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn a_ray_through_a_shared_edge_hits_one_of_the_two_triangles() {
        // Two triangles sharing the diagonal of a unit square; rays aimed
        // exactly at points inside the diagonal (its end vertices are
        // corners of the square, where rounding of the direction may
        // legitimately miss both).
        let (a, b, c, d) = (Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
        for i in 1..64 {
            let s = i as f32 / 64.0;
            let target = Vec3::new(s, s, 0.0);
            let o = Vec3::new(0.3, -0.7, 1.9);
            let ray = Ray::new(o, (target - o).normalize());
            let w = WatertightRay::new(&ray);
            let hits = intersect_triangle(&w, a, b, c, 0.0, f32::INFINITY).is_some() as u32
                + intersect_triangle(&w, a, c, d, 0.0, f32::INFINITY).is_some() as u32;
            assert!(hits >= 1, "ray at diagonal point {s} slipped through");
        }
    }
}
