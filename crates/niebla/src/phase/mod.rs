//! Phase functions: the angular distribution of light scattered in a medium.
//!
//! # Convention (the one place it is written; also in ARCHITECTURE.md)
//!
//! `p(wo, wi)` takes two unit directions that both point AWAY from the
//! scattering point, as in pbrt-v4 and Mitsuba 3:
//! - `wo` points toward the eye (the previous vertex of a path traced from the
//!   camera),
//! - `wi` points toward the light (the next vertex).
//!
//! Light arrives travelling along `-wi` and leaves along `wo`, so the cosine of
//! the scattering angle theta (between the incident and the scattered
//! propagation directions) is
//!
//! `mu = cos(theta) = -dot(wo, wi)`,
//!
//! and `mu = +1` (`wi = -wo`) is forward scattering: the light continues in
//! its direction of travel toward the eye. `g > 0` means forward scattering,
//! and Henyey-Greenstein reads `(1 - g^2) / (4 pi (1 + g^2 + 2 g dot(wo, wi))^1.5)`.
//! (pbrt-v2 used `w' = -wi` and the sign `- 2 g cos`; mixing the two turns
//! forward into backward scattering.)
//!
//! Every phase function is normalized, `integral over the sphere of p(wo, wi) dwi = 1`
//! (units 1/sr), reciprocal (`p(wo, wi) = p(wi, wo)`) and depends on `mu` only.
//! `sample(wo, u)` draws `wi` around the continuing direction `-wo`, and every
//! sampler here is exact: its density is the phase function itself, so
//! `pdf(wo, wi) == eval(wo, wi)` and `value / pdf == 1`.
//!
//! Numerics: directions are `f32`; the complements `1 - mu` and `1 + mu` are
//! computed from `|wo + wi|^2 / 2` and `|wo - wi|^2 / 2` ([`ScatteringCosine`]),
//! which keeps peaked lobes (HG with g = 0.99, the 381/sr Mie fog peak)
//! accurate within a few hundredths of a degree of forward.

mod cornette_shanks;
mod double_hg;
mod error;
mod fog;
mod hg;
mod isotropic;
mod rayleigh;
mod schlick;
mod tabulated;
mod tabulated_csv;
#[cfg(test)]
mod tests;

pub use cornette_shanks::CornetteShanks;
pub use double_hg::DoubleHg;
pub use error::PhaseError;
pub use fog::{FOG_G1, FOG_G2, FOG_MEAN_COSINE, FOG_W, MIE_FOG_COLUMN, MIE_FOG_CSV};
pub use hg::{HenyeyGreenstein, MAX_HG_ASYMMETRY};
pub use isotropic::Isotropic;
pub use rayleigh::Rayleigh;
pub use schlick::{k_for_mean_cosine, k_from_g, schlick_mean_cosine, Schlick};
pub use tabulated::Tabulated;

use crate::math::{spherical_direction, Frame, Vec2, Vec3, PI};
use std::sync::Arc;

/// Result of sampling a phase function: the direction `wi` (unit, pointing
/// away from the scattering point toward the next vertex), the phase function
/// value `p(wo, wi)` in 1/sr and the density of the sample per steradian.
/// For every function in this module `value == pdf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseSample {
    /// Sampled direction toward the next vertex (light side), unit length.
    pub wi: Vec3,
    /// `p(wo, wi)`, 1/sr.
    pub value: f32,
    /// Density of `wi` under the sampler, 1/sr.
    pub pdf: f32,
}

/// The cosine `mu` of the scattering angle together with `1 - mu` and
/// `1 + mu`, each computed without cancellation so that peaked lobes are
/// evaluated accurately next to `mu = +-1`.
///
/// ```
/// use niebla::math::Vec3;
/// use niebla::phase::ScatteringCosine;
/// let wo = Vec3::Z;
/// let c = ScatteringCosine::from_directions(wo, -wo); // forward scattering
/// assert_eq!(c.mu, 1.0);
/// assert_eq!(c.one_minus_mu, 0.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScatteringCosine {
    /// `mu = cos(theta)`, in [-1, 1]; +1 is forward.
    pub mu: f32,
    /// `1 - mu = 2 sin^2(theta / 2)`, in [0, 2].
    pub one_minus_mu: f32,
    /// `1 + mu = 2 cos^2(theta / 2)`, in [0, 2].
    pub one_plus_mu: f32,
}

