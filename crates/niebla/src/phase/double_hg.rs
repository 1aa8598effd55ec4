//! Double (two-term) Henyey-Greenstein, `w HG(g1) + (1 - w) HG(g2)` with mean
//! cosine `w g1 + (1 - w) g2` (common for clouds, smoke and fog; fitted to Mie in reference/mie_fog_fit.json).

use super::error::PhaseError;
use super::hg::HenyeyGreenstein;
use super::ScatteringCosine;

/// `p = w HG(g1) + (1 - w) HG(g2)` per steradian, usually `g1 > 0 > g2`
/// (forward lobe plus back lobe); mean cosine `w g1 + (1 - w) g2`.
/// Sampled exactly: choose a lobe with probability `w`, then sample it.
///
/// ```
/// use niebla::phase::DoubleHg;
/// let p = DoubleHg::new(0.8, 0.9, -0.5).unwrap();
/// assert!((p.mean_cosine() - (0.8 * 0.9 - 0.2 * 0.5)).abs() < 1e-6);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DoubleHg {
    /// Weight of the first lobe, in [0, 1].
    w: f32,
    /// First lobe.
    lobe1: HenyeyGreenstein,
    /// Second lobe.
    lobe2: HenyeyGreenstein,
}

impl DoubleHg {
    /// Mixture with weight `w` in [0, 1] of lobe `g1` and `1 - w` of lobe
    /// `g2`, each in (-1, 1) and clamped like [`HenyeyGreenstein::new`].
    pub fn new(w: f32, g1: f32, g2: f32) -> Result<DoubleHg, PhaseError> {
        if !(0.0..=1.0).contains(&w) {
            return Err(PhaseError::parameter("w", w, "0 <= w <= 1"));
        }
        Ok(DoubleHg { w, lobe1: HenyeyGreenstein::new_named("g1", g1)?, lobe2: HenyeyGreenstein::new_named("g2", g2)? })
    }

    /// Weight of the first lobe.
    pub fn w(&self) -> f32 {
        self.w
    }

    /// Asymmetry of the first lobe (after clamping).
    pub fn g1(&self) -> f32 {
        self.lobe1.g()
    }

    /// Asymmetry of the second lobe (after clamping).
    pub fn g2(&self) -> f32 {
        self.lobe2.g()
    }

    /// `p(mu)`, 1/sr.
    #[inline]
    pub fn eval_mu(&self, mu: f32) -> f32 {
        self.eval_cosine(ScatteringCosine::from_mu(mu))
    }

    /// `p` of a scattering cosine, 1/sr.
    #[inline]
    pub fn eval_cosine(&self, c: ScatteringCosine) -> f32 {
        self.w * self.lobe1.eval_cosine(c) + (1.0 - self.w) * self.lobe2.eval_cosine(c)
    }

    /// Scattering cosine; `u` selects the lobe and is then rescaled to [0, 1).
    #[inline]
    pub fn sample_mu(&self, u: f32) -> f32 {
        self.sample_cosine(u).mu
    }

    /// Scattering cosine with its complements (see [`DoubleHg::sample_mu`]).
    #[inline]
    pub fn sample_cosine(&self, u: f32) -> ScatteringCosine {
        if u < self.w {
            self.lobe1.sample_cosine(u / self.w)
        } else {
            let u = ((u - self.w) / (1.0 - self.w)).min(1.0 - f32::EPSILON / 2.0);
            self.lobe2.sample_cosine(u)
        }
    }

    /// Mean cosine, `w g1 + (1 - w) g2`.
    pub fn mean_cosine(&self) -> f32 {
        self.w * self.lobe1.g() + (1.0 - self.w) * self.lobe2.g()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn double_hg_with_equal_lobes_equals_single_hg() {
        let double = DoubleHg::new(0.3, 0.6, 0.6).unwrap();
        let single = HenyeyGreenstein::new(0.6).unwrap();
        for mu in [-1.0f32, -0.2, 0.5, 1.0] {
            assert!((double.eval_mu(mu) / single.eval_mu(mu) - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn double_hg_accepts_weights_zero_and_one() {
        for w in [0.0f32, 1.0] {
            let p = DoubleHg::new(w, 0.7, -0.4).unwrap();
            let c = p.sample_cosine(0.999_999);
            assert!(c.mu >= -1.0 && c.mu <= 1.0);
        }
    }
}
