//! Adaptive sampling (`niebla::adaptive`): the image has the plain
//! render's expectation, and pixels of uneven noise take uneven samples.

use niebla::adaptive::{render_adaptive, AdaptiveOptions};
use niebla::aov::{Aov, AovSet};
use niebla::integrator::{registry, PreparedIntegrator};
use niebla::render::RenderOptions;
use niebla::sampling::SamplerKind;
use niebla::scene::{build_scene, parse_scene_str, BuiltScene};

/// A spot light's cone in fog (bench/scenes/fog_spot.json's idea, small):
/// bright noisy cone, dim haze, a lit floor.
fn fog_spot(width: u32, height: u32) -> BuiltScene {
    let text = format!(
        r#"{{"version": 1,
        "camera": {{"type": "perspective", "position": [0, 1, 4], "target": [0, 0.8, 0], "width": {width}, "height": {height}}},
        "media": {{"fog": {{"type": "homogeneous", "sigma_t": 0.3, "albedo": 0.9, "phase": {{"type": "hg", "g": 0.5}}}}}},
        "ambient_medium": "fog",
        "shapes": [{{"type": "rectangle", "to_world": {{"scale": 6, "rotate_x": -90}}, "bsdf": {{"type": "diffuse", "reflectance": 0.5}}}}],
        "lights": [{{"type": "spot", "position": [0, 3, 0], "target": [0.3, 0, 0], "intensity": 40, "beam_width": 12, "cutoff_angle": 18}}]}}"#
    );
    let desc = parse_scene_str(&text, "fog_spot_small.json").unwrap_or_else(|e| panic!("{e}"));
    build_scene(&desc, "fog_spot_small.json", std::path::Path::new(".")).unwrap()
}

#[test]
fn adaptive_image_has_the_plain_mean() {
    let built = fog_spot(32, 24);
    let scene = &built.scene;
    let volpath = registry::defaults("volpath").unwrap();
    let spp = 64;
    let options = AdaptiveOptions { spp, threshold: 0.05, seed: 7, threads: None };
    let adaptive = render_adaptive(scene, &volpath, &options, &|_, _| {}, None).unwrap();
    let plain_options =
        RenderOptions { spp, seed: 8, first_sample: 0, threads: None, sampler: SamplerKind::Independent };
    let set = AovSet::EMPTY.with(Aov::Variance);
    let prepared = PreparedIntegrator::new(scene, &volpath);
    let (sums, layers) = prepared.render_aov_sums(scene, &plain_options, set, &|_, _| {}, None).unwrap();
    let (plain, layers) = (sums.mean(spp as u64), layers.layers(&sums, spp as u64));
    let plain_var = layers.get(Aov::Variance).unwrap();
    let n = plain.pixels.len();
    let (mut diff, mut var, mut outliers) = (0.0f64, 0.0f64, 0);
    for (i, (a, p)) in adaptive.image.pixels.iter().zip(&plain.pixels).enumerate() {
        for c in 0..3 {
            let d = (a[c] - p[c]) as f64;
            let v = (adaptive.variance[i][c] + plain_var.rgb(i)[c]) as f64;
            diff += d;
            var += v;
            if d.abs() > 4.0 * v.sqrt() + 1e-7 {
                outliers += 1;
            }
        }
    }
    let (mean_diff, se) = (diff / (3 * n) as f64, var.sqrt() / (3 * n) as f64);
    let taken: u64 = adaptive.spp.iter().sum();
    let fewer = adaptive.spp.iter().filter(|&&s| s < spp as u64).count();
    eprintln!(
        "adaptive - plain: mean {mean_diff:.3e}, SE {se:.3e}, {outliers} of {} beyond 4 SE; {:.1}% of the samples, {fewer} of {n} pixels stopped early",
        3 * n,
        100.0 * taken as f64 / (n as f64 * spp as f64)
    );
    assert!(mean_diff.abs() <= 4.0 * se, "mean difference {mean_diff}, SE {se}");
    assert!(outliers <= 3 * n / 100, "{outliers} pixel channels beyond 4 SE");
    assert!(fewer > 0 && fewer < n, "{fewer} of {n} pixels stopped early: the noise must be uneven");
}

