//! Emissive media as lights for `single` (`"volume_lights": true`):
//! - the floor under an emissive, purely absorbing sphere equals `rho / pi`
//!   times a 1-D quadrature of the closed-form radiance of the sphere's
//!   chords (and is black with the setting off, as before);
//! - in a scattering fog around an emissive sphere, over a floor, `single`
//!   agrees per 4x4 block within 4 combined standard errors with `volpath`
//!   at `max_depth = 2` without volume light sampling (free flight alone:
//!   emission seen directly and after one scattering event, the same light
//!   transport, by an estimator that shares no code path with `single`'s);
//! - the setting parses, defaults to false, names itself in the key only
//!   when on and reports the distribution's memory.
//!
//! More batches with `NIEBLA_SLOW_TESTS=1`.

mod common;

use common::block_stats;
use niebla::film::Image;
use niebla::integrator::{IntegratorSettings, SingleSampling};
use niebla::render::{render, RenderOptions};
use niebla::scene::{build_scene, parse_scene_str, Scene};
use niebla::tracking::TransmittanceMethod;

fn slow() -> bool {
    std::env::var("NIEBLA_SLOW_TESTS").is_ok_and(|v| v == "1")
}

fn load(text: &str) -> Scene {
    let desc = parse_scene_str(text, "single_volume_lights.json").unwrap();
    build_scene(&desc, "single_volume_lights.json", ".".as_ref()).unwrap().scene
}

fn single(sampling: SingleSampling, volume_lights: bool) -> IntegratorSettings {
    IntegratorSettings::Single { step: None, sampling, transmittance: TransmittanceMethod::Analytic, volume_lights }
}

/// `batches` independent renders (seeds `seed..seed + batches`).
fn batches(scene: &Scene, settings: &IntegratorSettings, spp: u32, batches: u64, seed: u64) -> Vec<Image> {
    (0..batches)
        .map(|b| {
            let options =
                RenderOptions { spp, seed: seed + b, first_sample: 0, threads: None, sampler: Default::default() };
            render(scene, settings, &options, &|_, _| {}, None).unwrap()
        })
        .collect()
}

/// Irradiance at a floor point a distance `d` below the center of a purely
/// absorbing sphere (radius `r`, absorption `sigma_a`) emitting `l_ve` per
/// unit length: a chord of length `l` has radiance `l_ve (1 - e^(-sigma_a l))
/// / sigma_a`, and `E = 2 pi int_0^theta_max L(theta) cos sin dtheta` with
/// `l(theta) = 2 sqrt(r^2 - d^2 sin^2 theta)`, `sin theta_max = r / d`.
fn floor_irradiance(d: f64, r: f64, sigma_a: f64, l_ve: f64) -> f64 {
    let theta_max = (r / d).asin();
    let n = 200_000;
    let h = theta_max / n as f64;
    (0..n)
        .map(|i| {
            let theta = (i as f64 + 0.5) * h;
            let s = theta.sin();
            let chord = 2.0 * (r * r - d * d * s * s).max(0.0).sqrt();
            let l = l_ve * (1.0 - (-sigma_a * chord).exp()) / sigma_a;
            2.0 * std::f64::consts::PI * l * theta.cos() * s * h
        })
        .sum()
}

