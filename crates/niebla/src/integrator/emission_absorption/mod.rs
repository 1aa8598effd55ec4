//! The emission-absorption integrator (pbrt-v2 `EmissionIntegrator`; Max 1995):
//! radiance emitted by media, attenuated by extinction, no in-scattering.

pub(crate) mod settings;

use crate::color::Rgb;
use crate::math::Ray;
use crate::medium::MediumPoint;
use crate::medium::{Medium, MediumId};
use crate::sampling::PixelSampler;
use crate::tracking::{medium_range, segment_transmittance, MarchStep, TransmittanceMethod};
use crate::world::Scene;

use super::{
    camera_layout, default_march_step, negligible_distance, trace_laid_out_camera_ray, Integrator, SegmentRadiance,
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
    fn radiance(&self, scene: &Scene, ray: Ray, medium: Option<MediumId>, sampler: &mut PixelSampler) -> Rgb {
        let diagonal = scene.diagonal();
        trace_laid_out_camera_ray(scene, ray, medium, self.transmittance, sampler, |m, _, ray, t_end, sampler| {
            emission_segment(m, ray, t_end, self.step, self.transmittance, diagonal, sampler)
        })
    }
}

/// Emission integral and transmittance over `[0, t_end)` of `ray` in medium `m`.
/// Homogeneous media with analytic transmittance use the closed form;
/// otherwise the emission integral is ray marched over the part of the
/// segment where the medium is, with the transmittance between march points
/// from `method`. Unbounded homogeneous segments are cut where their
/// remaining contribution is below 1e-6 (or at 1000 scene diagonals for
/// channels without extinction).
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
        return SegmentRadiance { radiance, transmittance };
    }
    // Slots of the camera-ray layout (no-ops outside a laid-out walk).
    if !m.is_emissive() {
        camera_layout::enter(sampler, camera_layout::TRANSMITTANCE);
        return SegmentRadiance {
            radiance: Rgb::ZERO,
            transmittance: segment_transmittance(m, ray, 0.0, t_end, method, sampler),
        };
    }
    let Some((t_a, t_b)) = marched_range(m, ray, t_end, diagonal) else {
        return SegmentRadiance { radiance: Rgb::ZERO, transmittance: Rgb::ONE };
    };
    let step = step.unwrap_or_else(|| default_march_step(m.max_sigma_t(), diagonal));
    camera_layout::enter(sampler, camera_layout::EMISSION_JITTER);
    let mut s = march_segment(m, ray, t_a, t_b, step, method, sampler, |mp, _, _| mp.l_ve);
    if !t_end.is_finite() && m.as_homogeneous().is_some() {
        s.transmittance = segment_transmittance(m, ray, 0.0, t_end, method, sampler);
    }
    s
}

/// The range `[t_a, t_b]` of `[0, t_end)` that is ray marched: the medium's
/// extent (a grid's box), with unbounded homogeneous segments cut where their
/// remaining contribution is negligible (see [`emission_segment`]).
pub(crate) fn marched_range(m: &Medium, ray: &Ray, t_end: f32, diagonal: f32) -> Option<(f32, f32)> {
    let (t_a, t_b) = medium_range(m, ray, 0.0, t_end)?;
    if t_b.is_finite() {
        return Some((t_a, t_b));
    }
    let sigma_t = m.as_homogeneous().map_or(Rgb::splat(m.max_sigma_t()), |h| h.sigma_t());
    Some((t_a, t_a + negligible_distance(sigma_t).unwrap_or(1000.0 * diagonal.max(1.0))))
}

/// Jittered ray march of `integral T(t_a, t) S(t) dt` over `[t_a, t_b]` in
/// medium `m`, where `source(point, position, sampler)` gives `S`: samples at
/// `t_a + (i + u) dt`. The transmittance from one sample to the next is the
/// extinction at the sample times the step for `RayMarch` (pbrt-v2's scheme,
/// biased, consistent) and an estimate by `method` otherwise (exact for a
/// homogeneous medium, unbiased trackers for grids), so that with an
/// unbiased `method` the stratified sum is an unbiased estimate of the
/// integral. Returns the integral and the transmittance over `[t_a, t_b]`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn march_segment(
    m: &Medium,
    ray: &Ray,
    t_a: f32,
    t_b: f32,
    step: MarchStep,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
    mut source: impl FnMut(&MediumPoint, crate::math::Vec3, &mut PixelSampler) -> Rgb,
) -> SegmentRadiance {
    let n = step.count_for(t_b - t_a);
    let dt = (t_b - t_a) / n as f32;
    let u = sampler.next_1d();
    let mut tr = Rgb::ONE;
    let mut l = Rgb::ZERO;
    let mut t_prev = t_a;
    let mut sigma_t = Rgb::ZERO;
    for i in 0..n {
        let t = t_a + (i as f32 + u) * dt;
        let p = ray.at(t);
        let mp = m.at_time(p, sampler.time());
        sigma_t = mp.sigma_t();
        // Step `i`'s tracking numbers (a no-op outside a laid-out walk).
        camera_layout::enter_march_step(sampler, i, camera_layout::STEP_TRANSMITTANCE);
        tr *= step_transmittance(m, ray, t_prev, t, sigma_t, method, sampler);
        if tr.max_channel() <= 0.0 {
            return SegmentRadiance { radiance: l, transmittance: Rgb::ZERO };
        }
        let s = source(&mp, p, sampler);
        l += tr * s * dt;
        t_prev = t;
    }
    camera_layout::enter_march_step(sampler, n, camera_layout::STEP_TRANSMITTANCE);
    tr *= step_transmittance(m, ray, t_prev, t_b, sigma_t, method, sampler);
    SegmentRadiance { radiance: l, transmittance: tr }
}

/// Transmittance between consecutive march points.
#[inline]
fn step_transmittance(
    m: &Medium,
    ray: &Ray,
    t0: f32,
    t1: f32,
    sigma_t_at_t1: Rgb,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
) -> Rgb {
    match method {
        TransmittanceMethod::RayMarch(_) => (sigma_t_at_t1 * (t1 - t0)).exp_neg(),
        _ => segment_transmittance(m, ray, t0, t1, method, sampler),
    }
}

#[cfg(test)]
#[path = "tests.rs"]
mod tests;
