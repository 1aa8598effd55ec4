//! Schlick's phase function (Blasi, Le Saec, Schlick 1993); pbrt-v2
//! `PhaseSchlick`: `(1 - k^2) / (4 pi (1 - k mu)^2)`, sampled in closed form
//! by `mu = (2 u + k - 1) / (2 k u - k + 1)`. Its `k` is not the mean cosine.

use super::error::{check_open_unit, PhaseError};
use super::ScatteringCosine;
use crate::math::INV_4PI;

/// Schlick's rational approximation of Henyey-Greenstein,
/// `p(mu) = (1 - k^2) / (4 pi (1 - k mu)^2)` per steradian, `k` in (-1, 1),
/// `k > 0` forward. `k` is NOT the mean cosine: that is
/// [`schlick_mean_cosine`]`(k) = 1/k - (1 - k^2) atanh(k) / k^2`
/// (`2k/3 + 2k^3/15 + ...` for small k). Use [`k_from_g`] for pbrt-v2's
/// approximate mapping or [`Schlick::with_mean_cosine`] for an exact one.
///
/// ```
/// use niebla::phase::Schlick;
/// let s = Schlick::with_mean_cosine(0.76).unwrap();
/// assert!((s.mean_cosine() - 0.76).abs() < 1e-5);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schlick {
    /// Parameter k in (-1, 1); k > 0 scatters forward.
    k: f32,
}

impl Schlick {
    /// Schlick with parameter `k` in (-1, 1).
    pub fn new(k: f32) -> Result<Schlick, PhaseError> {
        Ok(Schlick { k: check_open_unit("k", k)? })
    }

    /// Schlick whose mean cosine is exactly `g` (to f32 precision), with `k`
    /// from [`k_for_mean_cosine`].
    pub fn with_mean_cosine(g: f32) -> Result<Schlick, PhaseError> {
        Schlick::new(k_for_mean_cosine(g)?)
    }

    /// The parameter k.
    pub fn k(&self) -> f32 {
        self.k
    }

    /// `p(mu)`, 1/sr.
    #[inline]
    pub fn eval_mu(&self, mu: f32) -> f32 {
        self.eval_cosine(ScatteringCosine::from_mu(mu))
    }

    /// `p` of a scattering cosine, 1/sr; `1 - k mu` is written as
    /// `(1 - k) + k (1 - mu)` for k >= 0 and `(1 + k) - k (1 + mu)` for k < 0.
    #[inline]
    pub fn eval_cosine(&self, c: ScatteringCosine) -> f32 {
        let k = self.k;
        let denom = if k >= 0.0 { (1.0 - k) + k * c.one_minus_mu } else { (1.0 + k) - k * c.one_plus_mu };
        (1.0 - k) * (1.0 + k) * INV_4PI / (denom * denom)
    }

    /// Scattering cosine by exact inversion of the CDF,
    /// `mu = (2u + k - 1) / (2ku - k + 1)` (u = 0 backward, u -> 1 forward).
    #[inline]
    pub fn sample_mu(&self, u: f32) -> f32 {
        self.sample_cosine(u).mu
    }

    /// Inversion with `d = 1 - k + 2ku`: `1 - mu = 2 (1 - k)(1 - u) / d`,
    /// `1 + mu = 2 (1 + k) u / d`.
    #[inline]
    pub fn sample_cosine(&self, u: f32) -> ScatteringCosine {
        let k = self.k;
        let d = 1.0 - k + 2.0 * k * u;
        ScatteringCosine::from_complements(2.0 * (1.0 - k) * (1.0 - u) / d, 2.0 * (1.0 + k) * u / d)
    }

    /// Mean cosine, [`schlick_mean_cosine`]`(k)`.
    pub fn mean_cosine(&self) -> f32 {
        schlick_mean_cosine(self.k as f64) as f32
    }
}

/// pbrt-v2's mapping from an asymmetry `g` to Schlick's `k`,
/// `k = 1.5 g - 0.5 g^3` (attributed there to Thies Heidecke). Approximate:
/// the resulting mean cosine for g = 0.3 / 0.76 / 0.9 is 0.303 / 0.799 / 0.942
/// (computed by quadrature); use [`k_for_mean_cosine`] for an exact match.
pub fn k_from_g(g: f32) -> f32 {
    1.5 * g - 0.5 * g * g * g
}

