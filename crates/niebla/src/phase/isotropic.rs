//! The isotropic phase function; pbrt-v2 `PhaseIsotropic`, pbrt-v4 section 11.3.

use super::ScatteringCosine;
use crate::math::INV_4PI;

/// Isotropic scattering: `p = 1 / (4 pi)` per steradian, mean cosine 0.
///
/// ```
/// use niebla::phase::Isotropic;
/// assert_eq!(Isotropic.eval_mu(0.3), 0.25 / std::f32::consts::PI);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Isotropic;

impl Isotropic {
    /// `p(mu) = 1 / (4 pi)`, 1/sr.
    #[inline]
    pub fn eval_mu(&self, _mu: f32) -> f32 {
        INV_4PI
    }

    /// `p` of a scattering cosine, 1/sr.
    #[inline]
    pub fn eval_cosine(&self, _c: ScatteringCosine) -> f32 {
        INV_4PI
    }

    /// Scattering cosine `mu = 2 u - 1` for `u` uniform in [0, 1).
    #[inline]
    pub fn sample_mu(&self, u: f32) -> f32 {
        self.sample_cosine(u).mu
    }

    /// Scattering cosine with its complements, `1 + mu = 2 u`.
    #[inline]
    pub fn sample_cosine(&self, u: f32) -> ScatteringCosine {
        ScatteringCosine::from_complements(2.0 * (1.0 - u), 2.0 * u)
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
    fn isotropic_sample_mu_is_linear_in_u() {
        assert_eq!(Isotropic.sample_mu(0.0), -1.0);
        assert_eq!(Isotropic.sample_mu(0.5), 0.0);
        assert!((Isotropic.sample_mu(0.75) - 0.5).abs() < 1e-7);
    }
}
