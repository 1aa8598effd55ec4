//! The airlight of Sun, Ramamoorthi, Narasimhan and Nayar 2005 ("A practical
//! analytic single scattering model for real time rendering", SIGGRAPH 2005):
//! single-scattered radiance from an isotropic point light in a homogeneous
//! medium along a ray segment, in closed form up to the special function
//!
//! `F(u, v) = integral_0^v exp(-u tan xi) dxi`,
//!
//! which is tabulated once ([`AirlightTable`]). Derivation (the paper's, with
//! separate `sigma_s` and `sigma_t` where it uses one coefficient for both):
//! with the foot of the perpendicular from the light at ray parameter `t_c`
//! and distance `h`, substitute `t - t_c = h tan(theta)` and
//! `xi = pi/4 + theta/2`; then `dt / d^2 = 2 dxi / h` and
//! `t + d = t_c + h tan(xi)`, so for an isotropic phase `1/(4 pi)`
//!
//! `L_a = sigma_s I exp(-sigma_t t_c) / (2 pi h) [F(sigma_t h, xi_b) - F(sigma_t h, xi_a)]`,
//! `xi_x = pi/4 + atan((t_x - t_c)/h)/2`.
//!
//! Table: `F` and `dF/du` on 257 x 257 nodes, `u = 32 (i/256)^2` (dense near
//! 0, where `F(u, pi/2)` has a `u ln u` term) and `v` uniform on `[0, pi/2]`,
//! each entry integrated with graded Gauss-Legendre panels to ~1e-14.
//! Lookups are bicubic Hermite: in `v` with the exact derivatives
//! `dF/dv = exp(-u tan v)` and `d(dF/du)/dv = -tan v exp(-u tan v)`, in `u`
//! with the tabulated `dF/du` (linear in the first `u` cell, where `dF/du`
//! is unbounded at `v = pi/2`). Beyond `u = 32` the asymptotic series
//! `F = int_0^{tan v} exp(-u t) (1 - t^2 + t^4) dt` is used (relative error
//! ~`720/u^6`, 7e-7 at the joint). Measured error of the whole lookup (test
//! `f_table_matches_quadrature`): 2.2e-6 relative to `F(u, pi/2)` at worst,
//! at `u < 0.01`, `v = pi/2` (the `u ln u` corner); elsewhere below 1e-6.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
use std::sync::OnceLock;

/// Number of `u` cells of the table.
const N_U: usize = 256;
/// Number of `v` cells of the table.
const N_V: usize = 256;
/// Largest tabulated `u`; beyond it the asymptotic series is used.
pub const U_MAX: f64 = 32.0;

/// `F(u, v)` and `dF/du(u, v)` tabulated once (Sun et al. 2005, their eq. 10).
#[derive(Debug)]
pub struct AirlightTable {
    /// `F(u_i, v_j)` at `i * (N_V + 1) + j`.
    f: Vec<f64>,
    /// `dF/du(u_i, v_j)` (unused for `i = 0`).
    f_u: Vec<f64>,
}

