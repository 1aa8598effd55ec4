//! Free-flight sampling over majorant segments for the null-scattering path
//! integral (Miller, Georgiev, Jarosz 2019; pbrt-v4's `SampleT_maj`).
//!
//! Tentative collisions are sampled with the hero channel of the RGB majorant
//! `sigma_maj = d_max * sigma_t`; at each, the callback receives the point,
//! the coefficients there, `sigma_maj` and the majorant transmittance since
//! the previous collision, and decides (absorb, scatter, null) itself. The
//! function returns the majorant transmittance from the last collision to
//! the end of the range.

use crate::color::Rgb;
use crate::math::{Ray, Vec3};
use crate::medium::{GridMedium, Medium, MediumPoint};
use crate::sampling::PixelSampler;

use super::along_ray::{DensityAlongRay, GridAlongRay, GridLookup, UnitDensity};
use super::grid_dispatch::{with_grid_along_ray, GridRayVisitor};

/// A tentative collision handed to the callback of [`sample_t_maj`].
#[derive(Clone, Copy, Debug)]
pub struct MajorantCollision {
    /// Ray parameter of the collision.
    pub t: f32,
    /// World position.
    pub p: Vec3,
    /// Coefficients at `p`.
    pub point: MediumPoint,
    /// RGB majorant of the segment holding `p`.
    pub sigma_maj: Rgb,
    /// Majorant transmittance from the previous collision (or the start) to `p`.
    pub t_maj: Rgb,
}

/// Sample tentative collisions along `[0, t_max)` of `ray` in `medium` with
/// the majorant of channel `hero`. `callback(collision, sampler)` returns
/// `false` to stop (then the function returns `Rgb::ONE`); otherwise sampling
/// restarts at the collision (memorylessness). Returns the majorant
/// transmittance from the last collision to `t_max`.
pub fn sample_t_maj<F>(
    medium: &Medium,
    ray: &Ray,
    t_max: f32,
    hero: usize,
    sampler: &mut PixelSampler,
    callback: F,
) -> Rgb
where
    F: FnMut(MajorantCollision, &mut PixelSampler) -> bool,
{
    match medium {
        Medium::Homogeneous(h) => {
            let r = UnitDensity { t0: 0.0, t1: t_max };
            let point = h.point();
            walk(&r, h.sigma_t(), ray, hero, sampler, |_, _| point, callback)
        }
        Medium::Grid(g) => grid_flight(g, ray, t_max, hero, sampler, callback, |time| {
            move |p: Vec3, density: f32| g.point_with_density(p, density, time)
        }),
    }
}

/// [`sample_t_maj`] for estimators that never read emission (ratio and
/// delta tracking along shadow rays): the same collisions, random numbers
/// and coefficients `sigma_a`, `sigma_s`, but each collision's
/// `point.l_ve` is zero in grid media, whose emission fields (flame and
/// temperature grids, blackbody) are not looked up.
pub fn sample_t_maj_without_emission<F>(
    medium: &Medium,
    ray: &Ray,
    t_max: f32,
    hero: usize,
    sampler: &mut PixelSampler,
    callback: F,
) -> Rgb
where
    F: FnMut(MajorantCollision, &mut PixelSampler) -> bool,
{
    match medium {
        Medium::Homogeneous(_) => sample_t_maj(medium, ray, t_max, hero, sampler, callback),
        Medium::Grid(g) => grid_flight(g, ray, t_max, hero, sampler, callback, |time| {
            move |p: Vec3, density: f32| {
                let (sigma_a, sigma_s) = g.absorption_scattering(p, density, time);
                MediumPoint { sigma_a, sigma_s, l_ve: Rgb::ZERO }
            }
        }),
    }
}

/// The grid-medium case shared by [`sample_t_maj`] and
/// [`sample_t_maj_without_emission`]: clips `[0, t_max)` to the grid's
/// bounds (no overlap: no collision, returns `Rgb::ONE`), reads the
/// sampler's time and walks the density view along the ray, with the
/// coefficients at each collision given by `point_at(time)`.
fn grid_flight<F, P>(
    g: &GridMedium,
    ray: &Ray,
    t_max: f32,
    hero: usize,
    sampler: &mut PixelSampler,
    callback: F,
    point_at: impl FnOnce(f32) -> P,
) -> Rgb
where
    F: FnMut(MajorantCollision, &mut PixelSampler) -> bool,
    P: Fn(Vec3, f32) -> MediumPoint,
{
    let Some((a, b)) = g.clip(ray, 0.0, t_max) else {
        return Rgb::ONE;
    };
    let time = sampler.time();
    let flight = Flight { sigma_t: g.sigma_t(), ray, hero, sampler, point_at: point_at(time), callback };
    with_grid_along_ray(g, g.ray_to_grid(ray), (a, b), time, false, flight)
}

