//! Progressive photon beams (`ppb`) checked against numbers it did not
//! compute itself:
//! - on a homogeneous and a heterogeneous fog ball, `ppb` converges to
//!   `volpath` (relative MSE falls with passes; below 1e-2 after 512 passes,
//!   below 2.5e-3 after 4096 passes with `NIEBLA_SLOW_TESTS=1`: ppm's 1e-3
//!   is not reached, see `check_convergence`);
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
    build(&fog_ball_json(medium, size))
}

fn fog_ball_json(medium: &str, size: u32) -> String {
    format!(
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
    )
}

const HOMOGENEOUS: &str = r#"{"sigma_t": 2, "albedo": 0.8, "phase": {"type": "hg", "g": 0.3}}"#;

/// Chromatic extinction: the beams' channel ratio `T_c / T_h` at work.
const CHROMATIC: &str = r#"{"sigma_t": [1.2, 2, 3], "albedo": [0.9, 0.8, 0.7], "phase": {"type": "hg", "g": 0.3}}"#;

/// A linear density ramp along x (grey extinction).
const RAMP: &str = r#"{"type": "grid", "sigma_t": 2, "albedo": 0.8, "phase": {"type": "hg", "g": 0.3},
    "density": {"type": "grid", "dims": [4, 1, 1], "bounds": {"min": [-1, -1, -1], "max": [1, 1, 1]},
                "data": [0.25, 0.75, 1.25, 1.75]}}"#;

fn volpath() -> IntegratorSettings {
    IntegratorSettings::VolPath { max_depth: 1024, volume_light_sampling: true, emitter_guiding: true }
}

fn ppm(photons: u32, radius: f32, surface_radius: f32) -> IntegratorSettings {
    IntegratorSettings::Ppm(PpmSettings {
        photon: PhotonSettings {
            photons,
            radius: Some(radius),
            surface_radius: Some(surface_radius),
            query: VolumeQuery::Beam,
            ..PhotonSettings::ppm()
        },
        alpha: 2.0 / 3.0,
    })
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
    //
    // The slow bound is 2.5e-3, not the 1e-3 that ppm reaches: measured at
    // 4096 passes, ppb is at 1.30e-3 (homogeneous, flat since 2048 passes:
    // 1.35e-3), 1.74e-3 (chromatic) and 1.70e-3 (ramp grid), still falling
    // in the last two. The plateau of the homogeneous ball is an open
    // question (a small bias or the slow 1-D radius schedule), not hidden
    // by this bound: the test fails if convergence gets worse than today.
    let (reference_spp, passes, final_bound) = if slow() { (32_768, 4096, 2.5e-3) } else { (16_384, 512, 1e-2) };
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

#[test]
fn ppb_ppm_and_volpath_agree_on_the_mean() {
    // Image means of the chromatic fog ball over 8 independent batches each
    // (ppb and ppm: seeds, each a full progressive run of 64 passes from the
    // initial radius). Tolerance: 4 combined standard errors plus 1% for the
    // kernels' bias at the ball's boundary and the floor.
    let scene = fog_ball(CHROMATIC, 8);
    let batches = 8;
    let mut values = [Vec::new(), Vec::new(), Vec::new()];
    for b in 0..batches {
        values[0].push(render_n(&scene, volpath(), 2048, 0, 100 + b).mean().average() as f64);
        values[1].push(render_n(&scene, ppb(8000, 0.02, 0.2), 64, 0, 200 + b).mean().average() as f64);
        values[2].push(render_n(&scene, ppm(8000, 0.05, 0.2), 64, 0, 300 + b).mean().average() as f64);
    }
    let (v_mean, v_se) = mean_and_se(&values[0]);
    for (name, v) in [("ppb", &values[1]), ("ppm", &values[2])] {
        let (mean, se) = mean_and_se(v);
        let se = (se * se + v_se * v_se).sqrt();
        eprintln!(
            "{name} {mean:.5} vs volpath {v_mean:.5} +- {v_se:.5}: {:+.2}% ({:.1} SE)",
            (mean / v_mean - 1.0) * 100.0,
            (mean - v_mean) / se
        );
        assert!((mean - v_mean).abs() < 4.0 * se + 0.01 * v_mean, "{name} {mean} vs volpath {v_mean}");
        assert!(se < 0.01 * v_mean, "{name}: standard error {se:.2e} too large to check anything");
    }
}

/// A forward-scattering fog ball lit from behind by a directional light
/// shining towards the camera: most beams run nearly antiparallel to the
/// camera rays, where the 1D estimate's `1 / sin theta` weights are largest.
fn aligned_ball() -> Scene {
    build(
        r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 0, 4], "target": [0, 0, 0],
                   "fov_y": 34, "width": 8, "height": 8},
        "media": {"fog": {"sigma_t": 2, "albedo": 0.9, "phase": {"type": "hg", "g": 0.7}}},
        "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog"}],
        "lights": [{"type": "directional", "direction": [0, 0, 1], "irradiance": 3}]}"#,
    )
}

