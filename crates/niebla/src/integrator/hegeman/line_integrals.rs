//! Per-light line integrals of the density toward a light, precomputed on a
//! lattice over a grid medium's box (the per-light precomputation of
//! Hegeman, Ashikhmin, Premoze 2005, "A lighting model for general
//! participating media"): at each
//! node `x`, with `r` the distance from `x` along the straight line to the
//! light (the assumed most probable path) and `d` the density,
//! `D0 = int d dr`, `D1 = int r d dr`, `D2 = int r^2 d dr`.
//!
//! They hold density only, so the medium's coefficients, albedo and phase can
//! change without recomputing: `tau_t = sigma_t D0`, `tau_s = sigma_s D0` and
//! the moments of the scattering power `k = sigma_s (1 - g) d` are
//! `K_n = sigma_s (1 - g) D_n`.

use rayon::prelude::*;

use crate::math::{Ray, Vec3};
use crate::medium::GridMedium;

/// Where light comes from, as seen by the precomputation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSource {
    /// A point (point and spot lights).
    Point(Vec3),
    /// A direction toward the light (directional lights, environment directions).
    Direction(Vec3),
}

/// Line integrals `(D0, D1, D2)` toward one light on a lattice of nodes.
#[derive(Clone, Debug)]
pub struct LineIntegralLattice {
    /// The light this lattice belongs to.
    pub source: LightSource,
    lo: Vec3,
    hi: Vec3,
    n: [usize; 3],
    values: Vec<[f32; 3]>,
}

/// Line integrals `(D0, D1, D2)` of the density from `x` toward `source`,
/// midpoint rule with `step` (world units) over the part inside the grid box.
pub fn line_integrals(medium: &GridMedium, x: Vec3, source: LightSource, step: f32) -> [f32; 3] {
    let (wi, distance) = match source {
        LightSource::Point(p) => {
            let v = p - x;
            let d = v.length();
            if d == 0.0 {
                return [0.0; 3];
            }
            (v / d, d)
        }
        LightSource::Direction(w) => (w, f32::INFINITY),
    };
    let ray = Ray::new(x, wi);
    let Some((t0, t1)) = medium.clip(&ray, 0.0, distance) else {
        return [0.0; 3];
    };
    let n = ((t1 - t0) / step).ceil().max(1.0) as usize;
    let dt = (t1 - t0) / n as f32;
    let mut sums = [0f32; 3];
    for k in 0..n {
        let r = t0 + (k as f32 + 0.5) * dt;
        let d = medium.density_at(ray.at(r)) * dt;
        sums[0] += d;
        sums[1] += r * d;
        sums[2] += r * r * d;
    }
    sums
}

impl LineIntegralLattice {
    /// Integrate the lattice: `resolution` nodes along the longest side of the
    /// medium's world box (proportionally fewer along the others), marching
    /// with a step of one lattice cell.
    pub fn new(medium: &GridMedium, source: LightSource, resolution: usize) -> LineIntegralLattice {
        let (lo, hi) = medium.world_bounds;
        let extent = hi - lo;
        let longest = extent.max_element().max(1e-6);
        let n =
            [0, 1, 2].map(|a| ((extent[a] / longest * resolution as f32).ceil() as usize).clamp(2, resolution.max(2)));
        let step = longest / resolution as f32;
        let values: Vec<[f32; 3]> = (0..n[0] * n[1] * n[2])
            .into_par_iter()
            .map(|i| {
                let (x, y, z) = (i % n[0], (i / n[0]) % n[1], i / (n[0] * n[1]));
                let f =
                    Vec3::new(x as f32 / (n[0] - 1) as f32, y as f32 / (n[1] - 1) as f32, z as f32 / (n[2] - 1) as f32);
                line_integrals(medium, lo + extent * f, source, step)
            })
            .collect();
        LineIntegralLattice { source, lo, hi, n, values }
    }

    /// Trilinear `(D0, D1, D2)` at world point `p` (clamped to the box).
    #[inline]
    pub fn lookup(&self, p: Vec3) -> [f32; 3] {
        let f = ((p - self.lo) / (self.hi - self.lo)).clamp(Vec3::ZERO, Vec3::ONE);
        let g = [f.x * (self.n[0] - 1) as f32, f.y * (self.n[1] - 1) as f32, f.z * (self.n[2] - 1) as f32];
        let i = [0, 1, 2].map(|a| (g[a] as usize).min(self.n[a] - 2));
        let t = [0, 1, 2].map(|a| g[a] - i[a] as f32);
        let mut out = [0f32; 3];
        for corner in 0..8 {
            let (dx, dy, dz) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let w = (if dx == 1 { t[0] } else { 1.0 - t[0] })
                * (if dy == 1 { t[1] } else { 1.0 - t[1] })
                * (if dz == 1 { t[2] } else { 1.0 - t[2] });
            let v = self.values[(i[0] + dx) + self.n[0] * ((i[1] + dy) + self.n[1] * (i[2] + dz))];
            for c in 0..3 {
                out[c] += w * v[c];
            }
        }
        out
    }

    /// Nodes along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.n
    }

    /// `(D0, D1, D2)` at node `index` (x fastest).
    #[inline]
    pub fn node(&self, index: usize) -> [f32; 3] {
        self.values[index]
    }

    /// Bytes held by the lattice.
    pub fn memory_bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<[f32; 3]>()
    }
}
