//! The emission-absorption integrator (pbrt-v2 `EmissionIntegrator`; Max 1995):
//! radiance emitted by media, attenuated by extinction, no in-scattering.

use crate::color::Rgb;
use crate::math::Ray;
use crate::medium::{Medium, MediumId};
use crate::sampling::PixelSampler;
use crate::scene::Scene;
use crate::tracking::{MarchStep, TransmittanceMethod};

use super::{
    default_march_step, negligible_distance, trace_camera_ray, Integrator, SegmentRadiance,
};

/// Emission and absorption only. With `TransmittanceMethod::Analytic` a
/// homogeneous segment is integrated in closed form,
/// `L_ve (1 - exp(-sigma_t d)) / sigma_t`; otherwise the emission integral is
/// ray marched with a jittered start.
#[derive(Clone, Copy, Debug)]
pub struct EmissionIntegrator {
    /// Ray-march step; `None` picks [`default_march_step`] per medium.
    pub step: Option<MarchStep>,
    /// Transmittance estimator.
    pub transmittance: TransmittanceMethod,
}

impl Integrator for EmissionIntegrator {
    fn radiance(
        &self,
        scene: &Scene,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut PixelSampler,
    ) -> Rgb {
        let diagonal = scene.diagonal();
        trace_camera_ray(
            scene,
            ray,
            medium,
            self.transmittance,
            sampler,
            |m, _, ray, t_end, sampler| {
                emission_segment(
                    m,
                    ray,
                    t_end,
                    self.step,
                    self.transmittance,
                    diagonal,
                    sampler,
                )
            },
        )
    }
}

/// Emission integral and transmittance over `[0, t_end)` of `ray` in medium `m`.
/// Unbounded segments are cut where their remaining contribution is below 1e-6
/// (or at 1000 scene diagonals for channels without extinction).
pub(crate) fn emission_segment(
    m: &Medium,
    ray: &Ray,
    t_end: f32,
    step: Option<MarchStep>,
    method: TransmittanceMethod,
    diagonal: f32,
    sampler: &mut PixelSampler,
) -> SegmentRadiance {
    if let (Some(h), TransmittanceMethod::Analytic) = (m.as_homogeneous(), method) {
        let sigma_t = h.sigma_t();
        let transmittance = (sigma_t * t_end).map(|x| if x.is_nan() { 1.0 } else { (-x).exp() });
        let cap = 1000.0 * diagonal.max(1.0);
        let radiance = Rgb(std::array::from_fn(|c| {
            let (s, l) = (sigma_t[c], h.l_ve[c]);
            if l == 0.0 {
                0.0
            } else if s > 0.0 {
                l * (-(-s * t_end).exp_m1()) / s
            } else {
                l * t_end.min(cap)
            }
        }));
        return SegmentRadiance {
            radiance,
            transmittance,
        };
    }
    let t_max = bounded_length(m, t_end, diagonal);
    let step = step.unwrap_or_else(|| default_march_step(m.max_sigma_t(), diagonal));
    march_segment(ray, t_max, step, sampler.next_1d(), |p| {
        let mp = m.at(p);
        (mp.sigma_t(), mp.l_ve)
    })
}

/// Length over which an unbounded segment is integrated (see [`emission_segment`]).
pub(crate) fn bounded_length(m: &Medium, t_end: f32, diagonal: f32) -> f32 {
    if t_end.is_finite() {
        return t_end;
    }
    let sigma_t = match m.as_homogeneous() {
        Some(h) => h.sigma_t(),
        None => Rgb::splat(m.max_sigma_t()),
    };
    negligible_distance(sigma_t).unwrap_or(1000.0 * diagonal.max(1.0))
}

/// Jittered ray march of `integral T(0, t) S(t) dt` over `[0, t_max]`, where
/// `source(p)` returns `(sigma_t, S)` at a point: samples at `(i + u) dt`, the
/// transmittance to each sample accumulated step by step with the extinction
/// at the step's end (pbrt-v2's scheme; exact for homogeneous media).
pub(crate) fn march_segment(
    ray: &Ray,
    t_max: f32,
    step: MarchStep,
    u: f32,
    mut source: impl FnMut(crate::math::Vec3) -> (Rgb, Rgb),
) -> SegmentRadiance {
    let n = step.count_for(t_max);
    let dt = t_max / n as f32;
    let mut tr = Rgb::ONE;
    let mut l = Rgb::ZERO;
    let mut t_prev = 0.0;
    let mut sigma_t = Rgb::ZERO;
    for i in 0..n {
        let t = (i as f32 + u) * dt;
        let (st, s) = source(ray.at(t));
        sigma_t = st;
        tr *= (sigma_t * (t - t_prev)).exp_neg();
        l += tr * s * dt;
        t_prev = t;
        if tr.max_channel() < 1e-7 {
            return SegmentRadiance {
                radiance: l,
                transmittance: Rgb::ZERO,
            };
        }
    }
    tr *= (sigma_t * (t_max - t_prev)).exp_neg();
    SegmentRadiance {
        radiance: l,
        transmittance: tr,
    }
}