/// The floor under an emissive, purely absorbing sphere, seen by `single`
/// with volume lights: `rho / pi` times the quadrature's irradiance within 4
/// standard errors; with the setting off the floor stays black (the old image);
/// the image does not depend on the thread count.
#[test]
fn single_floor_under_an_emissive_absorbing_sphere_matches_the_quadrature() {
    let (r, height, sigma_a, l_ve, rho) = (0.5f64, 1.5f64, 2.0f64, 1.5f64, 0.8f64);
    let text = format!(
        r#"{{"version": 1,
        "camera": {{"type": "perspective", "position": [3, 1, 0], "target": [0, 0, 0], "fov_y": 0.2, "width": 4, "height": 4}},
        "media": {{"glow": {{"type": "homogeneous", "sigma_a": {sigma_a}, "sigma_s": 0, "emission": {{"L_ve": {l_ve}}}}}}},
        "shapes": [{{"type": "sphere", "center": [0, {height}, 0], "radius": {r}, "interior": "glow"}},
                   {{"type": "rectangle", "to_world": {{"scale": 4, "rotate_x": -90}},
                    "bsdf": {{"type": "diffuse", "reflectance": {rho}}}}}]}}"#
    );
    let scene = load(&text);
    let expected = rho / std::f64::consts::PI * floor_irradiance(height, r, sigma_a, l_ve);
    let n = if slow() { 64 } else { 16 };
    // Surfaces are shaded alike whatever the sampling along camera rays.
    let images = batches(&scene, &single(SingleSampling::Mis, true), 64, n, 1);
    let (mean, se) = block_stats(&images, 0, 0, 4)[1];
    let z = (mean - expected) / se;
    eprintln!("single: {mean:.6} +- {se:.1e} vs quadrature {expected:.6} (z = {z:.2})");
    assert!(z.abs() < 4.0, "single: {mean} +- {se} vs {expected}");
    assert!(se < 0.01 * expected, "se {se} vs {expected}");
    // Same seed and spp, one thread or two: the same image, bit for bit.
    let threaded = |threads| {
        let options = RenderOptions { spp: 4, seed: 3, first_sample: 0, threads, sampler: Default::default() };
        render(&scene, &single(SingleSampling::March, true), &options, &|_, _| {}, None).unwrap()
    };
    assert_eq!(threaded(Some(1)).pixels, threaded(Some(2)).pixels);
    let off = batches(&scene, &single(SingleSampling::Mis, false), 4, 1, 1);
    assert!(off[0].pixels.iter().all(|p| p.r() == 0.0 && p.g() == 0.0 && p.b() == 0.0));
}

/// An emissive homogeneous sphere inside a chromatic scattering fog, over a
/// diffuse floor and lit by nothing else: `single` with volume lights (march
/// and MIS sampling) against `volpath` at `max_depth = 2` with free flight
/// alone (emission counts along segments after fewer than `max_depth`
/// scattering events, so at most one: the single-scattered emission, the
/// floor lit by the sphere and the emission seen directly, which is exactly
/// what `single` computes). Every 4x4 block and channel within 4 combined SE.
#[test]
fn single_with_volume_lights_equals_volpath_limited_to_one_scattering_event() {
    let scene = load(
        r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 0.5, 4], "target": [0, 0, 0], "fov_y": 50, "width": 16, "height": 16},
        "media": {"glow": {"type": "homogeneous", "sigma_t": [2, 3, 4.5], "albedo": 0.4, "emission": {"L_ve": [3, 2, 1]}},
                  "fog": {"type": "homogeneous", "sigma_t": [0.3, 0.4, 0.6], "albedo": 0.9, "phase": {"type": "hg", "g": 0.3}}},
        "shapes": [{"type": "box", "min": [-2.5, -1, -2.5], "max": [2.5, 2.5, 2.5], "interior": "fog"},
                   {"type": "sphere", "center": [0.3, 0.2, 0], "radius": 0.45, "interior": "glow", "exterior": "fog"},
                   {"type": "rectangle", "to_world": {"scale": 3, "rotate_x": -90, "translate": [0, -0.5, 0]},
                    "bsdf": {"type": "diffuse", "reflectance": 0.5}}]}"#,
    );
    let n = if slow() { 64 } else { 16 };
    let reference = batches(
        &scene,
        &IntegratorSettings::VolPath { max_depth: 2, volume_light_sampling: false, emitter_guiding: true },
        64,
        n,
        5011,
    );
    for sampling in [SingleSampling::Mis, SingleSampling::March] {
        let images = batches(&scene, &single(sampling, true), 8, n, 11);
        let mut lit = 0;
        let mut z_max = 0.0f64;
        for by in 0..4 {
            for bx in 0..4 {
                let a = block_stats(&images, bx * 4, by * 4, 4);
                let b = block_stats(&reference, bx * 4, by * 4, 4);
                for c in 0..3 {
                    let se = (a[c].1.powi(2) + b[c].1.powi(2)).sqrt();
                    let z = (a[c].0 - b[c].0) / (se + 1e-12);
                    assert!(
                        z.abs() < 4.0,
                        "{sampling:?}: block ({bx}, {by}) channel {c}: single {:.5e} +- {:.1e}, volpath {:.5e} +- {:.1e}",
                        a[c].0,
                        a[c].1,
                        b[c].0,
                        b[c].1
                    );
                    if a[c].0 > 1e-3 {
                        lit += 1;
                    }
                    z_max = z_max.max(z.abs());
                }
            }
        }
        eprintln!("single {sampling:?} with volume lights vs volpath: largest |z| {z_max:.2}, {lit} lit");
        assert!(lit > 24, "{sampling:?}: only {lit} lit block channels");
    }
    // The comparison sees the light: without volume lights `single` misses
    // the scattered emission and the floor's light by far more than 4 SE.
    let off = batches(&scene, &single(SingleSampling::Mis, false), 8, n, 11);
    let mut z_max = 0.0f64;
    for by in 0..4 {
        for bx in 0..4 {
            let (a, b) = (block_stats(&off, bx * 4, by * 4, 4), block_stats(&reference, bx * 4, by * 4, 4));
            for c in 0..3 {
                let se = (a[c].1.powi(2) + b[c].1.powi(2)).sqrt();
                z_max = z_max.max((a[c].0 - b[c].0).abs() / (se + 1e-12));
            }
        }
    }
    eprintln!("single without volume lights vs volpath: largest |z| {z_max:.1}");
    assert!(z_max > 10.0, "largest |z| {z_max}");
}

