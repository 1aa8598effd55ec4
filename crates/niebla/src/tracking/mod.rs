//! Transmittance estimators along one medium segment of a ray.
//!
//! This is the interface that the heterogeneous-media work extends with delta,
//! ratio and residual ratio tracking over majorant segments: every estimator
//! takes a medium, a ray, a parameter range and random numbers, and returns a
//! per-channel transmittance estimate.

mod along_ray;
mod collision;
mod distance;
mod free_flight;
mod grid_dispatch;
mod ray_march;
mod trackers;

pub use along_ray::{DensityAlongRay, DensitySegment, GridAlongRay, GridLookup, UnitDensity};
pub use collision::{pass_through_weight, CollisionEvent, NullWeights};
pub use distance::MajorantProfile;
pub use free_flight::{sample_t_maj, sample_t_maj_without_emission, MajorantCollision};
pub use grid_dispatch::{with_grid_along_ray, GridRayVisitor};
pub use ray_march::{ray_march_optical_depth, MarchStep};
pub use trackers::{delta_tracking, ratio_tracking, residual_ratio_tracking, residual_ratio_tracking_with};

use crate::color::Rgb;
use crate::math::Ray;
use crate::medium::{GridMedium, Medium};
use crate::sampling::PixelSampler;

/// How transmittance along a segment is estimated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TransmittanceMethod {
    /// Closed form `exp(-sigma_t d)` for homogeneous media; heterogeneous media
    /// have none and use ratio tracking instead (unbiased).
    Analytic,
    /// Deterministic ray marching with one jittered offset (pbrt-v2
    /// `DensityRegion::tau`): unbiased optical depth, but `exp(-tau_hat)` is
    /// biased upward; consistent as the step shrinks.
    RayMarch(MarchStep),
    /// Delta tracking: a binary (0 or weight) estimate per call.
    Delta,
    /// Ratio tracking.
    Ratio,
    /// Residual ratio tracking with a per-cell control extinction.
    ResidualRatio,
}

/// Transmittance estimate over `[t0, t1]` of `ray` inside `medium`.
/// `t1` may be infinite (an unbounded medium along an escaping ray).
#[inline]
pub fn segment_transmittance(
    medium: &Medium,
    ray: &Ray,
    t0: f32,
    t1: f32,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
) -> Rgb {
    if !(t1 > t0) {
        return Rgb::ONE;
    }
    match medium {
        Medium::Homogeneous(h) => {
            let sigma_t = h.sigma_t();
            if !t1.is_finite() {
                // Only the closed form handles an unbounded homogeneous segment.
                return medium.exact_optical_depth(ray, t0, t1).unwrap_or(Rgb::ZERO).exp_neg();
            }
            let r = UnitDensity { t0, t1 };
            match method {
                TransmittanceMethod::Analytic => (sigma_t * (t1 - t0)).exp_neg(),
                TransmittanceMethod::RayMarch(step) => {
                    let u = sampler.next_1d();
                    ray_march_optical_depth(|_| sigma_t, t0, t1, step, u).exp_neg()
                }
                TransmittanceMethod::Delta => delta_tracking(&r, sigma_t, sampler),
                TransmittanceMethod::Ratio => ratio_tracking(&r, sigma_t, sampler),
                TransmittanceMethod::ResidualRatio => residual_ratio_tracking(&r, sigma_t, sampler),
            }
        }
        Medium::Grid(g) => grid_transmittance(g, ray, t0, t1, method, sampler),
    }
}

/// [`segment_transmittance`] in a grid medium: the density grid's type is
/// matched once, then the tracker runs concretely.
fn grid_transmittance(
    g: &GridMedium,
    ray: &Ray,
    t0: f32,
    t1: f32,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
) -> Rgb {
    let Some((a, b)) = g.clip(ray, t0, t1) else {
        return Rgb::ONE;
    };
    struct Track<'a> {
        sigma_t: Rgb,
        method: TransmittanceMethod,
        sampler: &'a mut PixelSampler,
    }
    impl GridRayVisitor for Track<'_> {
        type Output = Rgb;
        #[inline]
        fn visit<G: GridLookup>(self, r: &GridAlongRay<'_, G>) -> Rgb {
            run_tracker(r, self.sigma_t, r.t0, r.t1, self.method, self.sampler)
        }
    }
    let time = sampler.time();
    // Only residual ratio tracking reads the minima; the other trackers skip
    // zero-majorant cells without drawing a random number, so leaving the
    // minima out (and with them those cells) changes no estimate.
    let with_minorant = method == TransmittanceMethod::ResidualRatio;
    let track = Track { sigma_t: g.sigma_t(), method, sampler };
    with_grid_along_ray(g, g.ray_to_grid(ray), (a, b), time, with_minorant, track)
}