/// 8-point Gauss-Legendre nodes on [-1, 1] (positive half) and weights.
const GL8: [(f64, f64); 4] = [
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// Gauss-Legendre integral of `f` over `[a, b]` (8 points).
fn gl8(f: &impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let (m, r) = (0.5 * (a + b), 0.5 * (b - a));
    GL8.iter().map(|&(x, w)| w * (f(m - r * x) + f(m + r * x))).sum::<f64>() * r
}

/// Integral of `f` over `[a, b]`: 4 uniform panels, plus panels graded
/// geometrically toward `b` when `b = pi/2` (where `tan` blows up).
fn integrate_cell(f: &impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    if b < FRAC_PI_2 {
        let h = (b - a) / 4.0;
        return (0..4).map(|k| gl8(f, a + k as f64 * h, a + (k + 1) as f64 * h)).sum();
    }
    let mut sum = 0.0;
    let (mut lo, mut width) = (a, b - a);
    for _ in 0..60 {
        width *= 0.5;
        sum += gl8(f, lo, b - width);
        lo = b - width;
    }
    sum
}

/// `exp(-u tan v)`, the `v` derivative of `F` (1 at `u = 0`, 0 at `v = pi/2`).
#[inline]
fn dfdv(u: f64, v: f64) -> f64 {
    if u == 0.0 {
        1.0
    } else if v >= FRAC_PI_2 {
        0.0
    } else {
        (-u * v.tan()).exp()
    }
}

/// `-tan v exp(-u tan v)`, the `v` derivative of `dF/du`.
#[inline]
fn dfudv(u: f64, v: f64) -> f64 {
    if v >= FRAC_PI_2 {
        if u == 0.0 {
            f64::NEG_INFINITY
        } else {
            0.0
        }
    } else {
        let t = v.tan();
        -t * (-u * t).exp()
    }
}

#[inline]
fn u_node(i: usize) -> f64 {
    let s = i as f64 / N_U as f64;
    U_MAX * s * s
}

#[inline]
fn v_node(j: usize) -> f64 {
    FRAC_PI_2 * j as f64 / N_V as f64
}

/// Cubic Hermite on `[0, 1]` with values `p0, p1` and slopes (times the
/// interval length) `m0, m1`.
#[inline]
fn hermite(t: f64, p0: f64, m0: f64, p1: f64, m1: f64) -> f64 {
    let (t2, t3) = (t * t, t * t * t);
    (2.0 * t3 - 3.0 * t2 + 1.0) * p0 + (t3 - 2.0 * t2 + t) * m0 + (-2.0 * t3 + 3.0 * t2) * p1 + (t3 - t2) * m1
}

impl AirlightTable {
    /// Integrate the table (done once per process; see [`airlight_table`]).
    pub fn new() -> AirlightTable {
        let stride = N_V + 1;
        let mut f = vec![0.0; (N_U + 1) * stride];
        let mut f_u = vec![0.0; (N_U + 1) * stride];
        for i in 0..=N_U {
            let u = u_node(i);
            let value = |xi: f64| dfdv(u, xi);
            let derivative = |xi: f64| if xi >= FRAC_PI_2 { 0.0 } else { dfudv(u, xi) };
            let (mut acc, mut acc_u) = (0.0, 0.0);
            for j in 1..=N_V {
                let (a, b) = (v_node(j - 1), v_node(j));
                acc += integrate_cell(&value, a, b);
                acc_u += integrate_cell(&derivative, a, b);
                f[i * stride + j] = acc;
                f_u[i * stride + j] = acc_u;
            }
        }
        AirlightTable { f, f_u }
    }

    /// `F(u_i, v)` and `dF/du(u_i, v)` at node row `i` by Hermite in `v`.
    #[inline]
    fn row(&self, i: usize, v: f64) -> (f64, f64) {
        let stride = N_V + 1;
        let s = (v / FRAC_PI_2 * N_V as f64).clamp(0.0, N_V as f64);
        let j = (s as usize).min(N_V - 1);
        let t = s - j as f64;
        let (v0, v1) = (v_node(j), v_node(j + 1));
        let dv = v1 - v0;
        let u = u_node(i);
        let k = i * stride + j;
        let value = hermite(t, self.f[k], dv * dfdv(u, v0), self.f[k + 1], dv * dfdv(u, v1));
        let slope =
            if i == 0 { 0.0 } else { hermite(t, self.f_u[k], dv * dfudv(u, v0), self.f_u[k + 1], dv * dfudv(u, v1)) };
        (value, slope)
    }

    /// `F(u, v) = integral_0^v exp(-u tan xi) dxi` for `u >= 0`, `v` in `[0, pi/2]`.
    pub fn f(&self, u: f64, v: f64) -> f64 {
        debug_assert!(u >= 0.0, "F(u, v) needs u >= 0, got {u}");
        let v = v.clamp(0.0, FRAC_PI_2);
        if u >= U_MAX {
            return f_asymptotic(u, v);
        }
        let s = (u / U_MAX).sqrt() * N_U as f64;
        let i = (s as usize).min(N_U - 1);
        let (u0, u1) = (u_node(i), u_node(i + 1));
        let t = (u - u0) / (u1 - u0);
        let (f0, d0) = self.row(i, v);
        let (f1, d1) = self.row(i + 1, v);
        if i == 0 {
            f0 + t * (f1 - f0)
        } else {
            let du = u1 - u0;
            hermite(t, f0, du * d0, f1, du * d1)
        }
    }
}

impl Default for AirlightTable {
    fn default() -> AirlightTable {
        AirlightTable::new()
    }
}

/// The process-wide table, integrated on first use.
pub fn airlight_table() -> &'static AirlightTable {
    static TABLE: OnceLock<AirlightTable> = OnceLock::new();
    TABLE.get_or_init(AirlightTable::new)
}

