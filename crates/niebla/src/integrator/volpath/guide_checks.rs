//! Monte Carlo checks shared by the unit tests of `volpath`'s direction
//! guides: that a solid-angle density integrates to one, and that a
//! sampler's directions follow its density.

use crate::math::Vec3;
use crate::sampling::{sample_uniform_sphere, PixelSampler};

/// Mean and standard error of the mean of `n` draws of `draw`.
pub(super) fn mean_se(n: usize, mut draw: impl FnMut() -> f64) -> (f64, f64) {
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let v = draw();
        sum += v;
        sum2 += v * v;
    }
    let mean = sum / n as f64;
    (mean, ((sum2 / n as f64 - mean * mean) / n as f64).sqrt())
}

/// The integral over the sphere of the solid-angle density `pdf` (1/sr),
/// estimated with `n` uniform directions drawn from `s`: its mean and
/// standard error (1 for a normalized density).
pub(super) fn sphere_integral(s: &mut PixelSampler, n: usize, pdf: impl Fn(Vec3) -> f32) -> (f64, f64) {
    mean_se(n, || f64::from(pdf(sample_uniform_sphere(s.next_2d()))) * 4.0 * std::f64::consts::PI)
}

/// A shape check of a direction sampler against its density `pdf`: the
/// mean of `min(pdf, cap)` over `n` directions drawn by `sample` (draws
/// that give no direction are skipped, as they count zero) and the integral
/// of `pdf min(pdf, cap)` over the sphere with `n` uniform directions. The
/// two agree when the sampler's directions follow `pdf`; returns both.
pub(super) fn sampled_and_integrated(
    s: &mut PixelSampler,
    n: usize,
    cap: f64,
    mut sample: impl FnMut(&mut PixelSampler) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f32,
) -> (f64, f64) {
    let mut by_sampling = 0.0f64;
    for _ in 0..n {
        if let Some(w) = sample(s) {
            by_sampling += f64::from(pdf(w)).min(cap);
        }
    }
    let mut by_uniform = 0.0f64;
    for _ in 0..n {
        let p = f64::from(pdf(sample_uniform_sphere(s.next_2d())));
        by_uniform += p * p.min(cap) * 4.0 * std::f64::consts::PI;
    }
    (by_sampling / n as f64, by_uniform / n as f64)
}
