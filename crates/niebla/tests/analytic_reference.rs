//! The `analytic` integrator (Sun et al. 2005 airlight) against independent
//! numbers: the quadrature references of tests/reference/single_scatter_point.csv
//! (isotropic rows to the F table's error; the anisotropic rows only report
//! the closest-approach phase approximation), and `single` renders of a fog
//! box lit by a point light, a spot light and a directional light, block by
//! block within the noise of independent batches.

mod common;

use common::{field, homogeneous, read_reference_csv, scene};
use niebla::color::Rgb;
use niebla::integrator::{AnalyticIntegrator, IntegratorSettings, SingleSampling};
use niebla::light::{Light, PointLight};
use niebla::math::{Ray, Vec3};
use niebla::medium::MediumId;
use niebla::phase::PhaseFunction;
use niebla::render::{render, RenderOptions};
use niebla::sampling::PixelSampler;
use niebla::scene::{build_scene, parse_scene_str};
use niebla::tracking::TransmittanceMethod;

/// Relative tolerance against the quadrature rows: the F table's measured
/// error (2.2e-6 of F(u, pi/2)) amplified by the difference F(v1) - F(v2),
/// plus f32 rounding of the geometry and the result.
const CSV_TOLERANCE: f64 = 1e-5;

fn analytic_row(row: &std::collections::HashMap<String, String>) -> f64 {
    let sigma_t = field(row, "sigma_t") as f32;
    let sigma_s = field(row, "sigma_s") as f32;
    let phase = match row["phase"].as_str() {
        "isotropic" => PhaseFunction::isotropic(),
        "henyey_greenstein" => PhaseFunction::hg(field(row, "g") as f32),
        other => panic!("unknown phase {other}"),
    };
    let (h, t0, length) = (field(row, "h") as f32, field(row, "t0") as f32, field(row, "L") as f32);
    let light =
        Light::Point(PointLight { position: Vec3::new(t0, h, 0.0), intensity: Rgb::splat(field(row, "I") as f32) });
    let medium = homogeneous(sigma_t - sigma_s, sigma_s, Rgb::ZERO, phase);
    let s = scene(common::camera_along_x(1, 1, 30.0), vec![], vec![medium], vec![light], Some(MediumId(0)));
    let mut sampler = PixelSampler::from_key(1);
    let seg = AnalyticIntegrator::new().segment(&s, MediumId(0), &Ray::new(Vec3::ZERO, Vec3::X), length, &mut sampler);
    seg.radiance.g() as f64
}

#[test]
fn analytic_matches_quadrature_reference_isotropic_rows() {
    let rows = read_reference_csv("single_scatter_point.csv");
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    for row in rows.iter().filter(|r| r["phase"] == "isotropic") {
        let reference = field(row, "radiance");
        let value = analytic_row(row);
        let relative = (value - reference).abs() / reference;
        worst = worst.max(relative);
        assert!(relative < CSV_TOLERANCE, "case {}: {value:.9e} vs {reference:.9e} ({relative:.2e})", row["case"]);
        checked += 1;
    }
    assert_eq!(checked, 32);
    println!("analytic vs quadrature: {checked} isotropic rows, worst relative error {worst:.2e}");
}

/// Anisotropic phases are outside the closed form: 16 pieces with the phase
/// held at each midpoint. Its error on the HG rows: within 3% (measured
/// 0.4% for |g| = 0.5, 2.1% for g = 0.9).
#[test]
fn analytic_phase_midpoint_rule_is_within_three_percent_on_hg_rows() {
    let rows = read_reference_csv("single_scatter_point.csv");
    for row in rows.iter().filter(|r| r["phase"] == "henyey_greenstein") {
        let reference = field(row, "radiance");
        let value = analytic_row(row);
        assert!((value / reference - 1.0).abs() < 0.03, "case {}: {value:e} vs {reference:e}", row["case"]);
        println!(
            "case {} g {}: analytic {value:.4e} vs {reference:.4e} ({:+.1}%)",
            row["case"],
            row["g"],
            100.0 * (value / reference - 1.0)
        );
    }
}

fn fog_scene(spot: &str, phase: &str) -> String {
    format!(
        r#"{{
  "version": 1,
  "camera": {{"type": "perspective", "position": [0, 1.5, 5], "target": [0, 1, 0], "fov_y": 50,
             "width": 16, "height": 16}},
  "media": {{"fog": {{"sigma_t": [0.3, 0.35, 0.4], "albedo": 0.8, "phase": {phase}}}}},
  "shapes": [
    {{"type": "box", "min": [-3, -0.5, -3], "max": [3, 4, 6], "interior": "fog"}},
    {{"type": "rectangle", "to_world": {{"scale": 3, "rotate_x": -90}}, "bsdf": {{"type": "diffuse", "reflectance": 0.5}}}}
  ],
  "lights": [
    {spot},
    {{"type": "point", "position": [-1.5, 1, 1], "intensity": [1, 2, 3]}},
    {{"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": 0.5}}
  ]
}}"#
    )
}