/// Asymptotic `F` for large `u`: with `t = tan xi`,
/// `F = int_0^T exp(-u t) / (1 + t^2) dt ~ int_0^T exp(-u t) (1 - t^2 + t^4) dt`,
/// `T = tan v`, each term an incomplete gamma function
/// `(2n)!/u^(2n+1) P(2n+1, u T)`. The usual asymptote is the first term alone,
/// `(1 - exp(-u v))/u` (relative error ~`2/u^2`); with three terms the
/// relative error is ~`720/u^6` (7e-7 at `u = 32`).
pub fn f_asymptotic(u: f64, v: f64) -> f64 {
    let x = if v >= FRAC_PI_2 { f64::INFINITY } else { u * v.tan() };
    // P(n, x) = 1 - exp(-x) sum_{k < n} x^k / k!
    let regularized = |n: usize| {
        if !x.is_finite() {
            return 1.0;
        }
        let (mut term, mut sum) = (1.0, 1.0);
        for k in 1..n {
            term *= x / k as f64;
            sum += term;
        }
        1.0 - (-x).exp() * sum
    };
    regularized(1) / u - 2.0 / (u * u * u) * regularized(3) + 24.0 / u.powi(5) * regularized(5)
}

/// Airlight over `[t_a, t_b]` (`t_b` may be infinite) of a ray from a unit
/// isotropic point light at closest-approach parameter `t_c` and distance
/// `h > 0`, per unit `sigma_s I p`, where `p` is the phase value (`1/(4 pi)`
/// isotropic): `int_{t_a}^{t_b} exp(-sigma_t (t + d(t))) / d(t)^2 dt`, with
/// `d(t)^2 = h^2 + (t - t_c)^2`.
///
/// Uses the tabulated `F` except where the prefactor `exp(-sigma_t t_c)`
/// would amplify the table's absolute error (the segment lies more than 6
/// mean free paths of optical detour past the closest approach); there it
/// integrates the same expression with the exponent combined (Gauss-Legendre
/// in `w = u (tan xi - tan xi_a)`), which is well conditioned.
pub fn airlight_integral(table: &AirlightTable, sigma_t: f64, h: f64, t_c: f64, t_a: f64, t_b: f64) -> f64 {
    if !(t_b > t_a) || !(h > 0.0) {
        return 0.0;
    }
    let u = sigma_t * h;
    let xi_a = FRAC_PI_4 + 0.5 * ((t_a - t_c) / h).atan();
    let xi_b = if t_b.is_finite() { FRAC_PI_4 + 0.5 * ((t_b - t_c) / h).atan() } else { FRAC_PI_2 };
    let d_a = (h * h + (t_a - t_c) * (t_a - t_c)).sqrt();
    // Exponent of the prefactor relative to the integrand's largest value.
    let amplification = sigma_t * (t_a + d_a - t_c);
    if amplification <= 6.0 {
        let difference = table.f(u, xi_b) - table.f(u, xi_a);
        return (2.0 / h) * (-sigma_t * t_c).exp() * difference.max(0.0);
    }
    // exp(-sigma_t (t_c + h tan xi)) = exp(-sigma_t (t_a + d_a)) exp(-w),
    // dxi = dw / (u sec^2 xi), tan xi = tan xi_a + w / u.
    let tan_a = xi_a.tan();
    let w_max = if xi_b >= FRAC_PI_2 { 60.0 } else { (u * (xi_b.tan() - tan_a)).min(60.0) };
    let integrand = |w: f64| {
        let tan = tan_a + w / u;
        (-w).exp() / (u * (1.0 + tan * tan))
    };
    let edges: [f64; 6] = [0.0, 0.5, 2.0, 6.0, 16.0, 60.0];
    let mut sum = 0.0;
    for pair in edges.windows(2) {
        let (lo, hi) = (pair[0], pair[1].min(w_max));
        if hi > lo {
            sum += gl8(&integrand, lo, hi);
        }
    }
    (2.0 / h) * (-sigma_t * (t_a + d_a)).exp() * sum
}