#[test]
fn line_and_tube_estimates_agree_with_volpath_on_aligned_beams() {
    // Image means over 8 independent batches of 32 passes each, for the
    // 1D estimate alone (tube_sin 0), the 2D tube estimate alone
    // (tube_sin 1) and the 0.25 partition, against volpath. Each is a
    // consistent estimate of the same radiance, so all must agree within 4
    // combined standard errors plus 1.5% for the kernels' bias at radius 0.02
    // (the ball's edge). Also reported: the spread of the batch means, which
    // the tube estimate is meant to lower where beams and rays are parallel.
    let scene = aligned_ball();
    let batches = 8;
    let volpath_values: Vec<f64> =
        (0..batches).map(|b| render_n(&scene, volpath(), 1024, 0, 100 + b).mean().average() as f64).collect();
    let (v_mean, v_se) = mean_and_se(&volpath_values);
    for tube_sin in [0.0, 0.25, 1.0] {
        let settings = IntegratorSettings::Ppb(PpbSettings {
            photons: 4000,
            radius: Some(0.02),
            surface_radius: Some(0.2),
            tube_sin,
            ..PpbSettings::default()
        });
        let values: Vec<f64> =
            (0..batches).map(|b| render_n(&scene, settings, 32, 0, 400 + b).mean().average() as f64).collect();
        let (mean, se) = mean_and_se(&values);
        let se = (se * se + v_se * v_se).sqrt();
        eprintln!(
            "tube_sin {tube_sin}: ppb {mean:.5} vs volpath {v_mean:.5} +- {v_se:.5}: {:+.2}% ({:.1} SE), \
             batch spread {:.2}%",
            (mean / v_mean - 1.0) * 100.0,
            (mean - v_mean) / se,
            se * (batches as f64).sqrt() / v_mean * 100.0
        );
        assert!(
            (mean - v_mean).abs() < 4.0 * se + 0.015 * v_mean,
            "tube_sin {tube_sin}: ppb {mean} vs volpath {v_mean}"
        );
        if tube_sin > 0.0 {
            // The 1D estimate alone is allowed a larger spread (it is the
            // heavy-tailed one); the estimates with tubes must be precise.
            assert!(se < 0.03 * v_mean, "tube_sin {tube_sin}: standard error {se:.2e} too large to check anything");
        }
    }
}

#[test]
fn direct_beams_add_exactly_the_single_scattering_image() {
    // Storing direct beams and surface photons (store_direct) counts direct
    // light twice: the difference of the two renders must be the `single`
    // image (shadow rays), which computes that light independently. Without
    // the sky, whose radiance seen straight from the camera is in `single`'s
    // image but in neither difference term.
    let sky = r#",
          {"type": "constant", "radiance": 0.05}"#;
    let json = fog_ball_json(HOMOGENEOUS, 8);
    assert!(json.contains(sky));
    let scene = build(&json.replace(sky, ""));
    let base = PpbSettings { photons: 8000, radius: Some(0.03), surface_radius: Some(0.1), ..PpbSettings::default() };
    let with = IntegratorSettings::Ppb(PpbSettings { store_direct: true, ..base });
    let without = IntegratorSettings::Ppb(base);
    let single = IntegratorSettings::Single {
        step: None,
        sampling: SingleSampling::Mis,
        transmittance: TransmittanceMethod::Analytic,
        volume_lights: false,
    };
    let batches = 8;
    let mut diffs = Vec::new();
    let mut single_sum = 0.0;
    for b in 0..batches {
        let w = render_n(&scene, with, 32, 32 * b, 5).mean().average() as f64;
        let wo = render_n(&scene, without, 32, 32 * b, 5).mean().average() as f64;
        let s = render_n(&scene, single, 64, 64 * b, 6).mean().average() as f64;
        diffs.push((w - wo) - s);
        single_sum += s;
    }
    let single_mean = single_sum / batches as f64;
    let (mean, se) = mean_and_se(&diffs);
    eprintln!("single {single_mean:.4}; (with - without) - single = {mean:.2e} +- {se:.2e}");
    assert!(
        mean.abs() < 4.0 * se + 0.02 * single_mean,
        "difference {mean:.3e} +- {se:.3e} vs single {single_mean:.3e}"
    );
}

