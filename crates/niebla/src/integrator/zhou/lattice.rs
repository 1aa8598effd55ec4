//! The cell-centered lattice over a grid medium's world box on which the
//! `zhou` integrator samples the density for the RBF fit, solves the
//! diffusion equation and stores its per-view source radiance.

use crate::math::Vec3;

/// A cubic-cell lattice: node `(i, j, k)` sits at `lo + h (i + 1/2, j + 1/2, k + 1/2)`
/// (world units), stored x fastest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    /// World-space corner of the box.
    pub lo: Vec3,
    /// Cell edge length (world units).
    pub h: f32,
    /// Nodes per axis (>= 2 each).
    pub n: [usize; 3],
}

impl Lattice {
    /// A lattice with `resolution` cells along the longest side of `[lo, hi]`.
    pub fn over_box(lo: Vec3, hi: Vec3, resolution: usize) -> Lattice {
        let extent = (hi - lo).max(Vec3::splat(1e-6));
        let h = extent.max_element() / resolution.max(2) as f32;
        let n = [extent.x, extent.y, extent.z].map(|e| ((e / h).ceil() as usize).max(2));
        Lattice { lo, h, n }
    }

    /// Number of nodes.
    #[inline]
    pub fn len(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    /// True when the lattice has no nodes (never for a constructed lattice).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Flat index of node `(i, j, k)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.n[0] * (j + self.n[1] * k)
    }

    /// Node `(i, j, k)` of a flat index.
    #[inline]
    pub fn coords(&self, index: usize) -> [usize; 3] {
        [index % self.n[0], (index / self.n[0]) % self.n[1], index / (self.n[0] * self.n[1])]
    }

    /// World position of node `(i, j, k)`.
    #[inline]
    pub fn position(&self, i: usize, j: usize, k: usize) -> Vec3 {
        self.lo + Vec3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5) * self.h
    }

    /// World position of a flat index.
    #[inline]
    pub fn position_of(&self, index: usize) -> Vec3 {
        let [i, j, k] = self.coords(index);
        self.position(i, j, k)
    }

    /// Inclusive node index range per axis of the nodes within `radius` of `c`
    /// (a bounding box; empty ranges have `lo > hi`).
    pub fn node_box(&self, c: Vec3, radius: f32) -> [(usize, usize); 3] {
        let f = |a: usize, v: f32| {
            let lo = ((v - radius - self.lo[a]) / self.h - 0.5).ceil().max(0.0);
            let hi = ((v + radius - self.lo[a]) / self.h - 0.5).floor().min(self.n[a] as f32 - 1.0);
            if hi < 0.0 || lo > hi {
                (1, 0)
            } else {
                (lo as usize, hi as usize)
            }
        };
        [f(0, c.x), f(1, c.y), f(2, c.z)]
    }

    /// Flat indices of the 8 nodes around world point `x` and their
    /// trilinear weights (clamped to the outermost nodes).
    #[inline]
    pub fn corners(&self, x: Vec3) -> ([usize; 8], [f32; 8]) {
        let g = (x - self.lo) / self.h - Vec3::splat(0.5);
        let mut i = [0usize; 3];
        let mut t = [0f32; 3];
        for a in 0..3 {
            let v = g[a].clamp(0.0, (self.n[a] - 1) as f32);
            let i0 = (v as usize).min(self.n[a] - 2);
            i[a] = i0;
            t[a] = v - i0 as f32;
        }
        let mut base = [0usize; 8];
        let mut weights = [0f32; 8];
        for corner in 0..8 {
            let (dx, dy, dz) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            weights[corner] = (if dx == 1 { t[0] } else { 1.0 - t[0] })
                * (if dy == 1 { t[1] } else { 1.0 - t[1] })
                * (if dz == 1 { t[2] } else { 1.0 - t[2] });
            base[corner] = self.index(i[0] + dx, i[1] + dy, i[2] + dz);
        }
        (base, weights)
    }

    /// An RBF given in lattice units (centre in node coordinates, radius in
    /// cells) in world units.
    pub fn rbf_to_world(&self, rbf: &super::rbf::Rbf) -> super::rbf::Rbf {
        super::rbf::Rbf {
            center: self.lo + (rbf.center + Vec3::splat(0.5)) * self.h,
            radius: rbf.radius * self.h,
            weight: rbf.weight,
        }
    }

    /// Trilinear interpolation of a scalar field on the nodes.
    #[inline]
    pub fn interpolate(&self, values: &[f32], x: Vec3) -> f32 {
        let (base, weights) = self.corners(x);
        base.iter().zip(weights).map(|(&b, w)| values[b] * w).sum()
    }
}