impl ScatteringCosine {
    /// From the two directions of the convention (both pointing away from the
    /// scattering point): `1 - mu = |wo + wi|^2 / 2`, `1 + mu = |wo - wi|^2 / 2`.
    /// Symmetric in `wo` and `wi` bit for bit.
    #[inline]
    pub fn from_directions(wo: Vec3, wi: Vec3) -> ScatteringCosine {
        let one_minus_mu = 0.5 * (wo + wi).length_squared();
        let one_plus_mu = 0.5 * (wo - wi).length_squared();
        ScatteringCosine::from_complements(one_minus_mu, one_plus_mu)
    }

    /// From `mu` alone (precision limited to that of `mu` next to +-1).
    #[inline]
    pub fn from_mu(mu: f32) -> ScatteringCosine {
        let mu = mu.clamp(-1.0, 1.0);
        ScatteringCosine { mu, one_minus_mu: 1.0 - mu, one_plus_mu: 1.0 + mu }
    }

    /// From the scattering angle `theta` in radians (0 = forward), in double
    /// precision before rounding.
    pub fn from_theta(theta: f64) -> ScatteringCosine {
        let (sin_half, cos_half) = (0.5 * theta).sin_cos();
        ScatteringCosine {
            mu: theta.cos() as f32,
            one_minus_mu: (2.0 * sin_half * sin_half) as f32,
            one_plus_mu: (2.0 * cos_half * cos_half) as f32,
        }
    }

    /// From `1 - mu` and `1 + mu`: the smaller one is kept (it carries the
    /// precision) and the other becomes `2 -` it, so the two always add to 2
    /// within one rounding.
    #[inline]
    pub fn from_complements(one_minus_mu: f32, one_plus_mu: f32) -> ScatteringCosine {
        if one_minus_mu <= one_plus_mu {
            let one_minus_mu = one_minus_mu.clamp(0.0, 1.0);
            ScatteringCosine { mu: 1.0 - one_minus_mu, one_minus_mu, one_plus_mu: 2.0 - one_minus_mu }
        } else {
            let one_plus_mu = one_plus_mu.clamp(0.0, 1.0);
            ScatteringCosine { mu: one_plus_mu - 1.0, one_minus_mu: 2.0 - one_plus_mu, one_plus_mu }
        }
    }

    /// `mu` in double precision, from the smaller complement (for table lookups).
    #[inline]
    pub fn mu_f64(&self) -> f64 {
        let mu = if self.one_minus_mu <= self.one_plus_mu {
            1.0 - self.one_minus_mu as f64
        } else {
            self.one_plus_mu as f64 - 1.0
        };
        mu.clamp(-1.0, 1.0)
    }

    /// `sin(theta) = sqrt((1 - mu)(1 + mu))`.
    #[inline]
    pub fn sin_theta(&self) -> f32 {
        (self.one_minus_mu * self.one_plus_mu).max(0.0).sqrt()
    }
}

/// A phase function, dispatched by `match`: a closed set, so the per-sample
/// path has no virtual call.
/// See the module documentation for the direction convention.
///
/// ```
/// use niebla::math::{Vec2, Vec3};
/// use niebla::phase::PhaseFunction;
/// let phase = PhaseFunction::hg(0.9);
/// let wo = Vec3::Z;
/// // Forward scattering (wi = -wo) dominates backward (wi = wo).
/// assert!(phase.eval(wo, -wo) > 1000.0 * phase.eval(wo, wo));
/// let s = phase.sample(wo, Vec2::new(0.3, 0.7)).unwrap();
/// assert_eq!(s.pdf, phase.pdf(wo, s.wi));
/// ```
#[derive(Clone, Debug)]
pub enum PhaseFunction {
    /// Uniform over the sphere, `1 / (4 pi)`.
    Isotropic,
    /// Henyey-Greenstein (1941).
    HenyeyGreenstein(HenyeyGreenstein),
    /// Two-lobe Henyey-Greenstein mixture.
    DoubleHg(DoubleHg),
    /// Schlick's rational approximation (Blasi, Le Saec, Schlick 1993).
    Schlick(Schlick),
    /// Rayleigh, `3 (1 + mu^2) / (16 pi)`.
    Rayleigh,
    /// Cornette and Shanks (1992).
    CornetteShanks(CornetteShanks),
    /// Tabulated over the scattering angle (e.g. Mie fog), shared.
    Tabulated(Arc<Tabulated>),
}

