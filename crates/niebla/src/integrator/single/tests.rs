//! Tests of the densities `single` combines (equiangular and distance
//! sampling, their MIS weights) and of its segment estimate against the
//! closed-form airlight of Sun et al. 2005.

use super::*;
use crate::light::{Light, PointLight};
use crate::math::Vec3;
use crate::medium::HomogeneousMedium;
use crate::phase::PhaseFunction;
use crate::scene::{build_scene, parse_scene_str};

/// Ray along +z from the origin; a point light at distance `H` from its
/// line, closest approach at `T_C`; segments end at `T_END`.
const H: f32 = 1.0;
const T_C: f32 = 5.0;
const T_END: f32 = 10.0;

fn ray_z() -> Ray {
    Ray::new(Vec3::ZERO, Vec3::Z)
}

fn point_light() -> Light {
    Light::Point(PointLight { position: Vec3::new(0.0, H, T_C), intensity: Rgb::splat(10.0) })
}

fn equiangular_interval() -> super::super::equiangular::EquiangularInterval {
    match equiangular_target(&point_light(), &ray_z(), T_END) {
        PointLightTarget::Interval(e) => e,
        other => panic!("a point light off the ray gives an interval, not {other:?}"),
    }
}

fn fog(sigma_a: f32, sigma_s: f32) -> Medium {
    Medium::Homogeneous(HomogeneousMedium {
        sigma_a: Rgb::splat(sigma_a),
        sigma_s: Rgb::splat(sigma_s),
        l_ve: Rgb::ZERO,
        phase: PhaseFunction::Isotropic,
    })
}

/// Midpoint rule of `f` over `[a, b]` with `n` nodes, in f64.
fn midpoint(f: impl Fn(f32) -> f32, a: f64, b: f64, n: usize) -> f64 {
    let dt = (b - a) / n as f64;
    (0..n).map(|i| f((a + (i as f64 + 0.5) * dt) as f32) as f64).sum::<f64>() * dt
}

#[test]
fn equiangular_pdf_integrates_to_one_and_vanishes_outside() {
    // pdf = h / ((theta_b - theta_a) (h^2 + (t - t_c)^2)). Midpoint error
    // bound (b - a)^3 max|f''| / (24 n^2) = 1000 * 0.7 / (24 * 4e8) < 1e-7
    // (max|f''| = 2 / ((theta_b - theta_a) h^3) = 0.7); each f32 pdf value
    // is within a few ulps, so 1e-5 covers both.
    let e = equiangular_interval();
    let integral = midpoint(|t| e.pdf(t), 0.0, T_END as f64, 20_000);
    assert!((integral - 1.0).abs() < 1e-5, "integral {integral}");
    assert_eq!(e.pdf(-0.1), 0.0);
    assert_eq!(e.pdf(T_END + 0.1), 0.0);
    // Largest at the closest approach, by the ratio (h^2 + t_c^2) / h^2 = 26 over t = 0.
    let ratio = e.pdf(T_C) / e.pdf(0.0);
    assert!((ratio - 26.0).abs() < 26.0 * 1e-5, "ratio {ratio}");
}

#[test]
fn equiangular_sample_inverts_its_cdf() {
    // CDF(t) = (atan((t - t_c)/h) - theta_a) / (theta_b - theta_a) in f64;
    // the f32 sampler's t is within a few ulps of 10, whose effect on the CDF
    // is at most pdf_max * 1e-5 = 3e-6.
    let e = equiangular_interval();
    let theta = |t: f64| ((t - T_C as f64) / H as f64).atan();
    let (theta_a, theta_b) = (theta(0.0), theta(T_END as f64));
    for i in 0..=64 {
        let u = (i as f32 / 64.0).min(1.0 - f32::EPSILON);
        let t = e.sample(u) as f64;
        let cdf = (theta(t) - theta_a) / (theta_b - theta_a);
        assert!((cdf - u as f64).abs() < 1e-5, "u {u}: t {t}, CDF {cdf}");
    }
}