/// `volume_lights` on `single`: a boolean, false by default (old scenes keep
/// their key and image), named in the key only when on; the distribution's
/// memory is reported under its name only when on.
#[test]
fn single_volume_lights_setting_parses_keys_and_counts_memory() {
    use niebla::integrator::{precompute_memory, registry};
    let parse = |v: serde_json::Value| registry::parse(v.as_object().unwrap());
    let default = parse(serde_json::json!({"type": "single", "sampling": "mis"})).unwrap();
    assert_eq!(default, single(SingleSampling::Mis, false));
    assert_eq!(default.key(), "single(step=auto, sampling=mis, transmittance=analytic)");
    let on = parse(serde_json::json!({"type": "single", "sampling": "mis", "volume_lights": true})).unwrap();
    assert_eq!(on, single(SingleSampling::Mis, true));
    assert_eq!(on.key(), "single(step=auto, sampling=mis, transmittance=analytic, volume_lights=true)");
    let e = parse(serde_json::json!({"type": "single", "volume_lights": "yes"})).unwrap_err();
    assert!(e.path.contains("volume_lights") || e.message.contains("volume_lights"), "{e:?}");
    assert!(e.message.contains("bool"), "{e:?}");

    let scene = load(
        r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 1, 5], "target": [0, 0.5, 0], "width": 8, "height": 8},
        "media": {"fire": {"type": "grid", "sigma_t": 6, "albedo": 0.5,
            "density": {"type": "procedural", "shape": "cloud", "seed": 2, "resolution": 16},
            "emission": {"L_ve": 1}}},
        "ambient_medium": "fire"}"#,
    );
    let niebla::medium::Medium::Grid(g) = &scene.media[0] else { panic!("a grid medium") };
    let cells = g.majorant.res().iter().product::<usize>() as u64;
    assert_eq!(cells, 16 * 16 * 16);
    // 16 bytes per light cell; each majorant cell is split 2x2x2 (the finest
    // split within 2^15 light cells).
    let m = precompute_memory(&on, &scene).expect("an estimate with volume lights on");
    assert_eq!((m.bytes, m.field), (16 * 8 * cells, "volume_lights"));
    assert_eq!(precompute_memory(&default, &scene), None);
}
