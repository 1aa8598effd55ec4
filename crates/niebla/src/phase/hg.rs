//! Henyey-Greenstein (1941); pbrt-v4 section 11.3.1 and `util/scattering.h`.

use super::error::{check_open_unit, PhaseError};
use super::ScatteringCosine;
use crate::math::INV_4PI;

/// Largest `|g|` used: `new` accepts any `g` in (-1, 1) and clamps it to
/// [-0.99, 0.99], as pbrt-v4 does in `HGPhaseFunction` (the lobe of g = 0.99
/// is already about 0.6 degrees wide and peaks at 1600/sr).
pub const MAX_HG_ASYMMETRY: f32 = 0.99;

/// Henyey-Greenstein phase function,
/// `p(mu) = (1 - g^2) / (4 pi (1 + g^2 - 2 g mu)^1.5)` per steradian with
/// `mu = -dot(wo, wi)` (module convention); mean cosine `g`.
///
/// ```
/// use niebla::phase::HenyeyGreenstein;
/// let hg = HenyeyGreenstein::new(0.5).unwrap();
/// // p(1) = (1 - g^2) / (4 pi (1 - g)^3) = 0.75 / (4 pi 0.125)
/// assert!((hg.eval_mu(1.0) - 6.0 / (4.0 * std::f32::consts::PI)).abs() < 1e-5);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HenyeyGreenstein {
    /// Asymmetry g in [-0.99, 0.99] (after clamping); g > 0 scatters forward.
    g: f32,
}

impl HenyeyGreenstein {
    /// HG with asymmetry `g` in (-1, 1), clamped to `+-`[`MAX_HG_ASYMMETRY`].
    /// Errors on `|g| >= 1` or NaN.
    pub fn new(g: f32) -> Result<HenyeyGreenstein, PhaseError> {
        let g = check_open_unit("g", g)?;
        Ok(HenyeyGreenstein { g: g.clamp(-MAX_HG_ASYMMETRY, MAX_HG_ASYMMETRY) })
    }

    /// HG whose parameter name in error messages is `name` (for lobes of mixtures).
    pub(crate) fn new_named(name: &'static str, g: f32) -> Result<HenyeyGreenstein, PhaseError> {
        let g = check_open_unit(name, g)?;
        Ok(HenyeyGreenstein { g: g.clamp(-MAX_HG_ASYMMETRY, MAX_HG_ASYMMETRY) })
    }

    /// The asymmetry in use (after clamping), which is also the mean cosine.
    pub fn g(&self) -> f32 {
        self.g
    }

    /// `p(mu)`, 1/sr.
    #[inline]
    pub fn eval_mu(&self, mu: f32) -> f32 {
        self.eval_cosine(ScatteringCosine::from_mu(mu))
    }

    /// `p` of a scattering cosine, 1/sr.
    #[inline]
    pub fn eval_cosine(&self, c: ScatteringCosine) -> f32 {
        hg_eval(self.g, c)
    }

    /// Scattering cosine by inversion of the CDF; pbrt-v4 `SampleHenyeyGreenstein`
    /// with `u = 0` giving backward (`mu = -1`) and `u -> 1` forward.
    #[inline]
    pub fn sample_mu(&self, u: f32) -> f32 {
        self.sample_cosine(u).mu
    }

    /// Inversion of the CDF with `1 - mu` and `1 + mu` in cancellation-free form.
    ///
    /// With `d = 1 - g + 2 g u` and `s = (1 - g^2) / d` (so that
    /// `mu = (1 + g^2 - s^2) / (2 g)`, the inverse CDF of HG in `mu`):
    /// `1 - mu = (1 - g)(1 - u)(s + 1 - g) / d`, `1 + mu = (1 + g) u (1 + g + s) / d`.
    /// No division by `g`, so `g = 0` needs no special case.
    #[inline]
    pub fn sample_cosine(&self, u: f32) -> ScatteringCosine {
        let g = self.g;
        let d = 1.0 - g + 2.0 * g * u;
        let s = (1.0 - g) * (1.0 + g) / d;
        let one_minus_mu = (1.0 - g) * (1.0 - u) * (s + 1.0 - g) / d;
        let one_plus_mu = (1.0 + g) * u * (1.0 + g + s) / d;
        ScatteringCosine::from_complements(one_minus_mu, one_plus_mu)
    }

    /// Mean cosine, `g`.
    pub fn mean_cosine(&self) -> f32 {
        self.g
    }
}

/// HG value for asymmetry `g` (no clamping), 1/sr. The denominator
/// `1 + g^2 - 2 g mu` is written as `(1 - g)^2 + 2 g (1 - mu)` for g >= 0 and
/// `(1 + g)^2 - 2 g (1 + mu)` for g < 0: a sum of non-negative terms.
#[inline]
pub(crate) fn hg_eval(g: f32, c: ScatteringCosine) -> f32 {
    let denom = if g >= 0.0 {
        (1.0 - g) * (1.0 - g) + 2.0 * g * c.one_minus_mu
    } else {
        (1.0 + g) * (1.0 + g) - 2.0 * g * c.one_plus_mu
    };
    (1.0 - g) * (1.0 + g) * INV_4PI / (denom * denom.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hg_matches_textbook_formula_in_mu() {
        for g in [-0.8f32, -0.3, 0.0, 0.4, 0.9] {
            let hg = HenyeyGreenstein::new(g).unwrap();
            for mu in [-1.0f32, -0.5, 0.0, 0.3, 0.99, 1.0] {
                let g = g as f64;
                let mu64 = mu as f64;
                let expected = (1.0 - g * g) / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * mu64).powf(1.5));
                let got = hg.eval_mu(mu) as f64;
                assert!((got / expected - 1.0).abs() < 1e-5, "g {g} mu {mu}: {got} vs {expected}");
            }
        }
    }

    #[test]
    fn hg_sample_cosine_complements_add_to_two_and_invert_cdf() {
        // CDF of HG in mu: F(mu) = (1 - g^2) / (2 g) (1/s - 1/(1 + g)), s = sqrt(1 + g^2 - 2 g mu).
        for g in [-0.9f32, -0.2, 0.5, 0.99] {
            let hg = HenyeyGreenstein::new(g).unwrap();
            for u in [0.0f32, 0.1, 0.5, 0.9, 0.999_999] {
                let c = hg.sample_cosine(u);
                assert!((c.one_minus_mu + c.one_plus_mu - 2.0).abs() < 1e-6);
                let g = g as f64;
                let s = (1.0 + g * g - 2.0 * g * c.mu_f64()).sqrt();
                let cdf = (1.0 - g * g) / (2.0 * g) * (1.0 / s - 1.0 / (1.0 + g));
                assert!((cdf - u as f64).abs() < 1e-4, "g {g} u {u}: F = {cdf}");
            }
        }
    }

    #[test]
    fn hg_rejects_g_outside_open_unit_interval_and_clamps_to_099() {
        for g in [1.0f32, -1.0, 1.5, f32::NAN] {
            assert!(HenyeyGreenstein::new(g).is_err());
        }
        assert_eq!(HenyeyGreenstein::new(0.999).unwrap().g(), MAX_HG_ASYMMETRY);
        assert_eq!(HenyeyGreenstein::new(-0.995).unwrap().g(), -MAX_HG_ASYMMETRY);
    }
}
