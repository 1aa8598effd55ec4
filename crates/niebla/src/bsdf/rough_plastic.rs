//! Rough plastic: Mitsuba 3's `roughplastic`, a diffuse base under a rough
//! dielectric coating (Weidlich and Wilkie, "Arbitrarily layered
//! micro-facet surfaces", 2007, as Mitsuba simplifies it). A microfacet
//! reflection off the coating (Walter et al. 2007, isotropic Beckmann or
//! GGX), plus the base's diffuse light refracted in and out:
//!
//! `f = F D G / (4 cos_o cos_i) R_s
//!    + R_d / (1 - F_int) T(cos_o) T(cos_i) / (pi eta^2)`,
//!
//! where `T(cos)` is the coating's rough transmittance (the hemispherical
//! integral of its microfacet transmission for white light, tabulated at 64
//! cosines and interpolated linearly, as Mitsuba does) and `F_int` its
//! diffuse internal reflectance (twice the cosine-weighted mean of its rough
//! reflectance seen from inside); `nonlinear` uses `R_d / (1 - R_d F_int)`.
//! Both integrals are computed exactly as Mitsuba computes them: Gauss-Legendre
//! quadrature (32^2 nodes when the coating is seen from the less dense side,
//! else 128^2) over the visible-normal sampling square. One-sided.
//! Local frame: `+z` is the outward normal; `wo` toward the camera (Mitsuba's
//! `si.wi`), `wi` toward the light (Mitsuba's `wo`).

use std::sync::Mutex;

use super::fresnel::{fresnel_dielectric, reflect, refract};
use super::microfacet::{Microfacet, MicrofacetKind};
use super::LocalSample;
use crate::color::Rgb;
use crate::math::{Vec2, Vec3, INV_PI};

/// Number of cosines of the rough transmittance table (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`).
pub const ROUGH_TRANSMITTANCE_RES: usize = 64;

/// The coating's precomputed integrals for one (distribution, alpha, eta).
#[derive(Debug, PartialEq)]
pub struct CoatingTables {
    /// Rough transmittance `T(cos)` at `cos = i / 63` (the first at 1e-6).
    pub transmittance: [f32; ROUGH_TRANSMITTANCE_RES],
    /// Diffuse internal reflectance of the coating, in [0, 1].
    pub internal_reflectance: f32,
}

/// A rough coated diffuse surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughPlastic {
    /// Isotropic normal distribution of the coating.
    pub microfacet: Microfacet,
    /// Relative index of the coating `int_ior / ext_ior`, > 0 and not 1.
    pub eta: f32,
    /// Diffuse reflectance of the base, in [0, 1] per channel.
    pub diffuse_reflectance: Rgb,
    /// Multiplier of the specular reflection (default 1).
    pub specular_reflectance: Rgb,
    /// Mitsuba's `nonlinear`: the coating's internal reflections tint the base.
    pub nonlinear: bool,
    /// Weight of the specular lobe in sampling, `s / (d + s)` with `s`, `d`
    /// the mean specular and diffuse reflectances.
    pub specular_sampling_weight: f32,
    /// The coating's integrals, shared by every surface with the same
    /// distribution, roughness and index ([`coating_tables`]).
    pub tables: &'static CoatingTables,
}

impl RoughPlastic {
    /// A rough plastic with Mitsuba's derived constants; `diffuse_mean` and
    /// `specular_mean` are the mean reflectances used to steer sampling.
    /// The coating tables are computed on first use of these parameters.
    pub fn new(
        microfacet: Microfacet,
        eta: f32,
        diffuse_reflectance: Rgb,
        specular_reflectance: Rgb,
        nonlinear: bool,
        diffuse_mean: f32,
        specular_mean: f32,
    ) -> RoughPlastic {
        RoughPlastic {
            microfacet,
            eta,
            diffuse_reflectance,
            specular_reflectance,
            nonlinear,
            specular_sampling_weight: specular_mean / (diffuse_mean + specular_mean),
            tables: coating_tables(microfacet.kind, microfacet.alpha_u, eta),
        }
    }

    /// Rough transmittance at cosine `cos` in [0, 1], interpolated linearly
    /// in the table (Mitsuba's `lerp_gather`).
    #[inline]
    pub fn transmittance(&self, cos: f32) -> f32 {
        let x = cos * (ROUGH_TRANSMITTANCE_RES - 1) as f32;
        let index = (x as usize).min(ROUGH_TRANSMITTANCE_RES - 2);
        let w = x - index as f32;
        let t = &self.tables.transmittance;
        t[index] + (t[index + 1] - t[index]) * w
    }

