//! Thin dielectric: Mitsuba 3's `thindielectric`, a sheet of glass of
//! negligible thickness (a window, a soap film). Light reflects with the
//! sheet's total reflectance, the sum over the inter-reflections inside it,
//! `R' = R + T R T + T R^3 T + ... = 2 R / (1 + R)`, and otherwise passes
//! straight through (`wi = -wo`, no refraction). Both lobes are deltas.

use super::fresnel::fresnel_dielectric;
use crate::color::Rgb;
use crate::math::Vec3;

/// A thin glass sheet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectric {
    /// Relative index `ior_inside / ior_outside` of the sheet's material, > 0.
    pub eta: f32,
    /// Multiplier of the reflection (default 1).
    pub specular_reflectance: Rgb,
    /// Multiplier of the transmission (default 1).
    pub specular_transmittance: Rgb,
}

impl ThinDielectric {
    /// Total reflectance of the sheet at local incidence cosine `cos_o`
    /// (either side): `2 R / (1 + R)` with `R` the single-interface Fresnel
    /// reflectance.
    #[inline]
    pub fn reflectance(&self, cos_o: f32) -> f32 {
        let r = fresnel_dielectric(cos_o.abs(), self.eta);
        r * 2.0 / (1.0 + r)
    }

    /// Probability `1 - R'` that light at local incidence cosine `cos_o`
    /// (either side) passes the sheet straight through.
    #[inline]
    pub fn pass_probability(&self, cos_o: f32) -> f32 {
        1.0 - self.reflectance(cos_o)
    }

    /// Choose reflection (`u_lobe < R'`) or transmission: `(wi, weight
    /// f |cos| / pdf, pdf, transmitted)` in the local frame.
    #[inline]
    pub(super) fn sample_local(&self, wo: Vec3, u_lobe: f32) -> Option<(Vec3, Rgb, f32, bool)> {
        if wo.z == 0.0 {
            return None;
        }
        let r = self.reflectance(wo.z);
        if u_lobe < r {
            Some((Vec3::new(-wo.x, -wo.y, wo.z), self.specular_reflectance, r, false))
        } else {
            Some((-wo, self.specular_transmittance, 1.0 - r, true))
        }
    }
}