/// Mean over channels of the pixels `x0..x1`, `y0..y1` of `image`.
fn window_mean(image: &Image, (x0, x1): (u32, u32), (y0, y1): (u32, u32)) -> f64 {
    let mut sum = 0.0;
    for y in y0..y1 {
        for x in x0..x1 {
            sum += image.get(x, y).average() as f64;
        }
    }
    sum / ((x1 - x0) * (y1 - y0)) as f64
}

#[test]
fn ppb_and_volpath_agree_on_a_volumetric_caustic() {
    // The narrowed view of scenes/caustic_fog_area.json of ppm's caustic
    // test (tests/photon_mapping.rs): the caustic column under the glass
    // sphere reaches ppb only through beams that passed the glass. Image mean
    // and column mean (pixel columns 6..10, rows 4..13) over 8 independent
    // batches; tolerance 4 combined standard errors plus 1.5% for the
    // kernels' bias where they straddle the floor, the glass or the fog box.
    let mut json = include_str!("../../../scenes/caustic_fog_area.json").to_string();
    for (from, to) in [
        (r#""target": [0.0, 1.2, 0.0]"#, r#""target": [0.0, 0.75, 0.0]"#),
        (r#""fov_y": 45"#, r#""fov_y": 20"#),
        (r#""width": 320"#, r#""width": 16"#),
        (r#""height": 240"#, r#""height": 16"#),
    ] {
        assert!(json.contains(from), "{from:?} not found: the scene file changed");
        json = json.replace(from, to);
    }
    let scene = build(&json);
    let column = ((6, 10), (4, 13));
    let (batches, volpath_spp, passes) = if slow() { (8, 65_536, 512) } else { (8, 16_384, 128) };
    let settings = ppb(10_000, 0.01, 0.03);
    let mut vp = (Vec::new(), Vec::new());
    let mut pb = (Vec::new(), Vec::new());
    for b in 0..batches {
        let image = render_n(&scene, volpath(), volpath_spp, 0, 100 + b);
        vp.0.push(image.mean().average() as f64);
        vp.1.push(window_mean(&image, column.0, column.1));
        let image = render_n(&scene, settings, passes, 0, 200 + b);
        pb.0.push(image.mean().average() as f64);
        pb.1.push(window_mean(&image, column.0, column.1));
    }
    for (name, v, p) in [("image", &vp.0, &pb.0), ("caustic column", &vp.1, &pb.1)] {
        let ((v_mean, v_se), (p_mean, p_se)) = (mean_and_se(v), mean_and_se(p));
        let se = (v_se * v_se + p_se * p_se).sqrt();
        eprintln!(
            "{name}: volpath {v_mean:.5} +- {v_se:.5}, ppb {p_mean:.5} +- {p_se:.5}, difference {:+.2}% ({:.1} SE)",
            (p_mean / v_mean - 1.0) * 100.0,
            (p_mean - v_mean) / se
        );
        assert!(
            (p_mean - v_mean).abs() < 4.0 * se + 0.015 * v_mean,
            "{name}: volpath {v_mean} +- {v_se}, ppb {p_mean} +- {p_se}"
        );
        assert!(se < 0.02 * v_mean, "{name}: standard error {se:.2e} too large to check anything");
    }
}

#[test]
fn chromatic_grids_are_refused_with_a_clear_error() {
    let scene = fog_ball(&RAMP.replace(r#""sigma_t": 2,"#, r#""sigma_t": [1, 2, 3],"#), 4);
    let options = RenderOptions { spp: 1, seed: 0, first_sample: 0, threads: None, sampler: Default::default() };
    let e = render(&scene, &ppb(100, 0.1, 0.1), &options, &|_, _| {}, None).unwrap_err();
    assert!(matches!(e, RenderError::Unsupported { integrator: "ppb", .. }), "{e:?}");
    let message = e.to_string();
    assert!(message.contains("\"fog\"") && message.contains("grey sigma_t"), "{message}");
}

#[test]
fn ppb_is_bit_identical_for_any_thread_count() {
    let scene = fog_ball(RAMP, 13);
    let images: Vec<Image> = [1, 2, 3]
        .iter()
        .map(|&threads| {
            let options = RenderOptions {
                spp: 3,
                seed: 42,
                first_sample: 0,
                threads: Some(threads),
                sampler: Default::default(),
            };
            render(&scene, &ppb(3000, 0.05, 0.1), &options, &|_, _| {}, None).unwrap()
        })
        .collect();
    assert!(images[0].mean().max_channel() > 0.0);
    for other in &images[1..] {
        assert_eq!(images[0].pixels, other.pixels);
    }
}
