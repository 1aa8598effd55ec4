//! Fresnel equations and the law of reflection and Snell's law for smooth
//! interfaces (pbrt-v4 sections 9.3 and 9.4).
//!
//! Convention: `n` points to the *outside* of the interface and `eta` is the
//! relative index of refraction `ior_inside / ior_outside`. A cosine is taken
//! against that outward normal, so a negative cosine means the incident
//! direction lies inside, and the functions then use `1 / eta` themselves.

use crate::color::Rgb;
use crate::math::{safe_sqrt, Vec3};

/// Mirror direction of `wo` about the normal `n` (either orientation):
/// `-wo + 2 (wo . n) n`; pbrt-v4 equation 9.1.
///
/// ```
/// use niebla::bsdf::reflect;
/// use niebla::math::Vec3;
/// let wo = Vec3::new(0.6, 0.0, 0.8);
/// assert!((reflect(wo, Vec3::Z) - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
/// ```
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// Refracted direction of `wi` (pointing away from the surface) through an
/// interface with outward normal `n` and relative index `eta = ior_inside /
/// ior_outside`; pbrt-v4 section 9.3.2.
///
/// Returns the transmitted direction (pointing away from the surface on the
/// other side) and `etap`, the relative index *across this crossing*: the
/// index on the transmitted side over the index on the side of `wi` (`eta`
/// when `wi` is outside, `1 / eta` when inside). `None` on total internal
/// reflection.
///
/// ```
/// use niebla::bsdf::refract;
/// use niebla::math::Vec3;
/// // Normal incidence from outside passes straight into glass.
/// let (wt, etap) = refract(Vec3::Z, Vec3::Z, 1.5).unwrap();
/// assert!((wt + Vec3::Z).length() < 1e-6 && etap == 1.5);
/// ```
#[inline]
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    debug_assert!(eta > 0.0, "relative index of refraction must be positive, got {eta}");
    let mut cos_theta_i = n.dot(wi);
    let (eta, n) = if cos_theta_i < 0.0 {
        cos_theta_i = -cos_theta_i;
        (1.0 / eta, -n)
    } else {
        (eta, n)
    };
    // Snell's law: sin_t = sin_i / eta.
    let sin2_theta_i = (1.0 - cos_theta_i * cos_theta_i).max(0.0);
    let sin2_theta_t = sin2_theta_i / (eta * eta);
    if sin2_theta_t >= 1.0 {
        return None;
    }
    let cos_theta_t = safe_sqrt(1.0 - sin2_theta_t);
    let wt = -wi / eta + (cos_theta_i / eta - cos_theta_t) * n;
    Some((wt, eta))
}