    /// Probability of sampling the specular lobe at camera-side cosine `cos_o`.
    #[inline]
    fn prob_specular(&self, cos_o: f32) -> f32 {
        let t_o = self.transmittance(cos_o);
        let s = (1.0 - t_o) * self.specular_sampling_weight;
        let d = t_o * (1.0 - self.specular_sampling_weight);
        s / (s + d)
    }

    /// `f(wo, wi)` (1/sr, cosine excluded), zero unless both lie above.
    #[inline]
    pub fn eval_local(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.microfacet.eval(h);
        let f = fresnel_dielectric(wo.dot(h), self.eta);
        let g = self.microfacet.g(wo, wi, h);
        let specular = self.specular_reflectance * (f * d * g / (4.0 * wo.z * wi.z));
        let diff = self.diffuse_reflectance;
        let fi = self.tables.internal_reflectance;
        let base = if self.nonlinear {
            Rgb(std::array::from_fn(|c| diff[c] / (1.0 - diff[c] * fi)))
        } else {
            diff / (1.0 - fi)
        };
        let scale = INV_PI / (self.eta * self.eta) * self.transmittance(wo.z) * self.transmittance(wi.z);
        specular + base * scale
    }

    /// Density (1/sr) of `RoughPlastic::sample_local` returning `wi`: the
    /// mixture of the visible-normal reflection `D(h) G1(wo, h) / (4 cos_o)`
    /// and the cosine-weighted hemisphere.
    #[inline]
    pub fn pdf_local(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let p_spec = self.prob_specular(wo.z);
        let h = (wo + wi).normalize();
        let spec = self.microfacet.eval(h) * self.microfacet.smith_g1(wo, h) / (4.0 * wo.z);
        p_spec * spec + (1.0 - p_spec) * wi.z * INV_PI
    }

    /// Choose the specular lobe with probability from the rough
    /// transmittance at `wo` (reflect about a visible normal), else a
    /// cosine-weighted direction; the returned `f` and `pdf` are those of
    /// the whole model (both lobes), as for MIS.
    #[inline]
    pub(super) fn sample_local(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u_lobe < self.prob_specular(wo.z) {
            let (m, _) = self.microfacet.sample(wo, u);
            reflect(wo, m)
        } else {
            crate::sampling::sample_cosine_hemisphere(u)
        };
        let pdf = self.pdf_local(wo, wi);
        if !(pdf > 0.0) {
            return None;
        }
        Some(LocalSample { wi, f: self.eval_local(wo, wi), pdf, specular: false })
    }
}

/// Tables already computed, by (distribution, alpha bits, eta bits). Each is
/// built once per distinct coating and lives as long as the program (a
/// scene holds few distinct coatings; this keeps [`RoughPlastic`] `Copy`).
static TABLES: Mutex<Vec<(TableKey, &'static CoatingTables)>> = Mutex::new(Vec::new());

/// Distribution, bits of alpha, bits of eta.
type TableKey = (MicrofacetKind, u32, u32);

/// The coating integrals of a `kind` distribution of roughness `alpha` and
/// relative index `eta`, computed on first request and shared afterwards.
pub fn coating_tables(kind: MicrofacetKind, alpha: f32, eta: f32) -> &'static CoatingTables {
    let key = (kind, alpha.to_bits(), eta.to_bits());
    let mut tables = TABLES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, t)) = tables.iter().find(|(k, _)| *k == key) {
        return t;
    }
    let t: &'static CoatingTables = Box::leak(Box::new(compute_tables(kind, alpha, eta)));
    tables.push((key, t));
    t
}

/// Mitsuba's precomputation: at `mu = max(1e-6, i / 63)`, the rough
/// transmittance into the coating, and twice the mean over the same cosines
/// of `mu` times the rough reflectance seen from inside.
fn compute_tables(kind: MicrofacetKind, alpha: f32, eta: f32) -> CoatingTables {
    let distr = Microfacet::new(kind, alpha, alpha);
    let mut transmittance = [0.0f32; ROUGH_TRANSMITTANCE_RES];
    let mut internal = 0.0f32;
    let step = 1.0 / (ROUGH_TRANSMITTANCE_RES - 1) as f32;
    for (i, t) in transmittance.iter_mut().enumerate() {
        let mu = (i as f32 * step).max(1e-6);
        let wi = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
        *t = rough_integral(&distr, wi, eta, true);
        internal += rough_integral(&distr, wi, 1.0 / eta, false) * wi.z;
    }
    CoatingTables { transmittance, internal_reflectance: internal / ROUGH_TRANSMITTANCE_RES as f32 * 2.0 }
}

