//! The `zhou` integrator (Zhou et al. 2008, compensated ray marching,
//! reconstructed from the paper's abstract and a paraphrase of its body):
//! - the RBF fit: its relative L2 error falls as RBFs are added, and a
//!   density that *is* a sum of a few Gaussians is recovered closely;
//! - single scattering from the RBF model against the `single` integrator
//!   (which marches the full grid with exact shadow rays), under a constant
//!   environment (exact in SH) and a directional light;
//! - compensation: with the residual compensated the image is closer to the
//!   full-grid `single` image than without;
//! - thin limit: multiple scattering vanishes and zhou equals `single`;
//! - the fit cache: a second precomputation loads the same RBFs, and a
//!   corrupt cache file is refitted without error;
//! - against a high-spp `volpath` reference on the smoke scene, relative MSE
//!   bounded at the value measured when the test was written (+25%).

use niebla::film::Image;
use niebla::integrator::zhou::fit::{fit_rbfs, FitSettings};
use niebla::integrator::zhou::lattice::Lattice;
use niebla::integrator::zhou::{Compensation, LocalLights};
use niebla::integrator::{IntegratorSettings, SingleSampling, VolPathIntegrator, ZhouIntegrator, ZhouSettings};
use niebla::math::Vec3;
use niebla::render::{render, render_with, RenderOptions};
use niebla::scene::{build_scene, load_scene, parse_scene_str, Scene};
use niebla::tracking::TransmittanceMethod;

fn options(spp: u32, seed: u64) -> RenderOptions {
    RenderOptions { spp, seed, first_sample: 0, threads: None, sampler: Default::default() }
}

fn scene_from(text: &str) -> Scene {
    let desc = parse_scene_str(text, "zhou.json").unwrap();
    build_scene(&desc, "zhou.json", std::path::Path::new(".")).unwrap().scene
}

fn zhou(scene: &Scene, settings: ZhouSettings, spp: u32) -> Image {
    let integrator = ZhouIntegrator::new(scene, settings);
    render_with(scene, &integrator, &options(spp, 3), &|_, _| {}, None).unwrap()
}

fn single_reference(scene: &Scene, spp: u32) -> Image {
    let single = IntegratorSettings::Single {
        step: None,
        sampling: SingleSampling::Mis,
        transmittance: TransmittanceMethod::Ratio,
        volume_lights: false,
    };
    render(scene, &single, &options(spp, 9), &|_, _| {}, None).unwrap()
}

fn no_cache() -> ZhouSettings {
    ZhouSettings { cache: false, ..ZhouSettings::default() }
}

/// A procedural plume density sampled on a 32^3 lattice.
fn plume_lattice() -> (Lattice, Vec<f32>) {
    let params = niebla_volume::ProceduralParams {
        shape: niebla_volume::ProceduralShape::Plume,
        seed: 7,
        resolution: [32, 32, 32],
        ..Default::default()
    };
    let grid = niebla_volume::procedural_density(&params).unwrap();
    let lattice = Lattice::over_box(Vec3::ZERO, Vec3::ONE, 32);
    let density = (0..lattice.len())
        .map(|i| {
            let p = lattice.position_of(i);
            grid.lookup([p.x, p.y, p.z])
        })
        .collect();
    (lattice, density)
}

/// T7: more RBFs fit better (relative L2 error, 80 iterations each).
/// Measured: 0.215 / 0.183 / 0.099 for 25 / 100 / 400 RBFs. Teleportation
/// is printed, not asserted: each kept teleport lowers the objective when
/// made, but restarting the quasi-Newton memory can cost more than it gains
/// within a fixed iteration budget (0.183 against 0.173 without, at 100).
#[test]
fn fit_error_falls_with_the_number_of_rbfs() {
    let (lattice, density) = plume_lattice();
    let mut errors = Vec::new();
    for count in [25, 100, 400] {
        let settings = FitSettings { count, iterations: 80, teleport_every: 20, seed: 1 };
        let (rbfs, report) = fit_rbfs(&lattice, &density, &settings);
        assert_eq!(rbfs.len(), count);
        println!(
            "{count} RBFs: relative L2 error {:.4} ({} teleports kept)",
            report.relative_error, report.teleports_kept
        );
        errors.push(report.relative_error);
    }
    assert!(errors[0] > errors[1] && errors[1] > errors[2], "errors {errors:?}");
    assert!(errors[2] < 0.6 * errors[0], "errors {errors:?}");
    let without =
        fit_rbfs(&lattice, &density, &FitSettings { count: 100, iterations: 80, teleport_every: 0, seed: 1 }).1;
    println!("100 RBFs without teleportation: {:.4}", without.relative_error);
}