/// Per 4x4 block and channel: mean over batches and standard error of that mean.
fn block_stats(text: &str, settings: IntegratorSettings, spp: u32, batches: u64) -> Vec<(f64, f64)> {
    let desc = parse_scene_str(text, "fog.json").unwrap();
    let built = build_scene(&desc, "fog.json", std::path::Path::new(".")).unwrap();
    let mut per_batch: Vec<Vec<f64>> = Vec::new();
    for b in 0..batches {
        let options = RenderOptions { spp, seed: 500 + b, first_sample: 0, threads: None, sampler: Default::default() };
        let image = render(&built.scene, &settings, &options, &|_, _| {}, None).unwrap();
        let mut blocks = vec![0.0f64; 48];
        for y in 0..16 {
            for x in 0..16 {
                let p = image.get(x, y);
                for c in 0..3 {
                    blocks[((y / 4) * 4 + x / 4) as usize * 3 + c] += p[c] as f64 / 16.0;
                }
            }
        }
        per_batch.push(blocks);
    }
    (0..48)
        .map(|k| {
            let n = batches as f64;
            let mean = per_batch.iter().map(|b| b[k]).sum::<f64>() / n;
            let var = per_batch.iter().map(|b| (b[k] - mean).powi(2)).sum::<f64>() / (n - 1.0);
            (mean, (var / n).sqrt())
        })
        .collect()
}

/// Worst |z| and worst relative block difference between `analytic` and
/// `single` (MIS); `floor` is a relative error allowed on top of the two
/// standard errors (a known deterministic error of `analytic`).
fn compare_with_single(text: &str, floor: f64) -> (f64, f64) {
    let single = IntegratorSettings::Single {
        step: None,
        sampling: SingleSampling::Mis,
        transmittance: TransmittanceMethod::Analytic,
        volume_lights: false,
    };
    let reference = block_stats(text, single, 64, 10);
    let analytic = block_stats(text, IntegratorSettings::Analytic, 16, 10);
    let (mut worst_z, mut worst_relative): (f64, f64) = (0.0, 0.0);
    for k in 0..48 {
        let ((a, sa), (b, sb)) = (analytic[k], reference[k]);
        let z = (a - b) / (sa * sa + sb * sb + (floor * b).powi(2)).sqrt().max(1e-6 * b.abs());
        worst_z = worst_z.max(z.abs());
        worst_relative = worst_relative.max((a - b).abs() / b.abs().max(1e-9));
    }
    (worst_z, worst_relative)
}

/// Isotropic fog, a spot with `beam_width == cutoff_angle` (exact in closed
/// form), a point light and a directional light (distance sampled): every
/// block agrees with `single` within 4.5 standard errors (48 comparisons).
#[test]
fn analytic_matches_single_on_an_isotropic_fog() {
    let spot = r#"{"type": "spot", "position": [0.5, 3.5, 0], "target": [0, 0, 0], "intensity": 20, "cutoff_angle": 25, "beam_width": 25}"#;
    let (z, relative) = compare_with_single(&fog_scene(spot, r#"{"type": "isotropic"}"#), 0.0);
    println!("analytic vs single, isotropic fog: worst |z| {z:.2}, worst block difference {:.2}%", 100.0 * relative);
    assert!(z < 4.5, "worst |z| {z:.2}");
}

/// A spot with a falloff ring (beam 15, cutoff 25 degrees): the ring uses a
/// 16-piece midpoint rule for the falloff. Agreement within 4.5 standard
/// errors as well (the midpoint rule's error is below the noise here).
#[test]
fn analytic_matches_single_with_spot_falloff() {
    let spot = r#"{"type": "spot", "position": [0.5, 3.5, 0], "target": [0, 0, 0], "intensity": 20, "cutoff_angle": 25, "beam_width": 15}"#;
    let (z, relative) = compare_with_single(&fog_scene(spot, r#"{"type": "isotropic"}"#), 0.0);
    println!("analytic vs single, spot falloff: worst |z| {z:.2}, worst block difference {:.2}%", 100.0 * relative);
    assert!(z < 4.5, "worst |z| {z:.2}");
}

/// Henyey-Greenstein fog (g = 0.4): every block agrees with `single` within
/// 4.5 standard errors plus 0.25% of the value for the phase midpoint rule.
/// That rule is deterministic: against `single` with independent numbers
/// (20 x 512 spp) `analytic` is 0.17% low on the worst blocks (|z| 4.6
/// there, while `single` with Sobol numbers in either layout is within
/// |z| 2.6 of that reference on all 48), which the noise of `single` hid
/// before its Sobol dimensions were laid out.
#[test]
fn analytic_matches_single_on_an_hg_fog() {
    let spot = r#"{"type": "spot", "position": [0.5, 3.5, 0], "target": [0, 0, 0], "intensity": 20, "cutoff_angle": 25, "beam_width": 15}"#;
    let (z, relative) = compare_with_single(&fog_scene(spot, r#"{"type": "hg", "g": 0.4}"#), 2.5e-3);
    println!("analytic vs single, hg fog: worst |z| {z:.2}, worst block difference {:.2}%", 100.0 * relative);
    assert!(z < 4.5, "worst |z| {z:.2}");
}