/// [`walk`] as a [`GridRayVisitor`]: its arguments but the density view.
struct Flight<'a, P, F> {
    sigma_t: Rgb,
    ray: &'a Ray,
    hero: usize,
    sampler: &'a mut PixelSampler,
    point_at: P,
    callback: F,
}

impl<P, F> GridRayVisitor for Flight<'_, P, F>
where
    P: Fn(Vec3, f32) -> MediumPoint,
    F: FnMut(MajorantCollision, &mut PixelSampler) -> bool,
{
    type Output = Rgb;
    #[inline]
    fn visit<G: GridLookup>(self, r: &GridAlongRay<'_, G>) -> Rgb {
        walk(r, self.sigma_t, self.ray, self.hero, self.sampler, self.point_at, self.callback)
    }
}

/// The concrete loop of [`sample_t_maj`] over one density view.
fn walk<R, P, F>(
    r: &R,
    sigma_t: Rgb,
    ray: &Ray,
    hero: usize,
    sampler: &mut PixelSampler,
    point_at: P,
    mut callback: F,
) -> Rgb
where
    R: DensityAlongRay,
    P: Fn(Vec3, f32) -> MediumPoint,
    F: FnMut(MajorantCollision, &mut PixelSampler) -> bool,
{
    // Majorant optical depth since the previous collision, summed over the
    // segments crossed and exponentiated once per collision (and at the end).
    let mut tau = Rgb::ZERO;
    let grey = sigma_t[0] == sigma_t[1] && sigma_t[1] == sigma_t[2];
    let mut stopped = false;
    // Hero-channel majorant optical depth left to the next collision, once drawn.
    let mut to_collision: Option<f32> = None;
    let _ = r.segments(|seg| {
        let sigma_maj = sigma_t * seg.d_max;
        let mut t_min = seg.t0;
        if !(sigma_maj[hero] > 0.0) {
            // No collision for the hero channel: only attenuate the others.
            tau += sigma_maj * finite_length(seg.t1 - t_min);
            return std::ops::ControlFlow::Continue(());
        }
        loop {
            // The hero channel's majorant optical depth to the next collision is
            // drawn once and spent over the segments it crosses (the same
            // distribution as redrawing per segment, by memorylessness, without a
            // logarithm and a random number per segment crossed).
            let depth = *to_collision.get_or_insert_with(|| -(1.0 - sampler.next_1d()).ln());
            let t = t_min + depth / sigma_maj[hero];
            if !(t < seg.t1) {
                let length = finite_length(seg.t1 - t_min);
                to_collision = Some((depth - sigma_maj[hero] * length).max(0.0));
                tau += sigma_maj * length;
                return std::ops::ControlFlow::Continue(());
            }
            to_collision = None;
            tau += sigma_maj * (t - t_min);
            let t_maj = transmittance(tau, grey);
            let p = ray.at(t);
            let collision = MajorantCollision { t, p, point: point_at(p, r.density(t)), sigma_maj, t_maj };
            if !callback(collision, sampler) {
                stopped = true;
                return std::ops::ControlFlow::Break(());
            }
            tau = Rgb::ZERO;
            t_min = t;
        }
    });
    if stopped {
        Rgb::ONE
    } else {
        transmittance(tau, grey)
    }
}

/// `exp(-tau)` per channel, one exponential when the channels are equal
/// (`grey`: the medium's extinction is the same in every channel).
#[inline]
fn transmittance(tau: Rgb, grey: bool) -> Rgb {
    if grey {
        Rgb::splat((-tau[0]).exp())
    } else {
        tau.exp_neg()
    }
}

/// An infinite length replaced by the largest float, as pbrt-v4 does, so that
/// `0 * length` stays 0 for channels without extinction.
#[inline]
fn finite_length(l: f32) -> f32 {
    if l.is_finite() {
        l
    } else {
        f32::MAX
    }
}
