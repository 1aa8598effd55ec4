//! Gaussian radial basis functions `w exp(-|x - c|^2 / r^2)` (truncated at
//! `3 r`, as in the paper) approximating a density field, their
//! evaluation on a lattice through buckets, the RBF-weighted interpolation
//! of per-centre values (Zhou et al. Eq. 7) and closed-form optical depths.

use rayon::prelude::*;

use super::lattice::Lattice;
use crate::math::Vec3;

/// Support radius in units of `r`.
pub const SUPPORT: f32 = 3.0;

/// One Gaussian: density `weight exp(-|x - center|^2 / radius^2)` (world units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rbf {
    /// Centre (world).
    pub center: Vec3,
    /// Radius `r` (world length).
    pub radius: f32,
    /// Peak density `w`.
    pub weight: f32,
}

impl Rbf {
    /// Kernel value `exp(-|x-c|^2/r^2)` (no weight), 0 beyond the support.
    #[inline]
    pub fn kernel(&self, x: Vec3) -> f32 {
        let d2 = (x - self.center).length_squared();
        let r2 = self.radius * self.radius;
        if d2 >= SUPPORT * SUPPORT * r2 {
            0.0
        } else {
            (-d2 / r2).exp()
        }
    }

    /// Importance: the kernel's integral `w r^3 pi^1.5` (density x volume).
    #[inline]
    pub fn importance(&self) -> f32 {
        self.weight * self.radius.powi(3) * std::f32::consts::PI.powf(1.5)
    }

    /// Density integral of this RBF along `x + t w`, `t` in `[0, length]`
    /// (`length` may be infinite), untruncated kernel, closed form:
    /// `w r exp(-delta^2 (1 - mu^2)) sqrt(pi)/2 (erf((length - d mu)/r) + erf(delta mu))`
    /// with `d = |c - x|`, `delta = d/r`, `mu = cos(w, c - x)`.
    #[inline]
    pub fn optical_depth(&self, x: Vec3, w: Vec3, length: f32) -> f64 {
        let v = [0, 1, 2].map(|a| self.center[a] as f64 - x[a] as f64);
        let w = [w.x as f64, w.y as f64, w.z as f64];
        let r = self.radius as f64;
        let along = v[0] * w[0] + v[1] * w[1] + v[2] * w[2]; // d mu
        let perp2 = [0, 1, 2].map(|a| (v[a] - along * w[a]).powi(2)).iter().sum::<f64>();
        let far = if length.is_finite() { libm::erf((length as f64 - along) / r) } else { 1.0 };
        self.weight as f64
            * r
            * (-perp2 / (r * r)).exp()
            * (0.5 * std::f64::consts::PI.sqrt())
            * (far + libm::erf(along / r))
    }
}

/// `tau_u(delta, mu)`: optical depth of a unit-radius, unit-weight Gaussian
/// along a half-line starting at distance `delta` from its centre, at cosine
/// `mu` to the axis toward the centre.
#[inline]
pub fn unit_half_line_depth(delta: f64, mu: f64) -> f64 {
    (-delta * delta * (1.0 - mu * mu)).exp() * 0.5 * std::f64::consts::PI.sqrt() * (1.0 + libm::erf(mu * delta))
}

/// RBF indices per bucket of `BUCKET` x `BUCKET` x `BUCKET` lattice nodes,
/// each RBF listed in every bucket its support box touches.
pub struct Buckets {
    n: [usize; 3],
    lists: Vec<Vec<u32>>,
}

/// Bucket edge in lattice nodes.
const BUCKET: usize = 4;

impl Buckets {
    /// Buckets of `rbfs` over `lattice`.
    pub fn new(lattice: &Lattice, rbfs: &[Rbf]) -> Buckets {
        let n = lattice.n.map(|v| v.div_ceil(BUCKET));
        let mut lists = vec![Vec::new(); n[0] * n[1] * n[2]];
        for (index, rbf) in rbfs.iter().enumerate() {
            let b = lattice.node_box(rbf.center, SUPPORT * rbf.radius);
            if b.iter().any(|(lo, hi)| lo > hi) {
                continue;
            }
            for bz in b[2].0 / BUCKET..=b[2].1 / BUCKET {
                for by in b[1].0 / BUCKET..=b[1].1 / BUCKET {
                    for bx in b[0].0 / BUCKET..=b[0].1 / BUCKET {
                        lists[bx + n[0] * (by + n[1] * bz)].push(index as u32);
                    }
                }
            }
        }
        Buckets { n, lists }
    }

    /// RBFs that may reach node `[i, j, k]`.
    #[inline]
    pub fn near(&self, node: [usize; 3]) -> &[u32] {
        let b = node.map(|v| v / BUCKET);
        &self.lists[b[0] + self.n[0] * (b[1] + self.n[1] * b[2])]
    }
}

/// `D~` at every lattice node: the sum of the RBFs.
pub fn evaluate_at_nodes(lattice: &Lattice, rbfs: &[Rbf]) -> Vec<f32> {
    let buckets = Buckets::new(lattice, rbfs);
    (0..lattice.len())
        .into_par_iter()
        .with_min_len(256)
        .map(|node| {
            let x = lattice.position_of(node);
            buckets
                .near(lattice.coords(node))
                .iter()
                .map(|&l| rbfs[l as usize].weight * rbfs[l as usize].kernel(x))
                .sum()
        })
        .collect()
}

