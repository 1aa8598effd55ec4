//! Smooth plastic: Mitsuba 3's `plastic`, a diffuse base under a smooth
//! dielectric coating (Weidlich and Wilkie, "Arbitrarily layered
//! micro-facet surfaces", 2007, as Mitsuba simplifies it). A delta specular
//! reflection `F(cos_o)` off the coating, plus the base's diffuse light
//! refracted in and out: `f = R_d / (1 - F_dr) (1 - F(cos_o)) (1 - F(cos_i))
//! / (pi eta^2)`, where `F_dr` is the coating's diffuse internal reflectance
//! (`nonlinear`: `R_d / (1 - R_d F_dr)` instead, the infinite series of
//! reflections inside the coating that tints the color). One-sided.

use super::fresnel::fresnel_dielectric;
use super::LocalSample;
use crate::color::Rgb;
use crate::math::{Vec3, INV_PI};

/// A coated diffuse surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plastic {
    /// Relative index of the coating `int_ior / ext_ior`, > 0.
    pub eta: f32,
    /// Diffuse reflectance of the base, in [0, 1] per channel.
    pub diffuse_reflectance: Rgb,
    /// Multiplier of the specular reflection (default 1).
    pub specular_reflectance: Rgb,
    /// Mitsuba's `nonlinear`: account for the coating's internal
    /// reflections on the base color (darker, more saturated).
    pub nonlinear: bool,
    /// Weight of the specular lobe in sampling: `s / (d + s)` with `s`, `d`
    /// the mean specular and diffuse reflectances (over channels, or over a
    /// texture).
    pub specular_sampling_weight: f32,
    /// Diffuse Fresnel reflectance from inside the coating, `F_dr(1 / eta)`.
    pub fdr_int: f32,
}

impl Plastic {
    /// A plastic, with Mitsuba's derived constants; `diffuse_mean` and
    /// `specular_mean` are the mean reflectances used to steer sampling.
    pub fn new(
        eta: f32,
        diffuse_reflectance: Rgb,
        specular_reflectance: Rgb,
        nonlinear: bool,
        diffuse_mean: f32,
        specular_mean: f32,
    ) -> Plastic {
        Plastic {
            eta,
            diffuse_reflectance,
            specular_reflectance,
            nonlinear,
            specular_sampling_weight: specular_mean / (diffuse_mean + specular_mean),
            fdr_int: fresnel_diffuse_reflectance(1.0 / eta),
        }
    }

    /// Diffuse albedo term `R_d / (1 - F_dr)` (or the nonlinear form).
    #[inline]
    pub(super) fn diffuse_term(&self) -> Rgb {
        let d = self.diffuse_reflectance;
        if self.nonlinear {
            Rgb(std::array::from_fn(|c| d[c] / (1.0 - d[c] * self.fdr_int)))
        } else {
            d / (1.0 - self.fdr_int)
        }
    }

    /// Probability of sampling the specular lobe at incidence `cos_o > 0`
    /// given the Fresnel reflectance `f_o` there.
    #[inline]
    pub(super) fn prob_specular(&self, f_o: f32) -> f32 {
        let s = f_o * self.specular_sampling_weight;
        let d = (1.0 - f_o) * (1.0 - self.specular_sampling_weight);
        s / (s + d)
    }

    /// Diffuse part of `f(wo, wi)` (1/sr): the delta lobe is not included.
    #[inline]
    pub fn eval_local(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta);
        let f_i = fresnel_dielectric(wi.z, self.eta);
        self.diffuse_term() * (INV_PI / (self.eta * self.eta) * (1.0 - f_o) * (1.0 - f_i))
    }

    /// Density (1/sr) of sampling `wi` by the diffuse lobe.
    #[inline]
    pub fn pdf_local(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta);
        (1.0 - self.prob_specular(f_o)) * wi.z * INV_PI
    }

    /// Choose the specular lobe with [`Plastic::prob_specular`], else a
    /// cosine-weighted diffuse direction.
    #[inline]
    pub(super) fn sample_local(&self, wo: Vec3, u_lobe: f32, u: crate::math::Vec2) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta);
        let p_spec = self.prob_specular(f_o);
        if u_lobe < p_spec {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            let f = self.specular_reflectance * (f_o / wi.z);
            return Some(LocalSample { wi, f, pdf: p_spec, specular: true });
        }
        let wi = crate::sampling::sample_cosine_hemisphere(u);
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = (1.0 - p_spec) * wi.z * INV_PI;
        let f = self.eval_local(wo, wi);
        (pdf > 0.0).then_some(LocalSample { wi, f, pdf, specular: false })
    }
}

/// Diffuse Fresnel reflectance `F_dr(eta)` of a dielectric interface: the
/// fraction of uniform diffuse illumination from the side of relative index
/// `eta` (index across over index here) that is reflected. Mitsuba's fits:
/// Egan and Hilgeman (1973) for `eta < 1`, d'Eon and Irving (2011) otherwise.
///
/// ```
/// use niebla::bsdf::fresnel_diffuse_reflectance;
/// // Glass seen from air reflects about 9% of diffuse light.
/// assert!((fresnel_diffuse_reflectance(1.5) - 0.092).abs() < 0.002);
/// ```
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let inv_eta = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv_eta + (eta * (eta * -1.4399 + 0.7099) + 0.6681)
    } else {
        let c = [0.919_317f32, -3.4793, 6.753_35, -7.809_89, 4.985_54, -1.368_81];
        let mut acc = c[5];
        for i in (0..5).rev() {
            acc = acc * inv_eta + c[i];
        }
        acc
    }
}
