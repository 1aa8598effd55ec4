//! Tests of the emission integral of a segment against closed forms, and of
//! the default march step rule.

use super::*;
use crate::math::Vec3;
use crate::medium::HomogeneousMedium;
use crate::phase::PhaseFunction;

/// A purely absorbing homogeneous medium with per-channel `sigma_a` and `l_ve`.
fn absorbing(sigma_a: [f32; 3], l_ve: [f32; 3]) -> Medium {
    Medium::Homogeneous(HomogeneousMedium {
        sigma_a: Rgb(sigma_a),
        sigma_s: Rgb::ZERO,
        l_ve: Rgb(l_ve),
        phase: PhaseFunction::Isotropic,
    })
}

fn ray_z() -> Ray {
    Ray::new(Vec3::ZERO, Vec3::Z)
}

/// Relative error of `a` against `b`.
fn relative(a: f32, b: f64) -> f64 {
    ((a as f64 - b) / b).abs()
}

#[test]
fn analytic_emission_of_a_homogeneous_slab_is_the_closed_form() {
    // L = L_ve (1 - exp(-sigma_t d)) / sigma_t, T = exp(-sigma_t d); a channel
    // without extinction emits L_ve d. f32 exp_m1, exp and one division:
    // a few ulps, so 1e-6 relative (8 ulps).
    let (sigma, l_ve, d) = ([0.5f32, 2.0, 0.0], [1.0f32, 3.0, 0.25], 1.7f32);
    let m = absorbing(sigma, l_ve);
    let mut sampler = PixelSampler::new(0, 0, 0, 0);
    let s = emission_segment(&m, &ray_z(), d, None, TransmittanceMethod::Analytic, 10.0, &mut sampler);
    for c in 0..3 {
        let (sg, l, d) = (sigma[c] as f64, l_ve[c] as f64, d as f64);
        let (radiance, transmittance) =
            if sg > 0.0 { (l * -(-sg * d).exp_m1() / sg, (-sg * d).exp()) } else { (l * d, 1.0) };
        assert!(relative(s.radiance[c], radiance) < 1e-6, "channel {c}: {} vs {radiance}", s.radiance[c]);
        assert!(
            relative(s.transmittance[c], transmittance) < 1e-6,
            "channel {c}: {} vs {transmittance}",
            s.transmittance[c]
        );
    }
}

#[test]
fn analytic_emission_of_an_unbounded_medium_is_l_ve_over_sigma_t() {
    // A deep absorbing emitter looks like L_ve / sigma_a, and nothing passes.
    let m = absorbing([0.5, 2.0, 4.0], [1.0, 3.0, 2.0]);
    let mut sampler = PixelSampler::new(0, 0, 0, 0);
    let s = emission_segment(&m, &ray_z(), f32::INFINITY, None, TransmittanceMethod::Analytic, 10.0, &mut sampler);
    for (c, expected) in [2.0, 1.5, 0.5].into_iter().enumerate() {
        assert!(relative(s.radiance[c], expected) < 1e-6, "channel {c}: {}", s.radiance[c]);
        assert_eq!(s.transmittance[c], 0.0);
    }
}

/// The ray-marched estimate at jitter `u` over `[0, d]` with `n` steps of a
/// homogeneous emitter, in closed form: the transmittance between march
/// points is exact for `RayMarch` in a homogeneous medium, so the sum
/// `L_ve dt sum_i exp(-s (i + u) dt)` is geometric.
fn marched_closed_form(s: f64, l: f64, d: f64, n: u32, u: f64) -> f64 {
    let dt = d / n as f64;
    l * dt * (-s * u * dt).exp() * (-(-s * d).exp_m1()) / (-(-s * dt).exp_m1())
}