#[test]
fn distance_profile_of_a_homogeneous_segment_is_the_truncated_exponential() {
    // single's distance density: sigma exp(-sigma t) / (1 - exp(-sigma T)) on
    // [0, T] with sigma the channel-averaged extinction. Relative 1e-5: a few
    // f32 ulps of the exponential at sigma t <= 7.
    let m = fog(0.2, 0.5);
    let sigma = 0.7f64;
    let profile = majorant_profile(&m, &ray_z(), 0.0, T_END, m.sigma_t_per_density().average());
    let norm = -(-sigma * T_END as f64).exp_m1();
    for t in [0.0f32, 0.5, 2.0, 5.0, 9.9] {
        let expected = sigma * (-sigma * t as f64).exp() / norm;
        let pdf = profile.pdf(t) as f64;
        assert!(((pdf - expected) / expected).abs() < 1e-5, "t {t}: pdf {pdf}, expected {expected}");
    }
    let integral = midpoint(|t| profile.pdf(t), 0.0, T_END as f64, 20_000);
    assert!((integral - 1.0).abs() < 1e-5, "integral {integral}");
}

#[test]
fn mis_weights_of_distance_and_equiangular_sampling_sum_to_one() {
    // The balance heuristic weights single gives a point at t from either
    // strategy sum to one wherever either density is positive (one f32
    // division each: 2 ulps), so the MIS estimator counts each t once.
    let e = equiangular_interval();
    let m = fog(0.2, 0.5);
    let profile = majorant_profile(&m, &ray_z(), 0.0, T_END, m.sigma_t_per_density().average());
    for i in 0..200 {
        let t = (i as f32 + 0.5) * T_END / 200.0;
        let (p_distance, p_equiangular) = (profile.pdf(t), e.pdf(t));
        assert!(p_distance > 0.0 && p_equiangular > 0.0);
        let sum = balance_heuristic(p_distance, p_equiangular) + balance_heuristic(p_equiangular, p_distance);
        assert!((sum - 1.0).abs() < 2.5e-7, "t {t}: weights sum to {sum}");
    }
}

/// A scene filled with a homogeneous isotropic fog (sigma_a 0.2, sigma_s 0.5)
/// around the point light of [`point_light`], nothing else.
fn fog_scene() -> Scene {
    let text = r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 0, 0], "target": [0, 0, 1], "width": 4, "height": 4},
        "media": {"fog": {"sigma_a": 0.2, "sigma_s": 0.5, "phase": {"type": "isotropic"}}},
        "ambient_medium": "fog",
        "lights": [{"type": "point", "position": [0, 1, 5], "intensity": 10}]}"#;
    let desc = parse_scene_str(text, "fog.json").unwrap();
    build_scene(&desc, "fog.json", ".".as_ref()).unwrap().scene
}

#[test]
fn every_sampling_of_single_matches_the_closed_form_airlight() {
    // Sun et al. 2005: L = sigma_s I / (4 pi) int_0^T exp(-sigma_t (t + d)) / d^2 dt
    // (airlight_integral, tabulated F within 1e-5). Each sampling's mean over
    // independent samples lies within 4 of its standard errors, and the
    // segment's transmittance is exp(-sigma_t T).
    let scene = fog_scene();
    let id = scene.ambient_medium.unwrap();
    let table = crate::integrator::airlight_table();
    let expected = 0.5 * 10.0 / (4.0 * std::f64::consts::PI)
        * crate::integrator::airlight_integral(table, 0.7, H as f64, T_C as f64, 0.0, T_END as f64);
    for (sampling, n) in
        [(SingleSampling::Equiangular, 4000), (SingleSampling::Mis, 4000), (SingleSampling::March, 256)]
    {
        let single = SingleIntegrator {
            step: None,
            sampling,
            transmittance: TransmittanceMethod::Analytic,
            volume_lights: None,
        };
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for s in 0..n {
            let mut sampler = PixelSampler::new(11, 0, 0, s);
            let seg = single.segment(&scene, id, &ray_z(), T_END, &mut sampler);
            let x = seg.radiance[1] as f64;
            sum += x;
            sum2 += x * x;
            let transmittance = (-0.7f64 * T_END as f64).exp();
            assert!(((seg.transmittance[1] as f64 - transmittance) / transmittance).abs() < 1e-5);
        }
        let mean = sum / n as f64;
        let std_error = ((sum2 / n as f64 - mean * mean).max(0.0) / (n - 1) as f64).sqrt();
        // The comparison is only as sharp as the noise: at these counts the
        // sampled estimators' standard error is about 1% of the airlight and
        // the march's below 1e-4; a broken (noisy) estimator fails here.
        assert!(std_error < 0.02 * expected, "{sampling:?}: standard error {std_error} of {mean}");
        let tolerance = 4.0 * std_error + 1e-5 * expected;
        assert!((mean - expected).abs() < tolerance, "{sampling:?}: mean {mean} +- {std_error}, airlight {expected}");
    }
}
