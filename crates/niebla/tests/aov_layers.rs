//! Layers beside the beauty (`niebla::aov`): alpha against the closed form
//! of a slab, the transparent film recomposited over its background against
//! the opaque render, the split layers adding up to the beauty, and
//! `volpath`'s `direct` layer against the `single` integrator.

use niebla::aov::{Aov, AovImage, AovSet};
use niebla::color::Rgb;
use niebla::film::Image;
use niebla::integrator::{registry, IntegratorSettings, PreparedIntegrator};
use niebla::math::Vec2;
use niebla::render::RenderOptions;
use niebla::sampling::SamplerKind;
use niebla::scene::{build_scene, parse_scene_str, BuiltScene};

fn build(text: &str) -> BuiltScene {
    let desc = parse_scene_str(text, "aov_test.json").unwrap_or_else(|e| panic!("{e}"));
    build_scene(&desc, "aov_test.json", std::path::Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
}

/// The beauty and layers `set` of `spp` samples per pixel with `seed`.
fn render(built: &BuiltScene, settings: &IntegratorSettings, spp: u32, seed: u64, set: AovSet) -> (Image, AovImage) {
    let options = RenderOptions { spp, seed, first_sample: 0, threads: None, sampler: SamplerKind::Sobol };
    let prepared = PreparedIntegrator::new(&built.scene, settings);
    let (sums, layers) = prepared.render_aov_sums(&built.scene, &options, set, &|_, _| {}, None).unwrap();
    (sums.mean(spp as u64), layers.layers(&sums, spp as u64))
}

/// A slab `|z| < 0.5`, wide enough to fill the view, of a medium with
/// `sigma_t = 1` (`medium` JSON), seen along -z from z = 5.
fn slab(medium: &str) -> String {
    format!(
        r#"{{"version": 1,
            "camera": {{"type": "perspective", "position": [0, 0, 5], "target": [0, 0, 0],
                        "width": 16, "height": 16, "fov_y": 10}},
            "media": {{"slab": {medium}}},
            "shapes": [{{"type": "box", "min": [-20, -20, -0.5], "max": [20, 20, 0.5], "interior": "slab"}}],
            "lights": [{{"type": "constant", "radiance": 1}}]}}"#
    )
}

/// `1 - exp(-sigma_t d)` for the ray through the centre of pixel (x, y)
/// crossing the unit slab (`d = 1 / |dir.z|`).
fn slab_alpha(built: &BuiltScene, x: u32, y: u32) -> f32 {
    let ray = built.scene.camera.generate_ray(x, y, Vec2::splat(0.5));
    1.0 - (-1.0 / ray.d.z.abs()).exp()
}

/// Largest change of the slab's alpha within one pixel of this camera: the
/// path length `1/cos` varies by less than 1e-3 relative at a 10 degree
/// field of view, and `d alpha / d ln d <= 1/e`.
const WITHIN_PIXEL: f32 = 1e-3;