/// Zhou et al. Eq. 7 at every lattice node: `sum_l w_l B_l(x) v_l / sum_l w_l B_l(x)`
/// for per-RBF vectors `values[l * stride .. (l + 1) * stride]`. Where no RBF
/// reaches a node (or their sum is below `1e-6` of the largest weight) the
/// nearest centre's values are used, so residual-only wisps still get a source.
pub fn interpolate_at_nodes(lattice: &Lattice, rbfs: &[Rbf], values: &[f64], stride: usize) -> Vec<f32> {
    let buckets = Buckets::new(lattice, rbfs);
    let floor = 1e-6 * rbfs.iter().map(|r| r.weight).fold(0.0f32, f32::max) as f64;
    let mut out = vec![0f32; lattice.len() * stride];
    out.par_chunks_mut(stride).enumerate().with_min_len(256).for_each(|(node, o)| {
        let x = lattice.position_of(node);
        let mut acc = vec![0f64; stride];
        let mut total = 0f64;
        for &l in buckets.near(lattice.coords(node)) {
            let rbf = &rbfs[l as usize];
            let b = (rbf.weight * rbf.kernel(x)) as f64;
            if b > 0.0 {
                total += b;
                for (a, v) in acc.iter_mut().zip(&values[l as usize * stride..(l as usize + 1) * stride]) {
                    *a += b * v;
                }
            }
        }
        if total > floor {
            for (o, a) in o.iter_mut().zip(&acc) {
                *o = (a / total) as f32;
            }
        } else if let Some(l) = nearest(rbfs, x) {
            for (o, v) in o.iter_mut().zip(&values[l * stride..(l + 1) * stride]) {
                *o = *v as f32;
            }
        }
    });
    out
}

/// Index of the RBF whose centre is nearest to `x` in units of its radius.
fn nearest(rbfs: &[Rbf], x: Vec3) -> Option<usize> {
    rbfs.iter()
        .enumerate()
        .map(|(i, r)| (i, (r.center - x).length() / r.radius))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// T1: closed-form optical depth of a Gaussian against 1D quadrature.
    #[test]
    fn closed_form_optical_depth_matches_quadrature() {
        let rbf = Rbf { center: Vec3::new(0.3, -0.2, 0.5), radius: 0.4, weight: 2.5 };
        let cases = [
            (Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 0.1, 0.3).normalize(), f32::INFINITY),
            (Vec3::new(0.3, -0.2, 0.5), Vec3::new(0.0, 0.0, 1.0), f32::INFINITY),
            (Vec3::new(0.5, 0.0, 0.2), Vec3::new(-0.3, 0.9, 0.1).normalize(), 0.7),
            (Vec3::new(2.0, 1.0, 1.0), Vec3::new(1.0, 0.0, 0.0), f32::INFINITY),
        ];
        for (x, w, len) in cases {
            let closed = rbf.optical_depth(x, w, len);
            let end = if len.is_finite() { len as f64 } else { 20.0 };
            let n = 200_000;
            let dt = end / n as f64;
            let mut q = 0.0;
            for i in 0..n {
                let t = (i as f64 + 0.5) * dt;
                let p = [x.x as f64 + t * w.x as f64, x.y as f64 + t * w.y as f64, x.z as f64 + t * w.z as f64];
                let d2 = (p[0] - rbf.center.x as f64).powi(2)
                    + (p[1] - rbf.center.y as f64).powi(2)
                    + (p[2] - rbf.center.z as f64).powi(2);
                q += 2.5 * (-d2 / 0.16f64).exp() * dt;
            }
            // f32 inputs limit agreement to ~1e-7 relative.
            assert!((closed - q).abs() < 1e-6 * (1.0 + q), "{closed} vs {q}");
        }
        // The unit half-line form is the same integral.
        let (delta, mu) = (1.7f64, 0.35f64);
        let u = Rbf { center: Vec3::new(1.7, 0.0, 0.0), radius: 1.0, weight: 1.0 };
        let w = Vec3::new(mu as f32, (1.0 - mu * mu).sqrt() as f32, 0.0);
        assert!((u.optical_depth(Vec3::ZERO, w, f32::INFINITY) - unit_half_line_depth(delta, mu)).abs() < 1e-6);
    }

    #[test]
    fn interpolation_reproduces_constant_values_and_falls_back_to_the_nearest_centre() {
        let lattice = Lattice::over_box(Vec3::ZERO, Vec3::ONE, 8);
        let rbfs = vec![
            Rbf { center: Vec3::new(0.2, 0.2, 0.2), radius: 0.15, weight: 1.0 },
            Rbf { center: Vec3::new(0.3, 0.25, 0.2), radius: 0.1, weight: 0.5 },
        ];
        let values = vec![2.0, -1.0, 2.0, -1.0];
        let out = interpolate_at_nodes(&lattice, &rbfs, &values, 2);
        for node in out.chunks(2) {
            assert!((node[0] - 2.0).abs() < 1e-6 && (node[1] + 1.0).abs() < 1e-6);
        }
        let d = evaluate_at_nodes(&lattice, &rbfs);
        let x = lattice.position(1, 1, 1);
        let direct: f32 = rbfs.iter().map(|r| r.weight * r.kernel(x)).sum();
        assert!((d[lattice.index(1, 1, 1)] - direct).abs() < 1e-7);
    }
}