/// `1/(4 pi)`, the isotropic phase function.
pub const INV_FOUR_PI: f64 = 0.25 / PI;

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference `F` by dense composite Gauss-Legendre in `t = tan xi`
    /// pieces (independent of the table's cells).
    fn f_reference(u: f64, v: f64) -> f64 {
        let n = 4000;
        let f = |xi: f64| dfdv(u, xi);
        let mut sum = 0.0;
        for k in 0..n {
            let (a, b) = (v * k as f64 / n as f64, v * (k + 1) as f64 / n as f64);
            sum += if b >= FRAC_PI_2 { integrate_cell(&f, a, b) } else { gl8(&f, a, b) };
        }
        sum
    }

    #[test]
    fn f_of_zero_u_is_v() {
        let table = AirlightTable::new();
        for v in [0.0, 0.3, 1.0, 1.5, FRAC_PI_2] {
            assert!((table.f(0.0, v) - v).abs() < 1e-12);
        }
    }

    /// The tabulated `F` against quadrature over `u` in [0, 60] (table and
    /// asymptote) and `v` in [0, pi/2]; error relative to `F(u, pi/2)`.
    #[test]
    fn f_table_matches_quadrature() {
        let table = AirlightTable::new();
        let mut worst: f64 = 0.0;
        let mut state = 12345u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 0..600 {
            let u = if k % 3 == 0 { 60.0 * next() } else { 4.0 * next() * next() };
            let v = if k % 5 == 0 { FRAC_PI_2 } else { FRAC_PI_2 * next() };
            let reference = f_reference(u, v);
            let scale = f_reference(u, FRAC_PI_2);
            let error = (table.f(u, v) - reference).abs() / scale;
            worst = worst.max(error);
        }
        assert!(worst < 5e-6, "worst error {worst:.3e}");
        println!("F table: worst error {worst:.2e} relative to F(u, pi/2)");
    }

    /// The asymptotic branch is continuous with the table at `u = U_MAX`.
    #[test]
    fn asymptote_joins_the_table() {
        let table = AirlightTable::new();
        for v in [0.05, 0.2, 0.8, FRAC_PI_2] {
            let inside = table.f(U_MAX - 1e-9, v);
            let outside = f_asymptotic(U_MAX, v);
            assert!((inside - outside).abs() < 2e-6 * inside, "v {v}: {inside} vs {outside}");
        }
    }

    /// Closed form against direct quadrature in `t`, including segments far
    /// past the closest approach (the well-conditioned branch).
    #[test]
    fn airlight_integral_matches_quadrature_in_t() {
        let table = AirlightTable::new();
        let cases = [
            (0.5, 1.0, 2.0, 0.0, 4.0),
            (2.0, 0.3, -1.0, 0.0, 6.0),
            (1.0, 0.5, -20.0, 0.0, 10.0),
            (0.1, 2.0, 3.0, 1.0, 30.0),
            (3.0, 0.05, 1.0, 0.5, 1.5),
        ];
        for (sigma_t, h, t_c, t_a, t_b) in cases {
            let f = |t: f64| {
                let d2 = h * h + (t - t_c) * (t - t_c);
                (-sigma_t * (t + d2.sqrt())).exp() / d2
            };
            let n = 20000;
            let mut reference = 0.0;
            for k in 0..n {
                let (a, b) = (t_a + (t_b - t_a) * k as f64 / n as f64, t_a + (t_b - t_a) * (k + 1) as f64 / n as f64);
                reference += gl8(&f, a, b);
            }
            let value = airlight_integral(&table, sigma_t, h, t_c, t_a, t_b);
            assert!((value - reference).abs() < 1e-6 * reference, "{sigma_t} {h} {t_c}: {value:e} vs {reference:e}");
        }
    }
}
