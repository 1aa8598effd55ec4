//! Real spherical harmonics for the `zhou` integrator: evaluation, a
//! quadrature grid on the sphere for projections and products, rotation of
//! zonal harmonics, and the Legendre (zonal) coefficients of a phase function.
//!
//! Convention (pinned by a test; some PRT code bases carry extra minus signs
//! on `l = 1`): orthonormal real SH,
//! index `l*l + l + m`, no Condon-Shortley phase, so
//! `y_{1,-1} = sqrt(3/4pi) y`, `y_{1,0} = sqrt(3/4pi) z`, `y_{1,1} = sqrt(3/4pi) x`.
//! A function `f(w)` of a unit direction is `sum_lm f_lm y_lm(w)`. All math is
//! `f64`: these are precomputation paths, not per-sample code.

use crate::math::Vec3;
use crate::phase::PhaseFunction;

/// Largest supported SH order (bands `l < MAX_ORDER`).
pub const MAX_ORDER: usize = 6;

/// Number of coefficients of order `n` (bands `0..n`).
#[inline]
pub const fn coefficient_count(order: usize) -> usize {
    order * order
}

/// Evaluate all real SH of bands `0..order` at the unit direction `w`
/// (x, y, z as f64) into `out[..order^2]`.
pub fn eval_basis(order: usize, w: [f64; 3], out: &mut [f64]) {
    debug_assert!(order <= MAX_ORDER && out.len() >= order * order);
    let [x, y, z] = w;
    let norms = normalizations();
    // (x + i y)^m = sin^m(theta) e^{i m phi}: cos/sin parts without atan2.
    let mut cm = [0f64; MAX_ORDER];
    let mut sm = [0f64; MAX_ORDER];
    cm[0] = 1.0;
    for m in 1..order {
        cm[m] = cm[m - 1] * x - sm[m - 1] * y;
        sm[m] = cm[m - 1] * y + sm[m - 1] * x;
    }
    for m in 0..order {
        // pt[l] = P_l^m(z) / sin^m(theta), no Condon-Shortley phase.
        let mut pmm = 1.0;
        for k in 0..m {
            pmm *= (2 * k + 1) as f64;
        }
        let mut prev2 = 0.0;
        let mut prev = pmm;
        for l in m..order {
            let p = if l == m {
                pmm
            } else if l == m + 1 {
                z * (2 * m + 1) as f64 * pmm
            } else {
                ((2 * l - 1) as f64 * z * prev - (l + m - 1) as f64 * prev2) / (l - m) as f64
            };
            if l > m {
                prev2 = prev;
                prev = p;
            }
            let k = norms[l * l + l + m];
            if m == 0 {
                out[l * l + l] = k * p;
            } else {
                let s = std::f64::consts::SQRT_2 * k * p;
                out[l * l + l + m] = s * cm[m];
                out[l * l + l - m] = s * sm[m];
            }
        }
    }
}

/// [`normalization`] of every `(l, m >= 0)` up to [`MAX_ORDER`], at index
/// `l*l + l + m`, computed once per process (the per-view pass evaluates the
/// basis at every lattice node).
fn normalizations() -> &'static [f64; MAX_ORDER * MAX_ORDER] {
    static TABLE: std::sync::OnceLock<[f64; MAX_ORDER * MAX_ORDER]> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut table = [0.0; MAX_ORDER * MAX_ORDER];
        for l in 0..MAX_ORDER {
            for m in 0..=l {
                table[l * l + l + m] = normalization(l, m);
            }
        }
        table
    })
}

/// `K_lm = sqrt((2l+1)/(4pi) (l-m)!/(l+m)!)`.
fn normalization(l: usize, m: usize) -> f64 {
    let mut ratio = 1.0;
    for k in (l - m + 1)..=(l + m) {
        ratio /= k as f64;
    }
    ((2 * l + 1) as f64 / (4.0 * std::f64::consts::PI) * ratio).sqrt()
}

/// Gauss-Legendre nodes and weights on [-1, 1] (Newton on `P_n`).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..n {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, x);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let p = if n == 0 { 1.0 } else { p1 };
            let pm1 = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (x * p - pm1) / (x * x - 1.0);
            let dx = p / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        nodes[i] = x;
        weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
    (nodes, weights)
}

/// A product quadrature on the sphere (Gauss-Legendre in `cos theta`,
/// uniform in `phi`) with the SH basis of one order tabulated at its nodes.
/// With `3 order` x `6 order` nodes it integrates products of three
/// functions of that order exactly.
#[derive(Clone, Debug)]
pub struct SphereQuadrature {
    /// SH order of the tabulated basis.
    pub order: usize,
    /// Unit directions of the nodes.
    pub directions: Vec<[f64; 3]>,
    /// Solid-angle weights (sum 4 pi).
    pub weights: Vec<f64>,
    /// `basis[node * order^2 + k]`.
    pub basis: Vec<f64>,
}

impl SphereQuadrature {
    /// The quadrature for SH order `order` (1..=MAX_ORDER).
    pub fn new(order: usize) -> SphereQuadrature {
        let order = order.clamp(1, MAX_ORDER);
        SphereQuadrature::with_nodes(order, 3 * order, 6 * order)
    }