impl PhaseFunction {
    /// `p(wo, wi)` in 1/sr; both directions point away from the scattering point.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.eval_cosine(ScatteringCosine::from_directions(wo, wi))
    }

    /// `p` as a function of the scattering cosine, 1/sr.
    #[inline]
    pub fn eval_cosine(&self, c: ScatteringCosine) -> f32 {
        match self {
            PhaseFunction::Isotropic => Isotropic.eval_cosine(c),
            PhaseFunction::HenyeyGreenstein(f) => f.eval_cosine(c),
            PhaseFunction::DoubleHg(f) => f.eval_cosine(c),
            PhaseFunction::Schlick(f) => f.eval_cosine(c),
            PhaseFunction::Rayleigh => Rayleigh.eval_cosine(c),
            PhaseFunction::CornetteShanks(f) => f.eval_cosine(c),
            PhaseFunction::Tabulated(f) => f.eval_cosine(c),
        }
    }

    /// `p(mu)` in 1/sr, `mu = -dot(wo, wi)` the scattering cosine.
    #[inline]
    pub fn eval_mu(&self, mu: f32) -> f32 {
        self.eval_cosine(ScatteringCosine::from_mu(mu))
    }

    /// Density of [`PhaseFunction::sample`] at `wi`, per steradian. Every
    /// sampler in this module is exact, so this equals [`PhaseFunction::eval`].
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.eval(wo, wi)
    }

    /// Sample `wi` given `wo` (unit, toward the previous vertex) and two
    /// uniform numbers in [0, 1): `u.x` picks the scattering cosine, `u.y` the
    /// azimuth around `-wo`. `None` only if Cornette-Shanks' rejection loop
    /// exhausts its attempts (probability below 1e-30).
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<PhaseSample> {
        debug_assert!((wo.length_squared() - 1.0).abs() < 1e-3, "wo must be unit");
        let c = match self {
            PhaseFunction::Isotropic => Isotropic.sample_cosine(u.x),
            PhaseFunction::HenyeyGreenstein(f) => f.sample_cosine(u.x),
            PhaseFunction::DoubleHg(f) => f.sample_cosine(u.x),
            PhaseFunction::Schlick(f) => f.sample_cosine(u.x),
            PhaseFunction::Rayleigh => Rayleigh.sample_cosine(u.x),
            PhaseFunction::CornetteShanks(f) => f.sample_cosine(u.x, cornette_shanks::rejection_key(u))?,
            PhaseFunction::Tabulated(f) => f.sample_cosine(u.x),
        };
        let wi = direction_from_cosine(wo, c, u.y);
        // Evaluated from the returned (rounded) direction, so that
        // `pdf(wo, s.wi) == s.pdf` holds bit for bit.
        let value = self.eval(wo, wi);
        Some(PhaseSample { wi, value, pdf: value })
    }

    /// Mean cosine `<mu> = integral of p mu over the sphere` (the asymmetry
    /// parameter that drives multiple scattering).
    pub fn mean_cosine(&self) -> f32 {
        match self {
            PhaseFunction::Isotropic => Isotropic.mean_cosine(),
            PhaseFunction::HenyeyGreenstein(f) => f.mean_cosine(),
            PhaseFunction::DoubleHg(f) => f.mean_cosine(),
            PhaseFunction::Schlick(f) => f.mean_cosine(),
            PhaseFunction::Rayleigh => Rayleigh.mean_cosine(),
            PhaseFunction::CornetteShanks(f) => f.mean_cosine(),
            PhaseFunction::Tabulated(f) => f.mean_cosine(),
        }
    }

    /// A short name for logs and plots (`"hg"`, `"mie_fog"` is `"tabulated"`).
    pub fn name(&self) -> &'static str {
        match self {
            PhaseFunction::Isotropic => "isotropic",
            PhaseFunction::HenyeyGreenstein(_) => "hg",
            PhaseFunction::DoubleHg(_) => "double_hg",
            PhaseFunction::Schlick(_) => "schlick",
            PhaseFunction::Rayleigh => "rayleigh",
            PhaseFunction::CornetteShanks(_) => "cornette_shanks",
            PhaseFunction::Tabulated(_) => "tabulated",
        }
    }

    /// Isotropic phase function, `1 / (4 pi)` per steradian.
    pub fn isotropic() -> PhaseFunction {
        PhaseFunction::Isotropic
    }

    /// Henyey-Greenstein with asymmetry `g`; see [`HenyeyGreenstein::new`].
    ///
    /// # Panics
    /// If `g` is not in (-1, 1); use [`HenyeyGreenstein::new`] for user input.
    pub fn hg(g: f32) -> PhaseFunction {
        PhaseFunction::HenyeyGreenstein(HenyeyGreenstein::new(g).unwrap_or_else(|e| panic!("{e}")))
    }

    /// `w HG(g1) + (1 - w) HG(g2)`; see [`DoubleHg::new`].
    ///
    /// # Panics
    /// On parameters out of range; use [`DoubleHg::new`] for user input.
    pub fn double_hg(w: f32, g1: f32, g2: f32) -> PhaseFunction {
        PhaseFunction::DoubleHg(DoubleHg::new(w, g1, g2).unwrap_or_else(|e| panic!("{e}")))
    }

    /// Schlick with parameter `k` (not `g`); see [`Schlick::new`].
    ///
    /// # Panics
    /// If `k` is not in (-1, 1); use [`Schlick::new`] for user input.
    pub fn schlick(k: f32) -> PhaseFunction {
        PhaseFunction::Schlick(Schlick::new(k).unwrap_or_else(|e| panic!("{e}")))
    }

    /// Rayleigh, `3 (1 + mu^2) / (16 pi)` per steradian.
    pub fn rayleigh() -> PhaseFunction {
        PhaseFunction::Rayleigh
    }

    /// Cornette-Shanks with HG parameter `g` (its mean cosine is not `g`);
    /// see [`CornetteShanks::new`].
    ///
    /// # Panics
    /// If `g` is not in (-1, 1); use [`CornetteShanks::new`] for user input.
    pub fn cornette_shanks(g: f32) -> PhaseFunction {
        PhaseFunction::CornetteShanks(CornetteShanks::new(g).unwrap_or_else(|e| panic!("{e}")))
    }

    /// A tabulated phase function.
    pub fn tabulated(table: Tabulated) -> PhaseFunction {
        PhaseFunction::Tabulated(Arc::new(table))
    }

    /// Fog for multiple-scattering transport: the two-lobe HG fit of the Mie
    /// phase function of a polydisperse water fog (r_eff 8 um, 550 nm) with
    /// the Mie mean cosine kept exactly, [`FOG_W`], [`FOG_G1`], [`FOG_G2`]
    /// (reference/mie_fog_fit.json, case `poly`). Mean cosine 0.86001.
    pub fn fog() -> PhaseFunction {
        PhaseFunction::DoubleHg(fog::fog_double_hg())
    }

    /// Fog where the look of single scattering matters (forward peak, fog bow,
    /// glory): the tabulated Mie phase function of the same fog, column
    /// [`MIE_FOG_COLUMN`] of the shipped `data/mie_fog_phase.csv`. Parsed once
    /// and shared.
    pub fn mie_fog() -> PhaseFunction {
        PhaseFunction::Tabulated(fog::mie_fog_table())
    }
}

/// The direction `wi` whose scattering cosine relative to `wo` is `c`, at
/// azimuth `2 pi u_phi` around the continuing direction `-wo`.
#[inline]
fn direction_from_cosine(wo: Vec3, c: ScatteringCosine, u_phi: f32) -> Vec3 {
    let frame = Frame::from_z(-wo);
    frame.to_world(spherical_direction(c.sin_theta(), c.mu, 2.0 * PI * u_phi))
}