/// Mitsuba's `eval_transmittance` (`transmit`) or `eval_reflectance`: the
/// mean over visible normals `m` seen from `wi` of `(1 - F) G1(wt, m)` for
/// the refracted `wt`, or of `F G1(wr, m)` for the reflected `wr`, by
/// Gauss-Legendre quadrature on the sampling square.
fn rough_integral(distr: &Microfacet, wi: Vec3, eta: f32, transmit: bool) -> f32 {
    let (nodes, weights) = gauss_legendre(if eta > 1.0 { 32 } else { 128 });
    let n = nodes.len();
    let mut sum = 0.0f32;
    for j in 0..n * n {
        // drjit's meshgrid: x varies fastest.
        let (ix, iy) = (j % n, j / n);
        let node = Vec2::new(nodes[ix] * 0.5 + 0.5, nodes[iy] * 0.5 + 0.5);
        let (m, _) = distr.sample(wi, node);
        let cos_im = wi.dot(m);
        let f = fresnel_dielectric(cos_im, eta);
        let value = if transmit {
            match refract(wi, m, eta) {
                Some((wt, _)) if wt.z * wi.z < 0.0 => distr.smith_g1(wt, m) * (1.0 - f),
                _ => 0.0,
            }
        } else {
            let wr = reflect(wi, m);
            if wr.z > 0.0 && wi.z > 0.0 {
                distr.smith_g1(wr, m) * f
            } else {
                0.0
            }
        };
        if value.is_finite() {
            sum += value * (weights[ix] * weights[iy]) * 0.25;
        }
    }
    sum
}

/// Gauss-Legendre nodes on [-1, 1] and weights (summing to 2) of order `n`,
/// by Newton's method on the Legendre polynomial in f64, rounded to f32.
fn gauss_legendre(n: usize) -> (Vec<f32>, Vec<f32>) {
    let mut nodes = vec![0.0f32; n];
    let mut weights = vec![0.0f32; n];
    let last = n - 1;
    for i in 0..n.div_ceil(2) {
        let mut x = -(std::f64::consts::PI * (2 * i + 1) as f64 / (2 * n) as f64).cos();
        for _ in 0..100 {
            let (p, dp) = legendre_pd(n, x);
            let step = p / dp;
            x -= step;
            if step.abs() <= 4.0 * x.abs() * f64::EPSILON {
                break;
            }
        }
        let (_, dp) = legendre_pd(n, x);
        let w = (2.0 / ((1.0 - x * x) * dp * dp)) as f32;
        nodes[i] = x as f32;
        nodes[last - i] = -x as f32;
        weights[i] = w;
        weights[last - i] = w;
    }
    (nodes, weights)
}

/// The Legendre polynomial `P_n(x)` and its derivative.
fn legendre_pd(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 1..n {
        let p2 = ((2 * k + 1) as f64 * x * p1 - k as f64 * p0) / (k + 1) as f64;
        p0 = p1;
        p1 = p2;
    }
    (p1, n as f64 * (x * p1 - p0) / (x * x - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        // Order n integrates x^k exactly for k <= 2n - 1.
        let (x, w) = gauss_legendre(32);
        assert!((w.iter().map(|&w| w as f64).sum::<f64>() - 2.0).abs() < 1e-6);
        for k in [2, 10, 40, 62] {
            let q: f64 = x.iter().zip(&w).map(|(&x, &w)| w as f64 * (x as f64).powi(k)).sum();
            assert!((q - 2.0 / (k + 1) as f64).abs() < 1e-5, "x^{k}: {q}");
        }
    }

    #[test]
    fn smooth_limit_matches_the_smooth_coating() {
        // At alpha -> 0 the rough transmittance tends to 1 - F(cos) and the
        // internal reflectance to the diffuse Fresnel reflectance from inside
        // (which Mitsuba's smooth plastic takes from a fit, to about 1%).
        let t = coating_tables(MicrofacetKind::Ggx, 1e-3, 1.5);
        for i in [8, 32, 63] {
            let mu = i as f32 / 63.0;
            let smooth = 1.0 - fresnel_dielectric(mu, 1.5);
            assert!((t.transmittance[i] - smooth).abs() < 2e-3, "{mu}: {} vs {smooth}", t.transmittance[i]);
        }
        let fdr = super::super::fresnel_diffuse_reflectance(1.0 / 1.5);
        assert!((t.internal_reflectance - fdr).abs() < 0.02, "{} vs {fdr}", t.internal_reflectance);
    }
}