    /// A quadrature with `nt` Gauss-Legendre nodes in `cos theta` and `np`
    /// azimuths, tabulating the basis of order `order`.
    pub fn with_nodes(order: usize, nt: usize, np: usize) -> SphereQuadrature {
        let order = order.clamp(1, MAX_ORDER);
        let (zs, wz) = gauss_legendre(nt);
        let nc = coefficient_count(order);
        let mut directions = Vec::with_capacity(nt * np);
        let mut weights = Vec::with_capacity(nt * np);
        let mut basis = vec![0.0; nt * np * nc];
        for (z, wzi) in zs.iter().zip(&wz) {
            let s = (1.0 - z * z).max(0.0).sqrt();
            for j in 0..np {
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / np as f64;
                let d = [s * phi.cos(), s * phi.sin(), *z];
                let k = directions.len();
                eval_basis(order, d, &mut basis[k * nc..(k + 1) * nc]);
                directions.push(d);
                weights.push(wzi * 2.0 * std::f64::consts::PI / np as f64);
            }
        }
        SphereQuadrature { order, directions, weights, basis }
    }

    /// Number of coefficients.
    #[inline]
    pub fn coefficients(&self) -> usize {
        coefficient_count(self.order)
    }

    /// Values of the SH expansion `coeffs` at every node.
    pub fn synthesize(&self, coeffs: &[f64], out: &mut [f64]) {
        let nc = self.coefficients();
        for (k, o) in out.iter_mut().enumerate() {
            let b = &self.basis[k * nc..(k + 1) * nc];
            *o = b.iter().zip(coeffs).map(|(b, c)| b * c).sum();
        }
    }

    /// SH coefficients of the function with `values` at the nodes.
    pub fn project(&self, values: &[f64], out: &mut [f64]) {
        let nc = self.coefficients();
        out[..nc].fill(0.0);
        for (k, (v, w)) in values.iter().zip(&self.weights).enumerate() {
            let vw = v * w;
            for (o, b) in out.iter_mut().zip(&self.basis[k * nc..(k + 1) * nc]) {
                *o += vw * b;
            }
        }
    }
}

/// Coefficients of a zonal function (axis +z) with zonal coefficients
/// `zonal[l]` (the `m = 0` ones), rotated to the unit axis `a` and added,
/// times `scale`, to `out`: `out_lm += scale sqrt(4pi/(2l+1)) zonal_l y_lm(a)`.
pub fn add_rotated_zonal(order: usize, zonal: &[f64], a: [f64; 3], scale: f64, out: &mut [f64]) {
    let mut y = [0f64; MAX_ORDER * MAX_ORDER];
    eval_basis(order, a, &mut y);
    for l in 0..order {
        let f = scale * (4.0 * std::f64::consts::PI / (2 * l + 1) as f64).sqrt() * zonal[l];
        for k in l * l..(l + 1) * (l + 1) {
            out[k] += f * y[k];
        }
    }
}

/// The convolution factors `a_l = 2 pi int p(z) P_l(z) dz` of a phase
/// function normalized to 1 (`z` the scattering cosine, forward = +1): the
/// in-scattered radiance of an incident field `f` is `sum a_l f_lm y_lm`.
/// For Henyey-Greenstein `a_l = g^l`. Integrated by composite Gauss-Legendre
/// in the scattering angle (resolves forward peaks).
pub fn phase_convolution(phase: &PhaseFunction, order: usize) -> Vec<f64> {
    let (xs, ws) = gauss_legendre(8);
    let pieces = 512;
    let mut a = vec![0.0; order];
    let dtheta = std::f64::consts::PI / pieces as f64;
    for i in 0..pieces {
        for (x, w) in xs.iter().zip(&ws) {
            let theta = (i as f64 + 0.5 * (x + 1.0)) * dtheta;
            let z = theta.cos();
            let weight = 0.5 * dtheta * w * theta.sin() * 2.0 * std::f64::consts::PI;
            let p = phase.eval_mu(z as f32) as f64;
            let (mut p0, mut p1) = (1.0, z);
            for (l, al) in a.iter_mut().enumerate() {
                let pl = match l {
                    0 => 1.0,
                    1 => z,
                    _ => {
                        let p2 = ((2 * l - 1) as f64 * z * p1 - (l - 1) as f64 * p0) / l as f64;
                        p0 = p1;
                        p1 = p2;
                        p2
                    }
                };
                *al += weight * p * pl;
            }
        }
    }
    a
}

