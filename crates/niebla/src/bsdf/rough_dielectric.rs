//! Rough dielectric: Mitsuba 3's `roughdielectric` (Walter et al. 2007),
//! microfacet reflection and refraction between an inside of relative index
//! `eta` and the outside, sampled by visible normals with the lobe chosen
//! by the Fresnel reflectance. A medium boundary like the smooth
//! dielectric. Local frame: `+z` points outside; `wo` toward the camera,
//! `wi` toward the light (Mitsuba's `si.wi` and `wo`).

use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::microfacet::Microfacet;
use super::TransportMode;
use crate::color::Rgb;
use crate::math::{Vec2, Vec3};

/// A rough glass-like interface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    /// Normal distribution and roughness.
    pub microfacet: Microfacet,
    /// Relative index `ior_inside / ior_outside`, > 0 and != 1.
    pub eta: f32,
    /// Multiplier of the reflection (default 1).
    pub specular_reflectance: Rgb,
    /// Multiplier of the transmission (default 1).
    pub specular_transmittance: Rgb,
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

/// A sampled direction of a rough dielectric: `wi`, `f` (1/sr), density
/// (1/sr), whether it refracted, and `etap` (index on `wi`'s side over
/// index on `wo`'s side; 1 for reflection).
pub(super) struct RoughDielectricSample {
    pub wi: Vec3,
    pub f: Rgb,
    pub pdf: f32,
    pub transmitted: bool,
    pub etap: f32,
}

impl RoughDielectric {
    /// `eta` seen from the side of `wo` (the index across the interface
    /// from there) and the generalized half vector of `(wo, wi)` turned
    /// to `+z`; `None` when degenerate.
    #[inline]
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> Option<(bool, f32, Vec3)> {
        let reflect = wo.z * wi.z > 0.0;
        let eta = if wo.z > 0.0 { self.eta } else { 1.0 / self.eta };
        let m = wo + wi * if reflect { 1.0 } else { eta };
        let m = m.try_normalize()?;
        let m = if m.z < 0.0 { -m } else { m };
        Some((reflect, eta, m))
    }

    /// `f(wo, wi)` (1/sr, cosine excluded) for radiance transport
    /// (refraction carries `1 / etap^2`, see the module `bsdf`).
    #[inline]
    pub fn eval_local(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z == 0.0 || wi.z == 0.0 {
            return Rgb::ZERO;
        }
        let Some((reflect, eta, m)) = self.half_vector(wo, wi) else {
            return Rgb::ZERO;
        };
        let d = self.microfacet.eval(m);
        let f = fresnel_dielectric(wo.dot(m), self.eta);
        let g = self.microfacet.g(wo, wi, m);
        let value = if reflect {
            f * d * g / (4.0 * wo.z.abs())
        } else {
            let scale = 1.0 / (eta * eta);
            let denom = wo.dot(m) + eta * wi.dot(m);
            (scale * (1.0 - f) * d * g * eta * eta * wo.dot(m) * wi.dot(m) / (wo.z * denom * denom)).abs()
        };
        if !(value > 0.0) || !value.is_finite() {
            return Rgb::ZERO;
        }
        let tint = if reflect { self.specular_reflectance } else { self.specular_transmittance };
        tint * (value / wi.z.abs())
    }

    /// Density (1/sr) of `RoughDielectric::sample_local` returning `wi`.
    #[inline]
    pub fn pdf_local(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z == 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let Some((reflect, eta, m)) = self.half_vector(wo, wi) else {
            return 0.0;
        };
        let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
        if wo_m * wo.z <= 0.0 || wi_m * wi.z <= 0.0 {
            return 0.0;
        }
        let dwh_dwi = if reflect { 1.0 / (4.0 * wi_m) } else { eta * eta * wi_m / sqr(wo_m + eta * wi_m) };
        let wo_up = if wo.z < 0.0 { -wo } else { wo };
        let f = fresnel_dielectric(wo_m, self.eta);
        let prob = self.microfacet.pdf(wo_up, m) * if reflect { f } else { 1.0 - f };
        let pdf = prob * dwh_dwi.abs();
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// Sample a visible microfacet normal, then reflect (probability `F`)
    /// or refract (`1 - F`) about it; `u_lobe` chooses, `u` samples the normal.
    #[inline]
    pub(super) fn sample_local(
        &self,
        wo: Vec3,
        u_lobe: f32,
        u: Vec2,
        mode: TransportMode,
    ) -> Option<RoughDielectricSample> {
        if wo.z == 0.0 {
            return None;
        }
        let wo_up = if wo.z < 0.0 { -wo } else { wo };
        let (m, pdf_m) = self.microfacet.sample(wo_up, u);
        if !(pdf_m > 0.0) {
            return None;
        }
        let wo_m = wo.dot(m);
        let f = fresnel_dielectric(wo_m, self.eta);
        let (wi, pdf, weight, transmitted, etap) = if u_lobe < f {
            let wi = reflect(wo, m);
            if wi.z * wo.z <= 0.0 {
                return None;
            }
            let pdf = pdf_m * f / (4.0 * wi.dot(m)).abs();
            (wi, pdf, self.specular_reflectance, false, 1.0)
        } else {
            let (wi, etap) = refract(wo, m, self.eta)?;
            if wi.z * wo.z >= 0.0 {
                return None;
            }
            let wi_m = wi.dot(m);
            let dwh_dwi = etap * etap * wi_m / sqr(wo_m + etap * wi_m);
            let pdf = pdf_m * (1.0 - f) * dwh_dwi.abs();
            let factor = if mode == TransportMode::Radiance { 1.0 / (etap * etap) } else { 1.0 };
            (wi, pdf, self.specular_transmittance * factor, true, etap)
        };
        let g1 = self.microfacet.smith_g1(wi, m);
        if !(g1 > 0.0 && pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        // Mitsuba's sample weight is `tint G1(wi, m)` (times the radiance
        // factor); f = weight pdf / |cos_i| keeps it exact.
        let f = weight * (g1 * pdf / wi.z.abs());
        Some(RoughDielectricSample { wi, f, pdf, transmitted, etap })
    }
}

#[inline]
fn sqr(x: f32) -> f32 {
    x * x
}
