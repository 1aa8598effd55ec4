//! Two-sided Lambertian reflection: `f = reflectance / pi` whenever `wo` and
//! `wi` lie on the same side of the surface, sampled cosine-weighted on the
//! side of `wo` (pbrt-v4 section 9.2).

use super::BsdfSample;
use crate::color::Rgb;
use crate::math::{Frame, Vec2, Vec3, INV_PI};
use crate::sampling::sample_cosine_hemisphere;

/// Lambertian value: `reflectance / pi` on the side of `wo`, else zero.
#[inline]
pub(super) fn diffuse_eval(reflectance: Rgb, n: Vec3, wo: Vec3, wi: Vec3) -> Rgb {
    if n.dot(wo) * n.dot(wi) > 0.0 {
        reflectance * INV_PI
    } else {
        Rgb::ZERO
    }
}

/// Density of [`sample_diffuse`]: `|cos(wi, n)| / pi` on the side of `wo`, else zero.
#[inline]
pub(super) fn diffuse_pdf(n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let cos_i = n.dot(wi);
    if n.dot(wo) * cos_i > 0.0 {
        cos_i.abs() * INV_PI
    } else {
        0.0
    }
}

/// Cosine-weighted direction on the hemisphere of `wo` (Malley's method).
/// The pdf is computed from the world-space cosine exactly as
/// [`diffuse_pdf`] computes it, so `pdf(n, wo, s.wi) == s.pdf` bit for bit.
/// `None` for grazing `wo` or when rounding puts `wi` on the surface.
#[inline]
pub(super) fn sample_diffuse(reflectance: Rgb, n: Vec3, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
    let cos_o = n.dot(wo);
    if cos_o == 0.0 {
        return None;
    }
    let n_o = if cos_o > 0.0 { n } else { -n };
    let wi = Frame::from_z(n_o).to_world(sample_cosine_hemisphere(u));
    let pdf = diffuse_pdf(n, wo, wi);
    if !(pdf > 0.0) {
        return None;
    }
    Some(BsdfSample { wi, f: reflectance * INV_PI, pdf, is_specular: false, is_transmission: false, eta: 1.0 })
}
