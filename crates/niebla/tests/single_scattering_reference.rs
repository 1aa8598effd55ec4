//! The `single` integrator against independent quadrature values
//! (tests/reference/single_scatter_point.csv: homogeneous medium everywhere,
//! isotropic point light, camera ray segment [0, L]). Every sampling mode must
//! agree with every row within 4 standard errors estimated from its own
//! samples (reference README section 3), plus a floor for f32 rounding,
//! with the Sobol sampler's numbers in draw order and with the camera-ray
//! dimension layout (the segment as the first step of a laid-out walk).

mod common;

use common::{field, homogeneous, read_reference_csv, scene, Stats};
use niebla::color::Rgb;
use niebla::integrator::{SingleIntegrator, SingleSampling};
use niebla::light::{Light, PointLight};
use niebla::math::{Ray, Vec3};
use niebla::medium::MediumId;
use niebla::phase::PhaseFunction;
use niebla::sampling::{PixelSampler, SamplerKind};
use niebla::tracking::{MarchStep, TransmittanceMethod};

/// Mean and standard error of the segment radiance over `n` samples of one
/// pixel (Sobol; with the camera-ray layout when `laid_out`).
fn estimate(
    row: &std::collections::HashMap<String, String>,
    sampling: SingleSampling,
    n: u32,
    laid_out: bool,
) -> (f64, f64) {
    let sigma_t = field(row, "sigma_t") as f32;
    let sigma_s = field(row, "sigma_s") as f32;
    let phase = match row["phase"].as_str() {
        "isotropic" => PhaseFunction::isotropic(),
        "henyey_greenstein" => PhaseFunction::hg(field(row, "g") as f32),
        other => panic!("unknown phase {other}"),
    };
    let (h, t0, length) = (field(row, "h") as f32, field(row, "t0") as f32, field(row, "L") as f32);
    let intensity = field(row, "I") as f32;
    // Ray along +x from the origin; the light at perpendicular distance h from
    // the line, its foot at t0.
    let light = Light::Point(PointLight { position: Vec3::new(t0, h, 0.0), intensity: Rgb::splat(intensity) });
    let medium = homogeneous(sigma_t - sigma_s, sigma_s, Rgb::ZERO, phase);
    let s = scene(common::camera_along_x(1, 1, 30.0), vec![], vec![medium], vec![light], Some(MediumId(0)));
    // March step well below h (the integrand's width) and below the mean free path.
    let step = MarchStep::Length((0.25 * h).min(0.1));
    let integrator = SingleIntegrator {
        step: Some(step),
        sampling,
        transmittance: TransmittanceMethod::Analytic,
        volume_lights: None,
    };
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    let mut stats = Stats::default();
    for i in 0..n {
        let mut sampler = PixelSampler::for_pixel(SamplerKind::Sobol, 0x5eed, 0, 0, i as u64);
        if laid_out {
            // As the walk of a laid-out integrator sets it for its first segment.
            sampler.set_layout_block(Some(0));
        }
        let seg = integrator.segment(&s, MediumId(0), &ray, length, &mut sampler);
        stats.add(seg.radiance.g() as f64);
    }
    (stats.mean(), stats.standard_error())
}

fn check_all_rows(sampling: SingleSampling, n: u32) {
    let rows = read_reference_csv("single_scatter_point.csv");
    assert_eq!(rows.len(), 41);
    let mut checked = 0;
    let mut worst_z: f64 = 0.0;
    for (row, laid_out) in rows.iter().flat_map(|r| [(r, false), (r, true)]) {
        let unbounded_without_extinction = field(row, "sigma_t") == 0.0 && field(row, "L").is_infinite();
        if sampling == SingleSampling::March && unbounded_without_extinction {
            // A ray march needs a finite segment; equiangular sampling covers it.
            continue;
        }
        let reference = field(row, "radiance");
        let (mean, se) = estimate(row, sampling, n, laid_out);
        // Rounding floor: the integrand is evaluated in f32, whose relative
        // error (~1e-6 per operation) shows where an estimator has (nearly)
        // zero variance, e.g. equiangular sampling without extinction.
        let z = (mean - reference) / (se + 5e-6 * reference);
        worst_z = worst_z.max(z.abs());
        assert!(
            z.abs() < 4.0,
            "{sampling:?} case {} (laid out: {laid_out}): {mean:.6e} +- {se:.2e} vs reference {reference:.6e} (z = {z:.2})",
            row["case"]
        );
        // The estimate must also be useful: standard error below 2% of the value.
        assert!(se < 0.02 * reference, "{sampling:?} case {}: se {se:.2e} too large", row["case"]);
        checked += 1;
    }
    println!("{sampling:?}: {checked} rows (draw order and laid out), worst |z| = {worst_z:.2}");
}

#[test]
fn single_march_matches_quadrature_reference() {
    check_all_rows(SingleSampling::March, 2_000);
}

#[test]
fn single_equiangular_matches_quadrature_reference() {
    check_all_rows(SingleSampling::Equiangular, 20_000);
}

#[test]
fn single_mis_matches_quadrature_reference() {
    check_all_rows(SingleSampling::Mis, 20_000);
}

/// Equiangular sampling must beat distance sampling by far near a point light
/// in a thin medium (Kulla and Fajardo 2012): compare the variance of the
/// equiangular estimator with the MIS one on the h = 0.1 row, whose integrand
/// is a narrow peak.
#[test]
fn equiangular_sampling_has_low_variance_near_a_point_light() {
    let rows = read_reference_csv("single_scatter_point.csv");
    let row = rows.iter().find(|r| r["case"] == "7").unwrap(); // sigma_t 0.1, h 0.1
    let (_, se_eq) = estimate(row, SingleSampling::Equiangular, 20_000, true);
    let reference = field(row, "radiance");
    // With only the exponentials left, the relative standard error of 2e4
    // equiangular samples is tiny.
    assert!(se_eq / reference < 2e-3, "relative se {}", se_eq / reference);
}