#[test]
fn alpha_of_a_slab_is_one_minus_its_transmittance() {
    let alpha_set = AovSet::EMPTY.with(Aov::Alpha);
    let emission = registry::defaults("emission").unwrap();
    // Homogeneous: transmittance in closed form, so every sample is exact.
    let built = build(&slab(r#"{"type": "homogeneous", "sigma_t": 1, "albedo": 0.5}"#));
    let (_, layers) = render(&built, &emission, 4, 1, alpha_set);
    let alpha = &layers.get(Aov::Alpha).unwrap().data;
    for y in 0..16 {
        for x in 0..16 {
            let expected = slab_alpha(&built, x, y);
            let got = alpha[(y * 16 + x) as usize];
            assert!((got - expected).abs() <= WITHIN_PIXEL, "pixel ({x}, {y}): alpha {got}, expected {expected}");
        }
    }
    // A grid of constant density: ratio tracking with the majorant equal
    // to sigma_t, an estimate in [0, 1] per sample, so its standard error
    // over n samples is at most sqrt(0.25 / n).
    let built = build(&slab(
        r#"{"type": "grid", "sigma_t": 1, "albedo": 0.5,
            "density": {"type": "constant", "value": 1, "bounds": {"min": [-20, -20, -0.5], "max": [20, 20, 0.5]}}}"#,
    ));
    let spp = 256;
    let (_, layers) = render(&built, &emission, spp, 2, alpha_set);
    let alpha = &layers.get(Aov::Alpha).unwrap().data;
    let se = (0.25 / spp as f32).sqrt();
    let mut mean_error = 0.0;
    for y in 0..16 {
        for x in 0..16 {
            let expected = slab_alpha(&built, x, y);
            let got = alpha[(y * 16 + x) as usize];
            assert!(
                (got - expected).abs() <= 4.0 * se + WITHIN_PIXEL,
                "pixel ({x}, {y}): alpha {got}, expected {expected} (4 SE = {})",
                4.0 * se
            );
            mean_error += (got - expected) / 256.0;
        }
    }
    eprintln!("grid slab: mean alpha error {mean_error:.2e}, per-pixel SE bound {se:.4}");
    // The image mean: 256 independent pixels.
    assert!(mean_error.abs() <= 4.0 * se / 16.0 + WITHIN_PIXEL, "mean alpha error {mean_error}");
}

/// Fog in a sphere before a constant sky of radiance 1, lit by a point
/// light and the sky; `film` is the scene's film object.
fn fog_before_sky(film: &str) -> String {
    format!(
        r#"{{"version": 1,
            "camera": {{"type": "perspective", "position": [0, 0, 4], "target": [0, 0, 0], "width": 16, "height": 16, "fov_y": 40}},
            "film": {film},
            "media": {{"fog": {{"type": "homogeneous", "sigma_t": 1.2, "albedo": 0.8, "phase": {{"type": "hg", "g": 0.3}}}}}},
            "shapes": [{{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog"}}],
            "lights": [{{"type": "point", "position": [1, 2, 1], "intensity": 5}}, {{"type": "constant", "radiance": 1}}]}}"#
    )
}

#[test]
fn transparent_render_over_its_background_is_the_opaque_render() {
    let volpath = registry::defaults("volpath").unwrap();
    let set = AovSet::parse(["alpha", "variance"]).unwrap();
    let spp = 64;
    let (opaque, opaque_layers) = render(&build(&fog_before_sky("{}")), &volpath, spp, 3, set);
    let transparent_scene = build(&fog_before_sky(r#"{"transparent": true}"#));
    assert!(
        transparent_scene.scene.transparent_background && transparent_scene.settings.film.aovs.contains(Aov::Alpha)
    );
    let (held_out, layers) = render(&transparent_scene, &volpath, spp, 4, set);
    let alpha = &layers.get(Aov::Alpha).unwrap().data;
    let (var_o, var_t) = (opaque_layers.get(Aov::Variance).unwrap(), layers.get(Aov::Variance).unwrap());
    let n = opaque.pixels.len();
    let (mut diff_sum, mut var_sum, mut outliers, mut sky_pixels) = (0.0f64, 0.0f64, 0, 0);
    for (i, &a) in alpha.iter().enumerate() {
        // The sky has radiance 1: composite = held_out + (1 - alpha) * 1.
        let composite = held_out.pixels[i] + Rgb::splat(1.0 - a);
        if a == 0.0 {
            sky_pixels += 1;
            assert_eq!(held_out.pixels[i], Rgb::ZERO, "pixel {i}: the sky seen directly is held out");
        }
        for c in 0..3 {
            let d = (composite[c] - opaque.pixels[i][c]) as f64;
            let var = (var_o.rgb(i)[c] + var_t.rgb(i)[c]) as f64;
            diff_sum += d;
            var_sum += var;
            if d.abs() > 4.0 * var.sqrt() + 1e-6 {
                outliers += 1;
            }
        }
    }
    assert!(sky_pixels > 0 && sky_pixels < n, "{sky_pixels} of {n} pixels see the sky alone");
    // Image mean within 4 combined SE; single pixels beyond 4 SE are rare.
    let (mean_diff, se) = (diff_sum / (3 * n) as f64, var_sum.sqrt() / (3 * n) as f64);
    eprintln!(
        "composite - opaque: mean {mean_diff:.3e}, SE {se:.3e}, {outliers} of {} pixel channels beyond 4 SE",
        3 * n
    );
    assert!(mean_diff.abs() <= 4.0 * se, "mean difference {mean_diff}, SE {se}");
    assert!(outliers <= 3 * n / 100, "{outliers} of {} pixel channels beyond 4 SE", 3 * n);
}

#[test]
fn split_layers_add_up_to_the_beauty() {
    // Surfaces (a diffuse floor), single and multiple scattering, emission
    // (a glowing medium and the sky), all in one scene.
    let text = r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 0.5, 0], "width": 24, "height": 16},
        "media": {"fog": {"type": "homogeneous", "sigma_t": 2, "albedo": 0.9, "emission": {"L_ve": [0.2, 0.1, 0.05]}}},
        "shapes": [{"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6, "interior": "fog"},
                   {"type": "rectangle", "to_world": {"scale": 4, "rotate_x": -90}, "bsdf": {"type": "diffuse", "reflectance": 0.6}}],
        "lights": [{"type": "point", "position": [1, 2.5, 1], "intensity": 8}, {"type": "constant", "radiance": 0.3}]}"#;
    let built = build(text);
    let volpath = registry::defaults("volpath").unwrap();
    let spp = 16;
    let (beauty, layers) = render(&built, &volpath, spp, 5, AovSet::parse(["all"]).unwrap());
    // The beauty is the plain render's, bit for bit.
    let options = RenderOptions { spp, seed: 5, first_sample: 0, threads: None, sampler: SamplerKind::Sobol };
    let plain = PreparedIntegrator::new(&built.scene, &volpath).render(&built.scene, &options, &|_, _| {}, None);
    assert_eq!(plain.unwrap(), beauty);
    let split = [Aov::Direct, Aov::Indirect, Aov::Emission, Aov::Surface].map(|a| layers.get(a).unwrap());
    let mut totals = [0.0f64; 4];
    for i in 0..beauty.pixels.len() {
        for c in 0..3 {
            let parts = split.map(|l| l.rgb(i)[c]);
            let sum: f32 = parts.iter().sum();
            let scale: f32 = parts.iter().map(|p| p.abs()).sum::<f32>() + beauty.pixels[i][c].abs();
            // Per sample the split and the total add the same f32 terms in
            // other orders; each mean is rounded to f32 once.
            assert!(
                (sum - beauty.pixels[i][c]).abs() <= 1e-5 * scale + 1e-9,
                "pixel {i} channel {c}: layers {parts:?} add to {sum}, beauty {}",
                beauty.pixels[i][c]
            );
            for (t, p) in totals.iter_mut().zip(parts) {
                *t += p as f64;
            }
        }
    }
    eprintln!("image sums of direct, indirect, emission, surface: {totals:?}");
    assert!(totals.iter().all(|&t| t > 0.0), "every split layer has light: {totals:?}");
    // Features: albedo in [0, 1], normals of length 1 or 0 per sample.
    let albedo = layers.get(Aov::Albedo).unwrap();
    assert!(albedo.data.iter().all(|&a| (0.0..=1.0 + 1e-6).contains(&a)));
    let normal = layers.get(Aov::Normal).unwrap();
    assert!((0..beauty.pixels.len()).all(|i| normal.vec3(i).length() <= 1.0 + 1e-4));
    let depth = &layers.get(Aov::Depth).unwrap().data;
    assert!(depth.iter().all(|&d| (0.0..20.0).contains(&d)) && depth.iter().any(|&d| d > 3.0));
}

#[test]
fn direct_layer_equals_the_single_integrator() {
    // Fog filling the view, lit by a point light, nothing else: `single`
    // computes single scattering, volpath's `direct` layer is the same.
    let text = r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 0, 3], "target": [0, 0, 0], "width": 16, "height": 16, "fov_y": 50},
        "media": {"fog": {"type": "homogeneous", "sigma_t": 0.8, "albedo": 0.9, "phase": {"type": "hg", "g": 0.4}}},
        "shapes": [{"type": "box", "min": [-2, -2, -2], "max": [2, 2, 2], "interior": "fog"}],
        "lights": [{"type": "point", "position": [0.5, 0.5, 0], "intensity": 4}]}"#;
    let built = build(text);
    let volpath = registry::defaults("volpath").unwrap();
    let single =
        registry::parse_with_overrides(&serde_json::Map::new(), Some("single"), &[("sampling", "mis".into())]).unwrap();
    let direct_set = AovSet::EMPTY.with(Aov::Direct);
    // Independent renders (seeds): the spread of their image means gives
    // the standard error of each method's mean.
    let runs = 16;
    let means = |settings: &IntegratorSettings, direct: bool| -> (f64, f64) {
        let values: Vec<f64> = (0..runs)
            .map(|seed| {
                let (beauty, layers) = render(&built, settings, 4, 100 + seed, direct_set);
                let image = if direct {
                    let l = layers.get(Aov::Direct).unwrap();
                    (0..beauty.pixels.len()).map(|i| l.rgb(i).average() as f64).sum::<f64>()
                } else {
                    beauty.pixels.iter().map(|p| p.average() as f64).sum::<f64>()
                };
                image / beauty.pixels.len() as f64
            })
            .collect();
        let mean = values.iter().sum::<f64>() / runs as f64;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (runs - 1) as f64;
        (mean, (var / runs as f64).sqrt())
    };
    let (direct, se_direct) = means(&volpath, true);
    let (single_mean, se_single) = means(&single, false);
    let se = (se_direct.powi(2) + se_single.powi(2)).sqrt();
    eprintln!("volpath direct {direct:.5} (SE {se_direct:.1e}), single {single_mean:.5} (SE {se_single:.1e})");
    assert!(direct > 0.0 && se < 0.05 * direct, "direct {direct}, SE {se}");
    assert!(
        (direct - single_mean).abs() <= 4.0 * se,
        "volpath direct {direct}, single {single_mean}, combined SE {se}"
    );
}
