//! Unbiased transmittance estimators over majorant segments (Novák et al.
//! 2014, "Residual ratio tracking for estimating attenuation in
//! participating media"; Woodcock et al. 1965 for delta tracking): delta tracking (binary, weighted for chromatic
//! media), ratio tracking and residual ratio tracking. Each takes the density
//! along a ray, the medium's extinction per unit density `sigma_t` (RGB) and
//! random numbers, and returns a per-channel estimate whose expectation is
//! `exp(-integral sigma_t density dt)`.

use std::ops::ControlFlow;

use crate::color::Rgb;
use crate::sampling::PixelSampler;

use super::along_ray::DensityAlongRay;

/// Exponential step with rate `sigma > 0`.
#[inline]
fn exponential_step(sampler: &mut PixelSampler, sigma: f32) -> f32 {
    -(1.0 - sampler.next_1d()).ln() / sigma
}

/// Russian roulette on a running transmittance (pbrt-v3's rule): below 0.1 the
/// estimate survives with probability `1 - max(0.05, 1 - T)` and is divided by
/// it. Returns `false` when the estimate was terminated (it is then zero).
#[inline]
fn roulette(tr: &mut Rgb, sampler: &mut PixelSampler) -> bool {
    let m = tr.max_channel().abs();
    if m < 0.1 {
        let q = (1.0 - m).max(0.05);
        if sampler.next_1d() < q {
            *tr = Rgb::ZERO;
            return false;
        }
        *tr /= 1.0 - q;
    }
    true
}

/// Ratio tracking (Cramer 1978; Novak, Selle, Jarosz 2014): tentative
/// collisions at the scalar majorant `d_max * max(sigma_t)`; at each the
/// estimate is multiplied by the null-collision probability per channel,
/// `1 - sigma_t density / sigma_maj`. Russian roulette below 0.1.
pub fn ratio_tracking<R: DensityAlongRay>(r: &R, sigma_t: Rgb, sampler: &mut PixelSampler) -> Rgb {
    let sigma_t_max = sigma_t.max_channel();
    let mut tr = Rgb::ONE;
    let _ = r.segments(|seg| {
        let sigma_maj = seg.d_max * sigma_t_max;
        if !(sigma_maj > 0.0) {
            return ControlFlow::Continue(());
        }
        let mut t = seg.t0;
        loop {
            t += exponential_step(sampler, sigma_maj);
            if !(t < seg.t1) {
                return ControlFlow::Continue(());
            }
            let density = r.density(t);
            tr *= Rgb::ONE - sigma_t * (density / sigma_maj);
            if !roulette(&mut tr, sampler) {
                return ControlFlow::Break(());
            }
        }
    });
    tr
}

/// Delta (Woodcock) tracking as a transmittance estimator: tentative
/// collisions at the scalar majorant; a collision is real with probability
/// `P = max_c sigma_t,c density / sigma_maj` and ends the estimate at 0.
/// For grey media this is the binary track-length estimator; for chromatic
/// media the null branch carries the per-channel weight
/// `(1 - sigma_t,c density / sigma_maj) / (1 - P)` (spectral tracking, Kutz
/// et al. 2017), which keeps every channel unbiased.
pub fn delta_tracking<R: DensityAlongRay>(r: &R, sigma_t: Rgb, sampler: &mut PixelSampler) -> Rgb {
    let sigma_t_max = sigma_t.max_channel();
    let mut tr = Rgb::ONE;
    let _ = r.segments(|seg| {
        let sigma_maj = seg.d_max * sigma_t_max;
        if !(sigma_maj > 0.0) {
            return ControlFlow::Continue(());
        }
        let mut t = seg.t0;
        loop {
            t += exponential_step(sampler, sigma_maj);
            if !(t < seg.t1) {
                return ControlFlow::Continue(());
            }
            let sigma = sigma_t * r.density(t);
            let p_real = (sigma.max_channel() / sigma_maj).min(1.0);
            if sampler.next_1d() < p_real {
                tr = Rgb::ZERO;
                return ControlFlow::Break(());
            }
            if p_real > 0.0 {
                tr *= (Rgb::ONE - sigma / sigma_maj) / (1.0 - p_real);
            }
        }
    });
    tr
}

/// Residual ratio tracking (Novak, Selle, Jarosz 2014): per segment a control
/// extinction `sigma_c = sigma_t d_c` is integrated in closed form and ratio
/// tracking runs on the residual `sigma_t (density - d_c)` with a residual
/// majorant of `sigma_t_max (d_max - d_min)`, the full density range.
///
/// Choice of control: the middle of the segment's density range when the
/// range's optical depth over the segment is at most 2, else `d_min`. With a
/// middle control and the full range as majorant every factor lies in
/// [0.5, 1.5], which gives a lower variance than ratio tracking at the same
/// number of lookups (`niebla bench trackers`: on the smoke scene, 3.6e-2
/// against 7.4e-2 for the half-range majorant). Over an optically thick range
/// products of factors above 1 become heavy tailed (unbiased, but the sample
/// mean converges very slowly), so there the control falls back to the
/// minimum, where every factor is in [0, 1]. Where the density is constant
/// over a segment no lookup is made at all.
pub fn residual_ratio_tracking<R: DensityAlongRay>(r: &R, sigma_t: Rgb, sampler: &mut PixelSampler) -> Rgb {
    residual_ratio_tracking_with(r, sigma_t, 2.0, sampler)
}

/// [`residual_ratio_tracking`] with the residual majorant set to
/// `majorant_scale` times the largest residual `sigma_t_max (d_max - d_min) / 2`
/// of a middle control (`majorant_scale >= 1`; 2 is the full range). The
/// control is the middle of the range when `majorant_scale * half_range *
/// sigma_t_max * length <= 2`, else `d_min` with the full range as majorant.
pub fn residual_ratio_tracking_with<R: DensityAlongRay>(
    r: &R,
    sigma_t: Rgb,
    majorant_scale: f32,
    sampler: &mut PixelSampler,
) -> Rgb {
    let sigma_t_max = sigma_t.max_channel();
    let mut tr = Rgb::ONE;
    let _ = r.segments(|seg| {
        let length = seg.t1 - seg.t0;
        let half_range = 0.5 * (seg.d_max - seg.d_min);
        let thin = majorant_scale * half_range * sigma_t_max * length <= 2.0;
        // Thick: control at the minimum and the range as majorant (ratio
        // tracking on the excess over the minimum, factors in [0, 1]).
        let (d_control, residual_majorant) = if thin {
            (seg.d_min + half_range, majorant_scale.max(1.0) * half_range)
        } else {
            (seg.d_min, 2.0 * half_range)
        };
        // Control: exact.
        tr *= (sigma_t * (d_control * length)).map(|x| if x.is_nan() { 0.0 } else { x }).exp_neg();
        let sigma_residual = residual_majorant * sigma_t_max;
        if tr.is_black() {
            return ControlFlow::Break(());
        }
        if !(sigma_residual > 0.0) {
            return ControlFlow::Continue(());
        }
        let mut t = seg.t0;
        loop {
            t += exponential_step(sampler, sigma_residual);
            if !(t < seg.t1) {
                return ControlFlow::Continue(());
            }
            let residual = sigma_t * (r.density(t) - d_control);
            tr *= Rgb::ONE - residual / sigma_residual;
            if !roulette(&mut tr, sampler) {
                return ControlFlow::Break(());
            }
        }
    });
    tr
}