/// A world-space direction as f64 components.
#[inline]
pub fn dir64(v: Vec3) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn band_one_has_the_pinned_signs() {
        // T4: project a + b.w and recover a and b.
        let q = SphereQuadrature::new(3);
        let (a, b) = (0.7, [0.3, -0.2, 0.5]);
        let values: Vec<f64> = q.directions.iter().map(|d| a + b[0] * d[0] + b[1] * d[1] + b[2] * d[2]).collect();
        let mut c = vec![0.0; 9];
        q.project(&values, &mut c);
        // int (b.w) y_11 dw = b_x sqrt(3/4pi) 4pi/3, so b_x = c_11 sqrt(3/4pi).
        let k1 = (3.0 / (4.0 * std::f64::consts::PI)).sqrt();
        assert!((c[0] / (4.0 * std::f64::consts::PI).sqrt() - a).abs() < 1e-12);
        assert!((c[3] * k1 - b[0]).abs() < 1e-12, "x from y_11");
        assert!((c[1] * k1 - b[1]).abs() < 1e-12, "y from y_1-1");
        assert!((c[2] * k1 - b[2]).abs() < 1e-12, "z from y_10");
        for k in 4..9 {
            assert!(c[k].abs() < 1e-12);
        }
    }

    #[test]
    fn basis_is_orthonormal() {
        let q = SphereQuadrature::new(MAX_ORDER);
        let nc = q.coefficients();
        for i in 0..nc {
            for j in 0..nc {
                let s: f64 =
                    (0..q.weights.len()).map(|k| q.weights[k] * q.basis[k * nc + i] * q.basis[k * nc + j]).sum();
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!((s - expected).abs() < 1e-12, "<y{i}, y{j}> = {s}");
            }
        }
    }

    #[test]
    fn hg_convolution_factors_are_powers_of_g() {
        // T3, first half: a_l = g^l for Henyey-Greenstein.
        for g in [0.0f32, 0.3, -0.5, 0.8] {
            let a = phase_convolution(&PhaseFunction::hg(g), 6);
            for (l, al) in a.iter().enumerate() {
                assert!((al - (g as f64).powi(l as i32)).abs() < 2e-6, "g {g} l {l}: {al}");
            }
        }
    }

    #[test]
    fn convolution_matches_quadrature_of_the_in_scattering_integral() {
        // T3: J(w_o) = int L(w_i) p(w_o . w_i) dw_i equals sum a_l L_lm y_lm(w_o)
        // for a band-limited L.
        let order = 4;
        let coeffs: Vec<f64> = (0..16).map(|k| ((k * 37 % 11) as f64 - 5.0) / 7.0).collect();
        let phase = PhaseFunction::hg(0.4);
        let a = phase_convolution(&phase, order);
        // L at fine nodes (band-limited, so exact), integrate against p numerically.
        let mut y = [0f64; 36];
        let l_at = |d: [f64; 3], y: &mut [f64; 36]| {
            eval_basis(order, d, y);
            (0..16).map(|k| coeffs[k] * y[k]).sum::<f64>()
        };
        // A finer direct quadrature: 64 x 128 nodes.
        let (zs, wz) = gauss_legendre(64);
        for wo in [[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.0, -1.0, 0.0]] {
            let mut direct = 0.0;
            for (z, w) in zs.iter().zip(&wz) {
                let s = (1.0 - z * z).sqrt();
                for j in 0..128 {
                    let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / 128.0;
                    let d = [s * phi.cos(), s * phi.sin(), *z];
                    let mu = d[0] * wo[0] + d[1] * wo[1] + d[2] * wo[2];
                    direct +=
                        w * 2.0 * std::f64::consts::PI / 128.0 * l_at(d, &mut y) * phase.eval_mu(mu as f32) as f64;
                }
            }
            eval_basis(order, wo, &mut y);
            let via_sh: f64 = (0..order)
                .flat_map(|l| (l * l..(l + 1) * (l + 1)).map(move |k| (l, k)))
                .map(|(l, k)| a[l] * coeffs[k] * y[k])
                .sum();
            assert!((direct - via_sh).abs() < 1e-5 * (1.0 + direct.abs()), "{direct} vs {via_sh}");
        }
    }

    #[test]
    fn rotated_zonal_equals_direct_projection() {
        // A zonal function f(w) = exp(a . w) projected directly vs its zonal
        // coefficients rotated to a.
        let order = 5;
        let q = SphereQuadrature::new(order);
        let axis = [0.48, -0.6, 0.64];
        let f = |c: f64| (1.3 * c).exp();
        let (zs, wz) = gauss_legendre(64);
        let mut zonal = vec![0.0; order];
        let mut y = [0f64; 36];
        for (z, w) in zs.iter().zip(&wz) {
            eval_basis(order, [0.0, 0.0, *z], &mut y);
            for l in 0..order {
                zonal[l] += 2.0 * std::f64::consts::PI * w * f(*z) * y[l * l + l];
            }
        }
        let mut rotated = vec![0.0; 25];
        add_rotated_zonal(order, &zonal, axis, 1.0, &mut rotated);
        let values: Vec<f64> =
            q.directions.iter().map(|d| f(d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2])).collect();
        let mut direct = vec![0.0; 25];
        q.project(&values, &mut direct);
        // The quadrature is exact only for band-limited functions; exp(1.3 c)
        // has tiny energy above band 14, so agreement is near round-off.
        for k in 0..25 {
            assert!((rotated[k] - direct[k]).abs() < 1e-9, "k {k}: {} vs {}", rotated[k], direct[k]);
        }
    }
}