/// Unbiasedness over many independent renders of one small image: the
/// mean of 64 adaptive renders (at most 64 spp) against 64 plain renders
/// of 64 spp, within 4 SE.
#[test]
fn adaptive_mean_over_seeds_matches_the_plain_mean() {
    let built = fog_spot(8, 6);
    let scene = &built.scene;
    let volpath = registry::defaults("volpath").unwrap();
    let runs = 64u64;
    let mean_and_se = |values: &[f64]| {
        let m = values.iter().sum::<f64>() / values.len() as f64;
        let v = values.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (values.len() - 1) as f64;
        (m, (v / values.len() as f64).sqrt())
    };
    let prepared = PreparedIntegrator::new(scene, &volpath);
    let adaptive: Vec<f64> = (0..runs)
        .map(|seed| {
            let options = AdaptiveOptions { spp: 64, threshold: 0.2, seed, threads: None };
            render_adaptive(scene, &volpath, &options, &|_, _| {}, None).unwrap().image.mean().average() as f64
        })
        .collect();
    let plain: Vec<f64> = (0..runs)
        .map(|seed| {
            let options = RenderOptions {
                spp: 64,
                seed: 1000 + seed,
                first_sample: 0,
                threads: None,
                sampler: SamplerKind::Independent,
            };
            prepared.render(scene, &options, &|_, _| {}, None).unwrap().mean().average() as f64
        })
        .collect();
    let ((a, sa), (p, sp)) = (mean_and_se(&adaptive), mean_and_se(&plain));
    let se = (sa * sa + sp * sp).sqrt();
    eprintln!("image mean over {runs} seeds: adaptive {a:.5} (SE {sa:.1e}), plain {p:.5} (SE {sp:.1e})");
    assert!((a - p).abs() <= 4.0 * se, "adaptive {a}, plain {p}, SE {se}");
}

/// The figure of the report (run by hand): time and relative MSE against a
/// 1024 spp reference, plain (independent and Sobol samplers) and adaptive
/// (independent, as it must be), on the small fog_spot scene.
/// `cargo test -p niebla --test adaptive -- --ignored --nocapture`
#[test]
#[ignore]
fn adaptive_time_to_error_figure() {
    let built = fog_spot(96, 72);
    let scene = &built.scene;
    let volpath = registry::defaults("volpath").unwrap();
    let prepared = PreparedIntegrator::new(scene, &volpath);
    let plain = |spp: u32, seed: u64, sampler: SamplerKind| {
        let options = RenderOptions { spp, seed, first_sample: 0, threads: None, sampler };
        let start = std::time::Instant::now();
        let image = prepared.render(scene, &options, &|_, _| {}, None).unwrap();
        (image, start.elapsed().as_secs_f64())
    };
    let (reference, t_ref) = plain(1024, 1, SamplerKind::Sobol);
    eprintln!("reference 1024 spp: {t_ref:.1} s");
    for sampler in [SamplerKind::Independent, SamplerKind::Sobol] {
        for spp in [16, 32, 64, 128, 256] {
            let (image, t) = plain(spp, 2, sampler);
            eprintln!(
                "plain {} {spp:4} spp: rel MSE {:.3e} in {t:.2} s",
                sampler.name(),
                image.relative_mse(&reference)
            );
        }
    }
    for threshold in [0.1f32, 0.05, 0.03] {
        for spp in [64, 128, 256] {
            let options = AdaptiveOptions { spp, threshold, seed: 2, threads: None };
            let start = std::time::Instant::now();
            let result = render_adaptive(scene, &volpath, &options, &|_, _| {}, None).unwrap();
            let t = start.elapsed().as_secs_f64();
            let taken = result.spp.iter().sum::<u64>() as f64 / result.spp.len() as f64;
            eprintln!(
                "adaptive {spp:4} spp threshold {threshold}: rel MSE {:.3e} in {t:.2} s (mean {taken:.1} spp taken)",
                result.image.relative_mse(&reference)
            );
        }
    }
}
