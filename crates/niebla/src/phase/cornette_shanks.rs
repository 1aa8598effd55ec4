//! Cornette and Shanks (1992), "Physically reasonable analytic expression for
//! the single-scattering phase function", Applied Optics 31(16): HG times a Rayleigh-like `(1 + mu^2)`
//! factor, renormalized; its mean cosine is `3 g (4 + g^2) / (5 (2 + g^2))`,
//! not `g`. Sampled by rejection against HG (the ratio `p_CS / p_HG` is
//! bounded by `3 / (2 + g^2)`).

use super::error::{check_open_unit, PhaseError};
use super::hg::{hg_eval, HenyeyGreenstein};
use super::ScatteringCosine;
use crate::math::Vec2;
use crate::sampling::{hash_u64, PixelSampler};

/// Most candidates drawn by the rejection sampler. Each is accepted with
/// probability `(2 + g^2) / 3 >= 2/3`, so all 64 fail with probability
/// below `3^-64 = 3e-31`.
const MAX_REJECTION_ATTEMPTS: u32 = 64;

/// Cornette-Shanks phase function, Henyey-Greenstein times a Rayleigh-like
/// factor, renormalized:
/// `p(mu) = 3 (1 - g^2)(1 + mu^2) / (8 pi (2 + g^2)(1 + g^2 - 2 g mu)^1.5)`
/// per steradian, i.e. `p = 3 (1 + mu^2) / (2 (2 + g^2)) HG_g(mu)`.
///
/// `g` is the HG parameter, not the mean cosine: that is
/// `3 g (4 + g^2) / (5 (2 + g^2))` (g = 0.76 gives 0.810).
///
/// Sampling is exact by rejection: draw `mu` from HG(g) and accept it with
/// probability `(1 + mu^2) / 2`; the accepted density is exactly `p`, so
/// `pdf == eval`. The first candidate uses `u` itself; the acceptance test and
/// any further candidates use a counter-based stream keyed by the bits of the
/// caller's uniform numbers (deterministic, no state).
///
/// ```
/// use niebla::phase::CornetteShanks;
/// let cs = CornetteShanks::new(0.76).unwrap();
/// assert!((cs.mean_cosine() - 0.810).abs() < 1e-3);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CornetteShanks {
    /// HG lobe used as the rejection envelope (its g is this function's g).
    hg: HenyeyGreenstein,
    /// `3 / (2 (2 + g^2))`.
    factor: f32,
}

impl CornetteShanks {
    /// Cornette-Shanks with HG parameter `g` in (-1, 1), clamped like
    /// [`HenyeyGreenstein::new`] to +-0.99.
    pub fn new(g: f32) -> Result<CornetteShanks, PhaseError> {
        let hg = HenyeyGreenstein::new(check_open_unit("g", g)?)?;
        let g = hg.g();
        Ok(CornetteShanks { hg, factor: 3.0 / (2.0 * (2.0 + g * g)) })
    }

    /// The HG parameter g in use (after clamping).
    pub fn g(&self) -> f32 {
        self.hg.g()
    }

    /// `p(mu)`, 1/sr.
    #[inline]
    pub fn eval_mu(&self, mu: f32) -> f32 {
        self.eval_cosine(ScatteringCosine::from_mu(mu))
    }

    /// `p` of a scattering cosine, 1/sr.
    #[inline]
    pub fn eval_cosine(&self, c: ScatteringCosine) -> f32 {
        self.factor * (1.0 + c.mu * c.mu) * hg_eval(self.hg.g(), c)
    }

    /// Scattering cosine from one uniform number (the rejection stream is
    /// keyed by its bits); `None` with probability below 3e-31.
    pub fn sample_mu(&self, u: f32) -> Option<f32> {
        self.sample_cosine(u, hash_u64(u.to_bits() as u64)).map(|c| c.mu)
    }

    /// Rejection sampling against HG: first candidate from `u`, acceptance
    /// numbers and later candidates from the stream `PixelSampler::from_key(key)`.
    #[inline]
    pub fn sample_cosine(&self, u: f32, key: u64) -> Option<ScatteringCosine> {
        let mut stream = PixelSampler::from_key(key);
        let mut candidate_u = u;
        for _ in 0..MAX_REJECTION_ATTEMPTS {
            let c = self.hg.sample_cosine(candidate_u);
            if 2.0 * stream.next_1d() < 1.0 + c.mu * c.mu {
                return Some(c);
            }
            candidate_u = stream.next_1d();
        }
        None
    }

    /// Mean cosine, `3 g (4 + g^2) / (5 (2 + g^2))`.
    pub fn mean_cosine(&self) -> f32 {
        let g = self.hg.g();
        3.0 * g * (4.0 + g * g) / (5.0 * (2.0 + g * g))
    }
}

/// Key of the rejection stream for a 2D sample `u`: both coordinates' bits.
#[inline]
pub(crate) fn rejection_key(u: Vec2) -> u64 {
    ((u.x.to_bits() as u64) << 32) | u.y.to_bits() as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cornette_shanks_matches_published_formula() {
        for g in [-0.5f32, 0.0, 0.76] {
            let cs = CornetteShanks::new(g).unwrap();
            for mu in [-1.0f32, -0.3, 0.0, 0.6, 1.0] {
                let (g, m) = (g as f64, mu as f64);
                let expected = 3.0 * (1.0 - g * g) * (1.0 + m * m)
                    / (8.0 * std::f64::consts::PI * (2.0 + g * g) * (1.0 + g * g - 2.0 * g * m).powf(1.5));
                assert!((cs.eval_mu(mu) as f64 / expected - 1.0).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn cornette_shanks_at_g0_is_rayleigh() {
        let cs = CornetteShanks::new(0.0).unwrap();
        for mu in [-1.0f32, 0.0, 0.5] {
            let r = super::super::Rayleigh.eval_mu(mu);
            assert!((cs.eval_mu(mu) / r - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn cornette_shanks_sample_mu_is_deterministic_in_u() {
        let cs = CornetteShanks::new(0.7).unwrap();
        assert_eq!(cs.sample_mu(0.37), cs.sample_mu(0.37));
    }
}