#[test]
fn marched_emission_is_the_geometric_sum_at_its_jitter() {
    // Step 0.1 over d = 1.7: 17 steps. Each sample draws its jitter as the
    // first number of its sampler. 17 f32 products and sums: 1e-5 relative.
    let (s, l, d) = (2.0f32, 3.0f32, 1.7f32);
    let m = absorbing([s; 3], [l; 3]);
    let step = MarchStep::Length(0.1);
    let method = TransmittanceMethod::RayMarch(step);
    for sample in 0..32 {
        let mut sampler = PixelSampler::new(7, 1, 2, sample);
        let u = PixelSampler::new(7, 1, 2, sample).next_1d();
        let seg = emission_segment(&m, &ray_z(), d, Some(step), method, 10.0, &mut sampler);
        let expected = marched_closed_form(s as f64, l as f64, d as f64, 17, u as f64);
        assert!(relative(seg.radiance[0], expected) < 1e-5, "u {u}: {} vs {expected}", seg.radiance[0]);
        let transmittance = (-(s as f64) * d as f64).exp();
        assert!(relative(seg.transmittance[0], transmittance) < 1e-5, "u {u}: {}", seg.transmittance[0]);
    }
}

#[test]
fn marched_emission_mean_is_the_exact_integral() {
    // Integrating the geometric sum over u in [0, 1) gives exactly
    // L_ve (1 - exp(-s d)) / s: the jittered march is unbiased. Mean over
    // 4096 samples within 4 standard errors estimated from the same samples.
    let (s, l, d) = (2.0f32, 3.0f32, 1.7f32);
    let m = absorbing([s; 3], [l; 3]);
    let step = MarchStep::Count(4);
    let n = 4096;
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for sample in 0..n {
        let mut sampler = PixelSampler::new(3, 0, 0, sample);
        let seg =
            emission_segment(&m, &ray_z(), d, Some(step), TransmittanceMethod::RayMarch(step), 10.0, &mut sampler);
        let x = seg.radiance[0] as f64;
        sum += x;
        sum2 += x * x;
    }
    let mean = sum / n as f64;
    let std_error = ((sum2 / n as f64 - mean * mean).max(0.0) / (n - 1) as f64).sqrt();
    let exact = l as f64 * -(-(s as f64) * d as f64).exp_m1() / s as f64;
    assert!(std_error > 0.0 && (mean - exact).abs() < 4.0 * std_error, "mean {mean} +- {std_error}, exact {exact}");
}

#[test]
fn unbounded_march_is_cut_where_transmittance_falls_to_1e6() {
    // marched_range cuts an unbounded homogeneous segment at
    // ln(1e6) / min sigma_t, where the remaining emission is 1e-6 of the total.
    let m = absorbing([0.5, 2.0, 4.0], [1.0; 3]);
    let (t_a, t_b) = marched_range(&m, &ray_z(), f32::INFINITY, 10.0).unwrap();
    assert_eq!(t_a, 0.0);
    let remaining = (-0.5 * t_b as f64).exp();
    // 13.8155 is ln(1e6) to 6 digits: 1.1e-5 relative in the exponential.
    assert!((remaining - 1e-6).abs() < 1e-6 * 2e-5, "exp(-0.5 t_b) = {remaining}");
    // Without extinction in some channel: 1000 scene diagonals.
    let clear = absorbing([0.0, 1.0, 1.0], [1.0; 3]);
    assert_eq!(marched_range(&clear, &ray_z(), f32::INFINITY, 10.0), Some((0.0, 10000.0)));
    // A bounded segment is marched whole.
    assert_eq!(marched_range(&m, &ray_z(), 3.5, 10.0), Some((0.0, 3.5)));
}

#[test]
fn default_march_step_is_a_quarter_mean_free_path_within_diagonal_bounds() {
    // Quarter of the mean free path, clamped to [diagonal / 4096, diagonal / 64].
    // The values are exact in f32 (powers of two times the inputs).
    assert_eq!(default_march_step(1.0, 100.0), MarchStep::Length(0.25));
    assert_eq!(default_march_step(0.001, 100.0), MarchStep::Length(100.0 / 64.0));
    assert_eq!(default_march_step(1e4, 100.0), MarchStep::Length(100.0 / 4096.0));
    // No extinction: the coarse bound; no usable diagonal: 10 is assumed.
    assert_eq!(default_march_step(0.0, 100.0), MarchStep::Length(100.0 / 64.0));
    assert_eq!(default_march_step(1.0, f32::NAN), MarchStep::Length(10.0 / 64.0));
    assert_eq!(default_march_step(1.0, 0.0), MarchStep::Length(10.0 / 64.0));
}