/// A density that is a sum of 3 Gaussians of the model's family is fitted
/// to within a few percent by 3 RBFs (measured 4.7%; the fit is deterministic).
#[test]
fn fit_recovers_a_sum_of_gaussians() {
    let lattice = Lattice::over_box(Vec3::ZERO, Vec3::ONE, 24);
    let blobs = [
        (Vec3::new(0.3, 0.4, 0.5), 0.08, 1.0),
        (Vec3::new(0.6, 0.5, 0.4), 0.06, 0.6),
        (Vec3::new(0.5, 0.7, 0.6), 0.07, 0.8),
    ];
    let density: Vec<f32> = (0..lattice.len())
        .map(|i| {
            let p = lattice.position_of(i);
            blobs.iter().map(|(c, r, w)| w * (-(p - *c).length_squared() / (r * r)).exp()).sum()
        })
        .collect();
    let (_, report) =
        fit_rbfs(&lattice, &density, &FitSettings { count: 3, iterations: 300, teleport_every: 20, seed: 3 });
    println!("3 Gaussians: relative L2 error {:.4}", report.relative_error);
    assert!(report.relative_error < 0.06, "relative error {}", report.relative_error);
}

const SMOKE: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1.1, 4], "target": [0, 1, 0], "fov_y": 40, "width": 40, "height": 44},
  "media": {"plume": {"type": "grid", "density": {"type": "procedural", "shape": "plume", "seed": 7, "resolution": 64},
            "sigma_t": SIGMA, "albedo": 0.9, "phase": {"type": "hg", "g": 0.35},
            "to_world": {"scale": 2, "translate": [-1, 0, -1]}}},
  "ambient_medium": "plume",
  "lights": [{"type": "directional", "direction": [-0.6, -0.8, -0.35], "irradiance": [3.2, 2.9, 2.5]},
             {"type": "constant", "radiance": [0.16, 0.22, 0.34]}]
}"#;

fn mean_ratio(a: &Image, b: &Image) -> f64 {
    a.mean().average() as f64 / b.mean().average() as f64
}

/// Single scattering only: the RBF model's shadows (from `D~`) and its
/// interpolated source against `single` on the full grid. Measured: mean
/// ratio 0.994, relative MSE 1.20e-3 with compensation, 1.31e-3 without.
#[test]
fn single_scattering_matches_single_and_compensation_helps() {
    let scene = scene_from(&SMOKE.replace("SIGMA", "8"));
    let reference = single_reference(&scene, 256);
    let base = ZhouSettings { multiple_scattering: false, ..no_cache() };
    let with = zhou(&scene, base, 16);
    let without = zhou(&scene, ZhouSettings { compensation: Compensation::Off, ..base }, 16);
    let (e_with, e_without) = (with.relative_mse(&reference), without.relative_mse(&reference));
    let ratio = mean_ratio(&with, &reference);
    println!(
        "single only: mean ratio {ratio:.4}, relative MSE compensated {e_with:.4e}, uncompensated {e_without:.4e}"
    );
    assert!((ratio - 1.0).abs() < 0.04, "mean ratio {ratio}");
    assert!(e_with < 3e-3, "relative MSE {e_with}");
    assert!(e_with < e_without, "compensated {e_with} vs uncompensated {e_without}");
}

/// Optically thin: the diffusion term vanishes with the optical thickness,
/// so zhou with multiple scattering equals `single` (measured: means within
/// 0.03%, relative MSE 8e-6).
#[test]
fn thin_limit_matches_single() {
    let scene = scene_from(&SMOKE.replace("SIGMA", "0.05"));
    let reference = single_reference(&scene, 64);
    let image = zhou(&scene, no_cache(), 4);
    // Compare the medium's contribution: the background is the same in both.
    let ratio = mean_ratio(&image, &reference);
    let error = image.relative_mse(&reference);
    println!("thin: mean ratio {ratio:.5}, relative MSE {error:.3e}");
    assert!((ratio - 1.0).abs() < 0.02, "mean ratio {ratio}");
    assert!(error < 1e-3, "relative MSE {error}");
}

