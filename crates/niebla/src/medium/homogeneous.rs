use crate::color::Rgb;
use crate::phase::PhaseFunction;

use super::MediumPoint;

/// A medium with constant coefficients (per unit length) and constant emission.
#[derive(Clone, Debug)]
pub struct HomogeneousMedium {
    /// Absorption coefficient sigma_a (1/length).
    pub sigma_a: Rgb,
    /// Scattering coefficient sigma_s (1/length).
    pub sigma_s: Rgb,
    /// Emitted radiance per unit length L_ve.
    pub l_ve: Rgb,
    /// Phase function.
    pub phase: PhaseFunction,
}

impl HomogeneousMedium {
    /// Extinction sigma_t = sigma_a + sigma_s.
    #[inline]
    pub fn sigma_t(&self) -> Rgb {
        self.sigma_a + self.sigma_s
    }

    /// Coefficients at any point.
    #[inline]
    pub fn point(&self) -> MediumPoint {
        MediumPoint { sigma_a: self.sigma_a, sigma_s: self.sigma_s, l_ve: self.l_ve }
    }
}