#[inline]
fn run_tracker<R: DensityAlongRay>(
    r: &R,
    sigma_t: Rgb,
    t0: f32,
    t1: f32,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
) -> Rgb {
    match method {
        TransmittanceMethod::RayMarch(step) => {
            let u = sampler.next_1d();
            if r.zero_outside_segments() {
                ray_march::ray_march_occupied(r, sigma_t, t0, t1, step, u).exp_neg()
            } else {
                ray_march_optical_depth(|t| sigma_t * r.density(t), t0, t1, step, u).exp_neg()
            }
        }
        TransmittanceMethod::Delta => delta_tracking(r, sigma_t, sampler),
        TransmittanceMethod::Analytic | TransmittanceMethod::Ratio => ratio_tracking(r, sigma_t, sampler),
        TransmittanceMethod::ResidualRatio => residual_ratio_tracking(r, sigma_t, sampler),
    }
}

/// The piecewise-exponential distance-sampling profile of `ray` over
/// `[t0, t1]` in `medium`: rate `d_max * rate_per_density` per majorant
/// segment (one segment for a homogeneous medium).
pub fn majorant_profile(medium: &Medium, ray: &Ray, t0: f32, t1: f32, rate_per_density: f32) -> MajorantProfile {
    match medium {
        Medium::Homogeneous(_) => MajorantProfile::new(&UnitDensity { t0, t1 }, rate_per_density),
        Medium::Grid(g) => {
            let Some((a, b)) = g.clip(ray, t0, t1) else {
                return MajorantProfile::default();
            };
            struct Profile(f32);
            impl GridRayVisitor for Profile {
                type Output = MajorantProfile;
                #[inline]
                fn visit<G: GridLookup>(self, r: &GridAlongRay<'_, G>) -> MajorantProfile {
                    MajorantProfile::new(r, self.0)
                }
            }
            with_grid_along_ray(g, g.ray_to_grid(ray), (a, b), 0.0, false, Profile(rate_per_density))
        }
    }
}

/// The part of `[t0, t1]` of `ray` where `medium` can be non-zero: all of it
/// for a homogeneous medium, the grid's box for a grid medium.
#[inline]
pub fn medium_range(medium: &Medium, ray: &Ray, t0: f32, t1: f32) -> Option<(f32, f32)> {
    match medium {
        Medium::Homogeneous(_) => (t1 > t0).then_some((t0, t1)),
        Medium::Grid(g) => g.clip(ray, t0, t1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::medium::HomogeneousMedium;
    use crate::phase::PhaseFunction;

    fn fog(sigma_a: Rgb, sigma_s: Rgb) -> Medium {
        Medium::Homogeneous(HomogeneousMedium { sigma_a, sigma_s, l_ve: Rgb::ZERO, phase: PhaseFunction::Isotropic })
    }

    #[test]
    fn closed_form_and_ray_marched_transmittance_match_beer_lambert() {
        let m = fog(Rgb::new(0.1, 0.2, 0.3), Rgb::new(0.5, 0.25, 0.0));
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        let mut s = PixelSampler::from_key(1);
        for d in [0.01f32, 0.5, 2.0, 7.5] {
            let exact = Rgb::new(0.6, 0.45, 0.3).map(|st| (-st * d).exp());
            for method in [
                TransmittanceMethod::Analytic,
                TransmittanceMethod::RayMarch(MarchStep::Length(0.1)),
                TransmittanceMethod::RayMarch(MarchStep::Count(3)),
            ] {
                let t = segment_transmittance(&m, &ray, 1.0, 1.0 + d, method, &mut s);
                for c in 0..3 {
                    // f32 closed form: relative error a few ulps.
                    assert!((t[c] - exact[c]).abs() <= 1e-5 * exact[c].max(1e-3), "{method:?} d={d} c={c}");
                }
            }
        }
        // An unbounded segment: zero where sigma_t > 0.
        let t = segment_transmittance(&m, &ray, 0.0, f32::INFINITY, TransmittanceMethod::Analytic, &mut s);
        assert_eq!(t, Rgb::ZERO);
        let clear = fog(Rgb::ZERO, Rgb::ZERO);
        let t = segment_transmittance(&clear, &ray, 0.0, f32::INFINITY, TransmittanceMethod::Analytic, &mut s);
        assert_eq!(t, Rgb::ONE);
    }
}