/// The cache returns the same RBFs; a corrupt file is ignored and refitted.
#[test]
fn fits_are_cached_per_density() {
    let dir = std::env::temp_dir().join(format!("niebla-zhou-cache-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::env::set_var("NIEBLA_CACHE_DIR", &dir);
    let scene = scene_from(&SMOKE.replace("SIGMA", "8"));
    let settings = ZhouSettings { rbf_count: 60, fit_iterations: 10, ..ZhouSettings::default() };
    let first = ZhouIntegrator::new(&scene, settings);
    let files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    assert_eq!(files.len(), 1, "{files:?}");
    let second = ZhouIntegrator::new(&scene, settings);
    assert_eq!(first.rbfs()[0].len(), 60);
    for (a, b) in first.rbfs()[0].iter().zip(second.rbfs()[0]) {
        assert!((a.center - b.center).length() < 1e-6 && (a.radius - b.radius).abs() < 1e-7 && a.weight == b.weight);
    }
    // Other lighting or albedo reuse the fit: same key.
    let brighter = scene_from(&SMOKE.replace("SIGMA", "8").replace("\"albedo\": 0.9", "\"albedo\": 0.5"));
    let third = ZhouIntegrator::new(&brighter, settings);
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
    assert_eq!(third.rbfs()[0][0], second.rbfs()[0][0]);
    std::fs::write(&files[0], b"NIEBLA-RBF-1 truncated").unwrap();
    let refit = ZhouIntegrator::new(&scene, settings);
    assert_eq!(refit.rbfs()[0].len(), 60);
    assert!(std::fs::read(&files[0]).unwrap().len() > 60 * 20);
    std::env::remove_var("NIEBLA_CACHE_DIR");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Against volpath on the smoke scene (40 px wide, volpath 256 spp, zhou 16
/// spp). Measured when written: relative MSE 0.0132 with diffusion, 0.0392
/// single scattering only; the bound allows 25% for noise.
#[test]
fn smoke_error_against_volpath_does_not_regress() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/smoke.json");
    let mut scene = load_scene(&path).unwrap().scene;
    let aspect = scene.camera.height as f64 / scene.camera.width as f64;
    scene.camera.width = 40;
    scene.camera.height = (40.0 * aspect).round() as u32;
    let reference = render_with(&scene, &VolPathIntegrator::new(256), &options(256, 1), &|_, _| {}, None).unwrap();
    let with = zhou(&scene, no_cache(), 16).relative_mse(&reference);
    let without = zhou(&scene, ZhouSettings { multiple_scattering: false, ..no_cache() }, 16).relative_mse(&reference);
    println!("smoke: relative MSE vs volpath: zhou {with:.4}, single scattering only {without:.4}");
    assert!(with < without, "diffusion must bring the image closer: {with} vs {without}");
    assert!(with < 1.25 * MEASURED_WITH, "zhou {with}");
}

const MEASURED_WITH: f64 = 0.0132;

/// Bad `zhou` settings name the field and what was expected.
#[test]
fn bad_settings_name_the_field() {
    let with = |integrator: &str| {
        let text = SMOKE.replace("SIGMA", "8").replace(
            "\"ambient_medium\"",
            &format!("\"render\": {{\"integrator\": {integrator}}}, \"ambient_medium\""),
        );
        match parse_scene_str(&text, "zhou.json") {
            Err(e) => e.to_string(),
            Ok(desc) => match build_scene(&desc, "zhou.json", std::path::Path::new(".")) {
                Err(e) => e.to_string(),
                Ok(_) => String::from("accepted"),
            },
        }
    };
    let e = with(r#"{"type": "zhou", "resolution": 2}"#);
    assert!(e.contains("render.integrator.resolution") && e.contains("between 4 and 128"), "{e}");
    let e = with(r#"{"type": "zhou", "sh_order": 9}"#);
    assert!(e.contains("render.integrator.sh_order"), "{e}");
    let e = with(r#"{"type": "zhou", "compensation": "maybe"}"#);
    assert!(e.contains("compensation") && e.contains("full"), "{e}");
    let e = with(r#"{"type": "zhou", "rbfs": 10}"#);
    assert!(e.contains("rbfs"), "{e}");
    assert_eq!(with(r#"{"type": "zhou", "rbf_count": 50, "transmittance": "exact"}"#), "accepted");
}

/// Point lights inside the fog (scenes/fog.json, 40 px wide, volpath 256
/// spp, zhou 16 spp): lighting them through the calibrated hegeman model
/// (`local_lights: hegeman`, the default) at least halves the relative MSE
/// of lighting them through the RBF model and its diffusion (`rbf`).
/// Measured with `niebla bench interactive` at 96 px: 0.47 against 1.01.
#[test]
fn fog_local_lights_through_hegeman_halve_the_error() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/fog.json");
    let mut scene = load_scene(&path).unwrap().scene;
    let aspect = scene.camera.height as f64 / scene.camera.width as f64;
    scene.camera.width = 40;
    scene.camera.height = (40.0 * aspect).round() as u32;
    let reference = render_with(&scene, &VolPathIntegrator::new(256), &options(256, 1), &|_, _| {}, None).unwrap();
    let hegeman = zhou(&scene, no_cache(), 16).relative_mse(&reference);
    let rbf = zhou(&scene, ZhouSettings { local_lights: LocalLights::Rbf, ..no_cache() }, 16).relative_mse(&reference);
    println!("fog: relative MSE vs volpath: zhou local lights hegeman {hegeman:.4}, rbf {rbf:.4}");
    assert!(hegeman < 0.5 * rbf, "{hegeman} vs {rbf}");
}
