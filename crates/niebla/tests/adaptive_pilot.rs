//! Pilot-allocated sampling (`niebla::adaptive::pilot`): the image has the
//! plain render's expectation with the independent and the Sobol sampler,
//! the allocation keeps its mean and bounds, and the image does not depend
//! on the thread count.

use niebla::adaptive::pilot::{render_pilot, PilotOptions};
use niebla::aov::{Aov, AovSet};
use niebla::color::Rgb;
use niebla::integrator::{registry, PreparedIntegrator};
use niebla::render::RenderOptions;
use niebla::sampling::SamplerKind;
use niebla::scene::{build_scene, parse_scene_str, BuiltScene};

/// A spot light's cone in fog (bench/scenes/fog_spot.json's idea, small;
/// the scene of `tests/adaptive.rs`): bright noisy cone, dim haze, a lit
/// floor, so the noise and the cost per sample vary over the image.
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

fn mean_and_se(values: &[f64]) -> (f64, f64) {
    let m = values.iter().sum::<f64>() / values.len() as f64;
    let v = values.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (values.len() - 1) as f64;
    (m, (v / values.len() as f64).sqrt())
}

/// The image mean over 128 seeds of pilot-allocated renders (16x12 pixels,
/// 8 pilot samples, 64 samples per pixel on average) equals that of 128
/// plain independent renders of 64 spp within 4 SE, with the independent
/// and with the Owen-scrambled Sobol sampler (the claim of the module
/// documentation: `n_p` independent of pass 2, any prefix of a scrambled
/// Sobol sequence unbiased). Smoothing radius 0, so that the allocation
/// follows every pilot's noise (the argument holds for any radius); the
/// allocation must be uneven (the most samples of a pixel at least 3 times
/// the least, else the test shows nothing) and the SE small (below 1% of
/// the mean).
#[test]
fn pilot_mean_over_seeds_matches_the_plain_mean_with_both_samplers() {
    let built = fog_spot(16, 12);
    let scene = &built.scene;
    let volpath = registry::defaults("volpath").unwrap();
    let runs = 128u64;
    let prepared = PreparedIntegrator::new(scene, &volpath);
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
    let (p, sp) = mean_and_se(&plain);
    for sampler in [SamplerKind::Independent, SamplerKind::Sobol] {
        let (mut least, mut most) = (u64::MAX, 0u64);
        let pilot: Vec<f64> = (0..runs)
            .map(|seed| {
                let options = PilotOptions { radius: 0, ..PilotOptions::new(64, seed, sampler) };
                let result = render_pilot(scene, &volpath, &options, None).unwrap();
                least = least.min(*result.spp.iter().min().unwrap());
                most = most.max(*result.spp.iter().max().unwrap());
                result.image.mean().average() as f64
            })
            .collect();
        let (a, sa) = mean_and_se(&pilot);
        let se = (sa * sa + sp * sp).sqrt();
        eprintln!(
            "{}: pilot {a:.5} (SE {sa:.1e}), plain {p:.5} (SE {sp:.1e}), difference {:.2} SE; spp {least}..{most}",
            sampler.name(),
            (a - p) / se
        );
        assert!(se < 0.01 * p, "SE {se} too large to test anything");
        assert!((a - p).abs() <= 4.0 * se, "{}: pilot {a}, plain {p}, SE {se}", sampler.name());
        assert!(most >= 3 * least, "allocation {least}..{most} too even to test anything");
    }
}

/// Pixel by pixel on a 32x24 image: a Sobol pilot-allocated render (32 spp
/// on average) against a plain independent render of 256 spp; the mean
/// difference over the pixels within 4 SE (the variance layers' sum) and at
/// most 3% of the pixel channels beyond 4 of their own SE.
#[test]
fn sobol_pilot_image_matches_the_plain_image_pixel_by_pixel() {
    let built = fog_spot(32, 24);
    let scene = &built.scene;
    let volpath = registry::defaults("volpath").unwrap();
    let result = render_pilot(scene, &volpath, &PilotOptions::new(32, 5, SamplerKind::Sobol), None).unwrap();
    let plain_options =
        RenderOptions { spp: 256, seed: 8, first_sample: 0, threads: None, sampler: SamplerKind::Independent };
    let set = AovSet::EMPTY.with(Aov::Variance);
    let prepared = PreparedIntegrator::new(scene, &volpath);
    let (sums, layers) = prepared.render_aov_sums(scene, &plain_options, set, &|_, _| {}, None).unwrap();
    let (plain, layers) = (sums.mean(256), layers.layers(&sums, 256));
    let plain_var = layers.get(Aov::Variance).unwrap();
    let n = plain.pixels.len();
    let (mut diff, mut var, mut outliers) = (0.0f64, 0.0f64, 0);
    for (i, (a, p)) in result.image.pixels.iter().zip(&plain.pixels).enumerate() {
        for c in 0..3 {
            let d = (a[c] - p[c]) as f64;
            let v = (result.variance[i][c] + plain_var.rgb(i)[c]) as f64;
            diff += d;
            var += v;
            if d.abs() > 4.0 * v.sqrt() + 1e-7 {
                outliers += 1;
            }
        }
    }
    let (mean_diff, se) = (diff / (3 * n) as f64, var.sqrt() / (3 * n) as f64);
    eprintln!("sobol pilot - plain: mean {mean_diff:.3e}, SE {se:.3e}, {outliers} of {} beyond 4 SE", 3 * n);
    assert!(mean_diff.abs() <= 4.0 * se, "mean difference {mean_diff}, SE {se}");
    assert!(outliers <= 3 * n / 100, "{outliers} pixel channels beyond 4 SE");
}

