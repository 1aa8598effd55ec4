//! Rough conductor: Mitsuba 3's `roughconductor` (Walter et al. 2007 with a
//! complex-index Fresnel term), one-sided, sampled by visible normals.
//! Local frame: `+z` is the outward normal; `wo` toward the camera, `wi`
//! toward the light (Mitsuba's `si.wi` and `wo` respectively).

use super::fresnel::{fresnel_complex, reflect};
use super::microfacet::Microfacet;
use crate::color::Rgb;
use crate::math::{Vec2, Vec3};

/// A rough metal: microfacet reflection with the conductor Fresnel term of
/// complex index `eta + i k` (relative to the outside), scaled by
/// `specular_reflectance`. Black from behind (wrap it in `twosided`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    /// Normal distribution and roughness.
    pub microfacet: Microfacet,
    /// Real part of the index per channel, > 0.
    pub eta: Rgb,
    /// Extinction coefficient per channel, >= 0.
    pub k: Rgb,
    /// Multiplier of the reflection (Mitsuba's `specular_reflectance`, default 1).
    pub specular_reflectance: Rgb,
    /// World-space direction of the distribution's local x axis
    /// (`alpha_u`) at one hit: the shape's `dp/du` (any length), made
    /// orthogonal to the normal by [`Bsdf::frame`](super::Bsdf::frame)
    /// (Mitsuba 3's frame); set per hit by
    /// [`Bsdf::with_tangent`](super::Bsdf::with_tangent). `Vec3::ZERO` (the
    /// default, and always for isotropic roughness): the x axis of
    /// [`Frame::from_z`](crate::math::Frame::from_z), built from the
    /// normal alone. A plain `Vec3`, so the model is no larger than before.
    pub tangent: Vec3,
}

impl RoughConductor {
    /// `f(wo, wi)` (1/sr, cosine excluded) in the local frame:
    /// `F(wo . h) D(h) G(wo, wi, h) / (4 cos_o cos_i)`, zero unless both lie above.
    #[inline]
    pub fn eval_local(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.microfacet.eval(h);
        let g = self.microfacet.g(wo, wi, h);
        let value = d * g / (4.0 * wo.z * wi.z);
        if !(value > 0.0) {
            return Rgb::ZERO;
        }
        fresnel_complex(wo.dot(h), self.eta, self.k) * self.specular_reflectance * value
    }

    /// Density (1/sr) of [`RoughConductor::sample_local`] returning `wi`:
    /// `D(h) G1(wo, h) / (4 cos_o)`.
    #[inline]
    pub fn pdf_local(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        if wo.dot(h) <= 0.0 || wi.dot(h) <= 0.0 {
            return 0.0;
        }
        self.microfacet.eval(h) * self.microfacet.smith_g1(wo, h) / (4.0 * wo.z)
    }

    /// Sample `wi` by reflecting `wo` about a visible microfacet normal:
    /// `(wi, f, pdf)`, `None` from behind or when `wi` falls below the surface.
    #[inline]
    pub fn sample_local(&self, wo: Vec3, u: Vec2) -> Option<(Vec3, Rgb, f32)> {
        if wo.z <= 0.0 {
            return None;
        }
        let (m, pdf_m) = self.microfacet.sample(wo, u);
        if !(pdf_m > 0.0) {
            return None;
        }
        let wi = reflect(wo, m);
        let wi_m = wi.dot(m);
        if wi.z <= 0.0 || wi_m <= 0.0 {
            return None;
        }
        let pdf = pdf_m / (4.0 * wi_m);
        // Mitsuba's weight F G1(wi, m), turned into f = weight pdf / cos_i.
        let weight = self.microfacet.smith_g1(wi, m);
        if !(weight > 0.0 && pdf > 0.0) {
            return None;
        }
        let f = fresnel_complex(wo.dot(m), self.eta, self.k) * self.specular_reflectance * (weight * pdf / wi.z);
        Some((wi, f, pdf))
    }
}