/// Unpolarized Fresnel reflectance of a smooth dielectric interface, the mean
/// of the s- and p-polarized reflectances (pbrt-v4 equation 9.6).
///
/// `cos_theta_i` is the cosine of the incident direction to the outward
/// normal (negative from inside) and `eta = ior_inside / ior_outside`.
/// Returns 1 past the critical angle (total internal reflection). The
/// transmittance is `1 - R`: a dielectric absorbs nothing.
///
/// ```
/// use niebla::bsdf::fresnel_dielectric;
/// // Glass at normal incidence: ((1.5 - 1) / (1.5 + 1))^2 = 0.04.
/// assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
/// ```
#[inline]
pub fn fresnel_dielectric(cos_theta_i: f32, eta: f32) -> f32 {
    debug_assert!(eta > 0.0, "relative index of refraction must be positive, got {eta}");
    if eta == 1.0 {
        // Index-matched: exactly no reflection (rounding would leave ~1e-15).
        return 0.0;
    }
    let mut cos_theta_i = cos_theta_i.clamp(-1.0, 1.0);
    let eta = if cos_theta_i < 0.0 {
        cos_theta_i = -cos_theta_i;
        1.0 / eta
    } else {
        eta
    };
    let sin2_theta_i = 1.0 - cos_theta_i * cos_theta_i;
    let sin2_theta_t = sin2_theta_i / (eta * eta);
    if sin2_theta_t >= 1.0 {
        return 1.0;
    }
    let cos_theta_t = safe_sqrt(1.0 - sin2_theta_t);
    let r_parl = (eta * cos_theta_i - cos_theta_t) / (eta * cos_theta_i + cos_theta_t);
    let r_perp = (cos_theta_i - eta * cos_theta_t) / (cos_theta_i + eta * cos_theta_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

/// A complex number in f64, just enough for [`fresnel_complex`]. f64 keeps
/// `eta^2` finite for the huge `k` that models a perfect mirror.
#[derive(Clone, Copy, Debug)]
struct Complex {
    re: f64,
    im: f64,
}

impl Complex {
    fn new(re: f64, im: f64) -> Complex {
        Complex { re, im }
    }
    fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: Complex) -> Complex {
        Complex::new(self.re * o.re - self.im * o.im, self.re * o.im + self.im * o.re)
    }
    fn scale(self, s: f64) -> Complex {
        Complex::new(self.re * s, self.im * s)
    }
    /// Squared magnitude |z|^2.
    fn norm(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    fn div(self, o: Complex) -> Complex {
        // Smith's algorithm avoids overflow of |o|^2 for large operands.
        if o.re.abs() >= o.im.abs() {
            let r = o.im / o.re;
            let d = o.re + o.im * r;
            Complex::new((self.re + self.im * r) / d, (self.im - self.re * r) / d)
        } else {
            let r = o.re / o.im;
            let d = o.re * r + o.im;
            Complex::new((self.re * r + self.im) / d, (self.im * r - self.re) / d)
        }
    }
    /// Principal square root (non-negative real part).
    fn sqrt(self) -> Complex {
        let m = self.norm().sqrt();
        if m == 0.0 {
            return Complex::new(0.0, 0.0);
        }
        let re = (0.5 * (m + self.re)).max(0.0).sqrt();
        let im = (0.5 * (m - self.re)).max(0.0).sqrt();
        Complex::new(re, if self.im < 0.0 { -im } else { im })
    }
}

/// Fresnel reflectance of one wavelength band at a conductor with complex
/// index `eta + i k` relative to the outside medium (pbrt-v4 `FrComplex`,
/// section 9.5). `cos_theta_i` is clamped to [0, 1]: light meets a conductor
/// from outside only.
fn fresnel_complex_channel(cos_theta_i: f32, eta: f32, k: f32) -> f32 {
    let cos_theta_i = cos_theta_i.clamp(0.0, 1.0) as f64;
    let eta = Complex::new(eta as f64, k as f64);
    let one = Complex::new(1.0, 0.0);
    let sin2_theta_i = 1.0 - cos_theta_i * cos_theta_i;
    let sin2_theta_t = Complex::new(sin2_theta_i, 0.0).div(eta.mul(eta));
    let cos_theta_t = one.sub(sin2_theta_t).sqrt();
    let eta_cos_i = eta.scale(cos_theta_i);
    let r_parl = eta_cos_i.sub(cos_theta_t).div(eta_cos_i.add(cos_theta_t));
    let ci = Complex::new(cos_theta_i, 0.0);
    let eta_cos_t = eta.mul(cos_theta_t);
    let r_perp = ci.sub(eta_cos_t).div(ci.add(eta_cos_t));
    (0.5 * (r_parl.norm() + r_perp.norm())) as f32
}

/// Unpolarized Fresnel reflectance of a smooth conductor, per RGB channel,
/// for the complex relative index `eta + i k` (pbrt-v4 `FrComplex`, section
/// 9.5). With `k = 0` it equals [`fresnel_dielectric`] for incidence from
/// outside; as `k` grows it tends to 1 (a perfect mirror).
///
/// ```
/// use niebla::bsdf::fresnel_complex;
/// use niebla::color::Rgb;
/// // Aluminium (Tungsten's RGB table): about 92% at normal incidence.
/// let r = fresnel_complex(1.0, Rgb::new(1.657, 0.880, 0.521), Rgb::new(9.224, 6.270, 4.837));
/// assert!((r.g() - 0.92).abs() < 0.01);
/// ```
#[inline]
pub fn fresnel_complex(cos_theta_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    Rgb(std::array::from_fn(|c| fresnel_complex_channel(cos_theta_i, eta[c], k[c])))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// s-polarized reflectance (electric field perpendicular to the plane of
    /// incidence), written independently of `fresnel_dielectric` from the
    /// angle form of the Fresnel equations: R_s = sin^2(t - i) / sin^2(t + i).
    fn r_s(theta_i: f64, eta: f64) -> f64 {
        let theta_t = (theta_i.sin() / eta).asin();
        ((theta_t - theta_i).sin() / (theta_t + theta_i).sin()).powi(2)
    }

    #[test]
    fn normal_incidence_reflectance_is_squared_index_contrast() {
        // ((eta - 1) / (eta + 1))^2: glass 0.04, water 0.02035; f32 rounding only.
        for (eta, expected) in [(1.5f32, 0.04f32), (1.333, 0.020_35), (2.42, 0.1724)] {
            let closed = ((eta - 1.0) / (eta + 1.0)).powi(2);
            assert!((closed - expected).abs() < 1e-4, "closed form {closed} for eta {eta}");
            assert!((fresnel_dielectric(1.0, eta) - closed).abs() < 1e-6);
            // The same from inside (reciprocity of normal incidence).
            assert!((fresnel_dielectric(-1.0, eta) - closed).abs() < 1e-6);
        }
        assert_eq!(fresnel_dielectric(0.3, 1.0), 0.0);
    }

    #[test]
    fn total_internal_reflection_past_the_critical_angle() {
        // Inside glass (eta = 1.5) the critical angle is asin(1 / 1.5) = 41.81 deg.
        let eta = 1.5f32;
        let critical = (1.0 / eta).asin();
        for deg in [42.0f32, 50.0, 70.0, 89.9] {
            let cos_i = deg.to_radians().cos();
            assert_eq!(fresnel_dielectric(-cos_i, eta), 1.0, "{deg} deg from inside");
            let wi = Vec3::new(deg.to_radians().sin(), 0.0, -cos_i);
            assert!(refract(wi, Vec3::Z, eta).is_none(), "{deg} deg refracts");
        }
        // Just below it some light escapes, and from outside there is no TIR.
        let below = (critical - 0.01).cos();
        assert!(fresnel_dielectric(-below, eta) < 1.0);
        assert!(refract(Vec3::new((critical - 0.01).sin(), 0.0, -below), Vec3::Z, eta).is_some());
        assert!(fresnel_dielectric(0.01, eta) < 1.0);
    }

    #[test]
    fn brewster_angle_reflects_only_s_polarization() {
        // At tan(theta_B) = eta the p-polarized reflectance vanishes, so the
        // unpolarized R is R_s / 2, R_s from the independent angle form above.
        // Agreement to 1e-6 (f32 arithmetic on values ~0.07).
        for eta in [1.333f64, 1.5, 2.42] {
            let theta_b = eta.atan();
            let expected = 0.5 * r_s(theta_b, eta);
            let r = fresnel_dielectric(theta_b.cos() as f32, eta as f32) as f64;
            assert!((r - expected).abs() < 1e-6, "eta {eta}: R {r} vs R_s/2 {expected}");
            // Away from Brewster, R exceeds R_s / 2 (R_p > 0).
            let off = theta_b + 0.3;
            assert!(fresnel_dielectric(off.cos() as f32, eta as f32) as f64 > 0.5 * r_s(off, eta) + 1e-4);
        }
    }

    #[test]
    fn fresnel_dielectric_matches_the_angle_form_at_all_angles() {
        // Unpolarized R = (R_s + R_p) / 2 with R_p = tan^2(t - i) / tan^2(t + i).
        let eta = 1.5f64;
        for i in 1..90 {
            let theta_i = (i as f64).to_radians();
            let theta_t = (theta_i.sin() / eta).asin();
            let r_p = ((theta_t - theta_i).tan() / (theta_t + theta_i).tan()).powi(2);
            let expected = 0.5 * (r_s(theta_i, eta) + r_p);
            let r = fresnel_dielectric(theta_i.cos() as f32, eta as f32) as f64;
            assert!((r - expected).abs() < 2e-6, "{i} deg: {r} vs {expected}");
        }
    }

    #[test]
    fn complex_fresnel_reduces_to_dielectric_when_k_is_zero() {
        for eta in [1.2f32, 1.5, 2.0] {
            for i in 0..=90 {
                let cos_i = (i as f32).to_radians().cos();
                let r = fresnel_complex(cos_i, Rgb::splat(eta), Rgb::ZERO);
                let d = fresnel_dielectric(cos_i, eta);
                assert!((r.g() - d).abs() < 1e-6, "eta {eta}, {i} deg: {} vs {d}", r.g());
            }
        }
    }

    #[test]
    fn complex_fresnel_normal_incidence_is_closed_form() {
        // R0 = ((n - 1)^2 + k^2) / ((n + 1)^2 + k^2).
        let (n, k) = (0.2f32, 3.9f32);
        let closed = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        let r = fresnel_complex(1.0, Rgb::splat(n), Rgb::splat(k));
        assert!((r.r() - closed).abs() < 1e-6);
    }

    #[test]
    fn huge_extinction_makes_a_perfect_mirror() {
        // For k cos >> n, 1 - R ~ 2 n / (k^2 cos) (the p-polarized part): with
        // k = 1e6 that is 1e-10 even at 89 deg, below f32 resolution at 1.
        for i in 0..90 {
            let cos_i = (i as f32).to_radians().cos();
            let r = fresnel_complex(cos_i, Rgb::splat(1.0), Rgb::splat(1e6));
            assert!((r.r() - 1.0).abs() < 1e-6, "{i} deg: {}", r.r());
        }
    }

    #[test]
    fn refraction_obeys_snell_and_reversal() {
        let eta = 1.333f32;
        let wi = Vec3::new(0.5, 0.3, 0.812).normalize();
        let (wt, etap) = refract(wi, Vec3::Z, eta).unwrap();
        assert_eq!(etap, eta);
        assert!((wt.length() - 1.0).abs() < 1e-6);
        // sin_i = eta sin_t, same plane of incidence, other side.
        let sin_i = (1.0 - wi.z * wi.z).sqrt();
        let sin_t = (1.0 - wt.z * wt.z).sqrt();
        assert!((sin_i - eta * sin_t).abs() < 1e-6);
        assert!(wt.z < 0.0 && (wi.x * wt.y - wi.y * wt.x).abs() < 1e-6);
        // Refracting back from inside returns the original direction.
        let (back, etap_back) = refract(wt, Vec3::Z, eta).unwrap();
        assert!((back - wi).length() < 1e-6);
        assert!((etap_back - 1.0 / eta).abs() < 1e-7);
    }
}
