//! Smooth dielectric interface: specular reflection with probability equal to
//! the Fresnel reflectance `R`, specular refraction (Snell's law) otherwise;
//! pbrt-v4 section 9.5 (`DielectricBxDF`, smooth case).

use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::{BsdfSample, TransportMode};
use crate::color::Rgb;
use crate::math::Vec3;

/// Sample a smooth dielectric with `eta = ior_inside / ior_outside` and
/// outward normal `n`, for `wo` on either side.
///
/// The lobe is chosen with the Fresnel weights themselves (reflection with
/// probability `R`, refraction with `T = 1 - R`), so `f |cos| / pdf` is exactly
/// 1 for a reflection and `1 / etap^2` (radiance) or 1 (importance) for a
/// refraction. Past the critical angle `R = 1` and every sample reflects.
/// `eta == 1` is index-matched: `wi = -wo` exactly, weight 1.
pub(super) fn sample_dielectric(eta: f32, n: Vec3, wo: Vec3, u_lobe: f32, mode: TransportMode) -> Option<BsdfSample> {
    debug_assert!(eta > 0.0, "relative index of refraction must be positive, got {eta}");
    let cos_o = n.dot(wo);
    if cos_o == 0.0 {
        return None;
    }
    if eta == 1.0 {
        return Some(pass_through(wo, cos_o));
    }
    let r = fresnel_dielectric(cos_o, eta);
    let t = 1.0 - r;
    if u_lobe < r {
        // Specular reflection: f = R / |cos|, chosen with probability R.
        // Divide by the cosine of the computed wi (not of wo, equal up to
        // rounding) so that f |cos(wi, n)| / pdf is 1 up to one rounding.
        let wi = reflect(wo, n);
        let cos_i = n.dot(wi).abs();
        if cos_i == 0.0 {
            return None;
        }
        let f = Rgb::splat(r / cos_i);
        return Some(BsdfSample { wi, f, pdf: r, is_specular: true, is_transmission: false, eta: 1.0 });
    }
    // Specular transmission: f = T / |cos_i| (/ etap^2 for radiance), chosen with probability T.
    let (wi, etap) = refract(wo, n, eta)?;
    let cos_i = n.dot(wi).abs();
    if cos_i == 0.0 {
        return None;
    }
    let mut f = t / cos_i;
    if mode == TransportMode::Radiance {
        f /= etap * etap;
    }
    Some(BsdfSample { wi, f: Rgb::splat(f), pdf: t, is_specular: true, is_transmission: true, eta: etap })
}

/// The index-matched crossing shared by `Null` and `Dielectric { eta: 1 }`:
/// `wi = -wo`, `f = 1 / |cos|`, `pdf = 1`, so the weight is exactly 1.
pub(super) fn pass_through(wo: Vec3, cos_o: f32) -> BsdfSample {
    BsdfSample {
        wi: -wo,
        f: Rgb::splat(1.0 / cos_o.abs()),
        pdf: 1.0,
        is_specular: true,
        is_transmission: true,
        eta: 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lobe_choice_follows_fresnel_reflectance() {
        // Glass from outside at normal incidence: R = 0.04, so u_lobe < 0.04 reflects.
        let n = Vec3::Z;
        let r = sample_dielectric(1.5, n, n, 0.039, TransportMode::Radiance).unwrap();
        assert!(!r.is_transmission && (r.pdf - 0.04).abs() < 1e-6);
        assert!((r.wi - n).length() < 1e-6);
        let t = sample_dielectric(1.5, n, n, 0.041, TransportMode::Radiance).unwrap();
        assert!(t.is_transmission && (t.pdf - 0.96).abs() < 1e-6 && t.eta == 1.5);
        assert!((t.wi + n).length() < 1e-6);
        // Radiance mode divides by etap^2; importance mode does not.
        assert!((t.f.r() - 0.96 / 2.25).abs() < 1e-6);
        let t_importance = sample_dielectric(1.5, n, n, 0.5, TransportMode::Importance).unwrap();
        assert!((t_importance.f.r() - 0.96).abs() < 1e-6);
    }
}