/// Mean cosine of Schlick's function with parameter `k` in (-1, 1):
/// `<mu> = 1/k - (1 - k^2) atanh(k) / k^2`, by the series
/// `sum over n >= 1 of 2 k^(2n-1) / (4n^2 - 1)` when `|k| < 0.05`.
pub fn schlick_mean_cosine(k: f64) -> f64 {
    if k.abs() < 0.05 {
        let k2 = k * k;
        let mut term = k;
        let mut sum = 0.0;
        for n in 1..=12 {
            let n = n as f64;
            sum += 2.0 * term / (4.0 * n * n - 1.0);
            term *= k2;
        }
        sum
    } else {
        1.0 / k - (1.0 - k * k) * k.atanh() / (k * k)
    }
}

/// The `k` whose Schlick function has mean cosine exactly `g` (solved by
/// bisection on the monotone [`schlick_mean_cosine`] in double precision, then
/// rounded to f32). `g` must be in (-1, 1).
///
/// ```
/// use niebla::phase::{k_for_mean_cosine, schlick_mean_cosine};
/// let k = k_for_mean_cosine(0.9).unwrap();
/// assert!((schlick_mean_cosine(k as f64) - 0.9).abs() < 1e-6);
/// ```
pub fn k_for_mean_cosine(g: f32) -> Result<f32, PhaseError> {
    let g = check_open_unit("g", g)? as f64;
    let (mut lo, mut hi) = (-1.0f64, 1.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if schlick_mean_cosine(mid) < g {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let k = (0.5 * (lo + hi)) as f32;
    // Keep k inside the open interval after rounding.
    Ok(k.clamp(-1.0 + f32::EPSILON, 1.0 - f32::EPSILON))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schlick_pbrt_v2_mapping_gives_methods_mean_cosines() {
        // g = 0.3 / 0.76 / 0.9 -> <mu> 0.303 / 0.799 / 0.942 (3 digits, by quadrature).
        for (g, expected) in [(0.3f32, 0.303), (0.76, 0.799), (0.9, 0.942)] {
            let m = schlick_mean_cosine(k_from_g(g) as f64);
            assert!((m - expected).abs() < 5e-4, "g {g}: <mu> = {m}");
        }
    }

    #[test]
    fn schlick_mean_cosine_series_and_closed_form_agree_at_switch() {
        // d<mu>/dk ~ 2/3, so the 2e-12 step moves <mu> by 1.3e-12; the closed
        // form loses ~1e-14 to cancellation at k = 0.05.
        let (a, b) = (schlick_mean_cosine(0.05 - 1e-12), schlick_mean_cosine(0.05 + 1e-12));
        assert!((b - a - 1.334e-12).abs() < 1e-13, "{a} vs {b}");
        assert!((schlick_mean_cosine(-0.3) + schlick_mean_cosine(0.3)).abs() < 1e-15);
    }

    #[test]
    fn k_for_mean_cosine_inverts_mean_cosine() {
        for g in [-0.95f32, -0.5, 0.0, 0.01, 0.3, 0.76, 0.9, 0.99] {
            let k = k_for_mean_cosine(g).unwrap();
            let m = schlick_mean_cosine(k as f64);
            // f32 rounding of k: |d<mu>/dk| <= 1.5 near |k| -> 1, times 6e-8.
            assert!((m - g as f64).abs() < 2e-7, "g {g}: k {k}, <mu> {m}");
        }
        assert!(k_for_mean_cosine(1.0).is_err());
    }

    #[test]
    fn schlick_sample_inverts_cdf() {
        // F(mu) = (1 - k^2) / (2k) (1 / (1 - k mu) - 1 / (1 + k)).
        for k in [-0.7f32, 0.4, 0.95] {
            let s = Schlick::new(k).unwrap();
            for u in [0.0f32, 0.2, 0.5, 0.8, 0.999] {
                let mu = s.sample_cosine(u).mu_f64();
                let k = k as f64;
                let cdf = (1.0 - k * k) / (2.0 * k) * (1.0 / (1.0 - k * mu) - 1.0 / (1.0 + k));
                assert!((cdf - u as f64).abs() < 1e-5, "k {k} u {u}: F = {cdf}");
            }
        }
    }
}
