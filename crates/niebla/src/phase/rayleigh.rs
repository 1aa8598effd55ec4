//! Rayleigh scattering (unpolarized); pbrt-v2 `PhaseRayleigh`; sampling by
//! Cardano's formula, cf. Frisvad 2011, "Importance sampling the Rayleigh
//! phase function", JOSA A: `z = 2 (2 u - 1)`, `A = cbrt(z + sqrt(z^2 + 1))`,
//! `mu = A - 1/A`.

use super::ScatteringCosine;
use crate::math::PI;

/// Rayleigh phase function, `p(mu) = 3 (1 + mu^2) / (16 pi)` per steradian
/// (small particles, sigma_s ~ lambda^-4); mean cosine 0.
///
/// ```
/// use niebla::phase::Rayleigh;
/// let p = Rayleigh;
/// assert!((p.eval_mu(1.0) / p.eval_mu(0.0) - 2.0).abs() < 1e-6);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rayleigh;

impl Rayleigh {
    /// `p(mu)`, 1/sr.
    #[inline]
    pub fn eval_mu(&self, mu: f32) -> f32 {
        self.eval_cosine(ScatteringCosine::from_mu(mu))
    }

    /// `p` of a scattering cosine, 1/sr.
    #[inline]
    pub fn eval_cosine(&self, c: ScatteringCosine) -> f32 {
        3.0 / (16.0 * PI) * (1.0 + c.mu * c.mu)
    }

    /// Scattering cosine by exact inversion of the CDF
    /// `F(mu) = (mu^3 + 3 mu + 4) / 8`: with `z = 2 (2u - 1)` and
    /// `A = cbrt(z + sqrt(z^2 + 1))`, `mu = A - 1/A` (Cardano).
    #[inline]
    pub fn sample_mu(&self, u: f32) -> f32 {
        self.sample_cosine(u).mu
    }

    /// Scattering cosine with its complements, computed in f64.
    #[inline]
    pub fn sample_cosine(&self, u: f32) -> ScatteringCosine {
        let z = 2.0 * (2.0 * u as f64 - 1.0);
        // z + sqrt(z^2 + 1) = 1 / (sqrt(z^2 + 1) - z): use the form without cancellation.
        let root = (z * z + 1.0).sqrt();
        let sum = if z >= 0.0 { z + root } else { 1.0 / (root - z) };
        let a = sum.cbrt();
        let mu = (a - 1.0 / a).clamp(-1.0, 1.0);
        ScatteringCosine::from_complements((1.0 - mu) as f32, (1.0 + mu) as f32)
    }

    /// Mean cosine, 0.
    pub fn mean_cosine(&self) -> f32 {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rayleigh_cardano_inverts_cdf() {
        for u in [0.0f32, 0.01, 0.25, 0.5, 0.75, 0.999] {
            let mu = Rayleigh.sample_cosine(u).mu_f64();
            let cdf = (mu * mu * mu + 3.0 * mu + 4.0) / 8.0;
            assert!((cdf - u as f64).abs() < 1e-6, "u {u}: F = {cdf}");
        }
    }
}