/// The allocation on a real render (3x3 smoothing, so that it is uneven on
/// this small image): the mean is `spp` exactly, every pixel lies between
/// spp / 8 and 8 spp, and pixels of larger `sqrt(v / c)` take more.
/// Layers change neither the beauty nor the spp map, and the split layers
/// add up to the beauty in every pixel.
#[test]
fn allocation_keeps_its_mean_and_bounds_and_layers_split_the_beauty() {
    let built = fog_spot(24, 18);
    let scene = &built.scene;
    let volpath = registry::defaults("volpath").unwrap();
    let split = [Aov::Direct, Aov::Indirect, Aov::Emission, Aov::Surface];
    let set = split.into_iter().fold(AovSet::EMPTY, AovSet::with).with(Aov::Variance).with(Aov::Alpha);
    let mut options = PilotOptions { radius: 1, ..PilotOptions::new(64, 3, SamplerKind::Independent) };
    let bare = render_pilot(scene, &volpath, &options, None).unwrap();
    let pixels = bare.spp.len() as u64;
    assert_eq!(bare.spp.iter().sum::<u64>(), 64 * pixels);
    let (least, most) = (*bare.spp.iter().min().unwrap(), *bare.spp.iter().max().unwrap());
    assert!(least >= 8 && most <= 512, "spp {least}..{most}");
    assert!(most >= 3 * least, "spp {least}..{most}: the noise must be uneven");
    // Pixels of higher sqrt(v / c) take at least as many samples.
    let weight: Vec<f64> = bare.pilot_variance.iter().zip(&bare.pilot_cost).map(|(v, c)| (v / c).sqrt()).collect();
    for i in 0..bare.spp.len() {
        for j in 0..bare.spp.len() {
            if weight[i] > weight[j] * 1.01 {
                assert!(
                    bare.spp[i] + 1 >= bare.spp[j],
                    "pixels {i}, {j}: weights {} > {}, spp {} < {}",
                    weight[i],
                    weight[j],
                    bare.spp[i],
                    bare.spp[j]
                );
            }
        }
    }
    options.layers = set;
    let result = render_pilot(scene, &volpath, &options, None).unwrap();
    assert_eq!(bare.image.pixels, result.image.pixels, "layers changed the beauty");
    assert_eq!(bare.spp, result.spp, "layers changed the spp map");
    let layers = result.layers.as_ref().expect("layers asked for");
    for (i, p) in result.image.pixels.iter().enumerate() {
        let sum = split.iter().fold(Rgb::ZERO, |s, &a| s + layers.get(a).unwrap().rgb(i));
        for c in 0..3 {
            assert!((sum[c] - p[c]).abs() <= 1e-5 * p[c].abs() + 1e-7, "pixel {i}: layers {sum:?}, beauty {p:?}");
        }
        assert_eq!(layers.get(Aov::Variance).unwrap().rgb(i), result.variance[i]);
        let alpha = layers.get(Aov::Alpha).unwrap().data[i];
        assert!((0.0..=1.0).contains(&alpha), "alpha {alpha}");
    }
}

/// The image, the spp map, the variance and the layers are the same with
/// 1 and 2 threads, bit for bit (Sobol sampler, with layers).
#[test]
fn pilot_render_is_deterministic_across_thread_counts() {
    let built = fog_spot(20, 15);
    let scene = &built.scene;
    let volpath = registry::defaults("volpath").unwrap();
    let mut options = PilotOptions::new(32, 9, SamplerKind::Sobol);
    options.layers = AovSet::EMPTY.with(Aov::Direct).with(Aov::Alpha);
    options.threads = Some(1);
    let one = render_pilot(scene, &volpath, &options, None).unwrap();
    options.threads = Some(2);
    let two = render_pilot(scene, &volpath, &options, None).unwrap();
    assert_eq!(one.image, two.image);
    assert_eq!(one.spp, two.spp);
    assert_eq!(one.variance, two.variance);
    assert_eq!(one.dimensions, two.dimensions);
    let (a, b) = (one.layers.unwrap(), two.layers.unwrap());
    for aov in [Aov::Direct, Aov::Alpha] {
        assert_eq!(a.get(aov).unwrap().data, b.get(aov).unwrap().data, "{}", aov.name());
    }
    assert!(one.spp.iter().any(|&n| n != 32), "the allocation must be uneven");
}
