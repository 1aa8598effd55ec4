//! Emissive media as lights (`volpath`'s `volume_light_sampling`): with and
//! without light sampling of the emission inside media, every 4x4 block of
//! pixels agrees within 4 combined standard errors (the two estimators share
//! no sample: one collects emission only at free-flight collisions, the
//! other mostly by shadow rays toward points drawn in the emitters); and the
//! floor's radiance under an emissive, purely absorbing sphere equals a 1-D
//! quadrature of the closed-form radiance of its chords.
//!
//! Heavier versions (more batches and samples) with `NIEBLA_SLOW_TESTS=1`.

mod common;

use common::block_stats;
use niebla::film::Image;
use niebla::integrator::{IntegratorSettings, VolumeLights};
use niebla::math::Vec3;
use niebla::render::{render, RenderOptions};
use niebla::sampling::PixelSampler;
use niebla::scene::{build_scene, parse_scene_str, Scene};

fn slow() -> bool {
    std::env::var("NIEBLA_SLOW_TESTS").is_ok_and(|v| v == "1")
}

fn load(text: &str) -> Scene {
    let desc = parse_scene_str(text, "volume_lights.json").unwrap();
    build_scene(&desc, "volume_lights.json", ".".as_ref()).unwrap().scene
}

fn volpath(volume_light_sampling: bool) -> IntegratorSettings {
    IntegratorSettings::VolPath { max_depth: 64, volume_light_sampling, emitter_guiding: true }
}

/// Per-pixel means over `batches` renders and the renders themselves.
fn batches(scene: &Scene, settings: &IntegratorSettings, spp: u32, batches: u64, seed: u64) -> Vec<Image> {
    (0..batches)
        .map(|b| {
            let options =
                RenderOptions { spp, seed: seed + b, first_sample: 0, threads: None, sampler: Default::default() };
            render(scene, settings, &options, &|_, _| {}, None).unwrap()
        })
        .collect()
}

/// Every 4x4 block agrees within 4 combined standard errors; returns the
/// ratio of the summed variances (without / with volume light sampling, at
/// their sample counts) over the image. Scenes keep every visible surface
/// near the emitter, so that free flight alone finds its light often enough
/// for batch means to be normal.
fn assert_agree(name: &str, scene: &Scene, spp_with: u32, spp_without: u32, n: u64) -> f64 {
    let with = batches(scene, &volpath(true), spp_with, n, 11);
    let without = batches(scene, &volpath(false), spp_without, n, 5011);
    let (w, h) = (with[0].width / 4, with[0].height / 4);
    let (mut var_with, mut var_without) = (0.0, 0.0);
    let mut lit = 0;
    for by in 0..h {
        for bx in 0..w {
            let a = block_stats(&with, bx * 4, by * 4, 4);
            let b = block_stats(&without, bx * 4, by * 4, 4);
            for c in 0..3 {
                let se = (a[c].1.powi(2) + b[c].1.powi(2)).sqrt();
                let z = (a[c].0 - b[c].0) / (se + 1e-12);
                assert!(
                    z.abs() < 4.0,
                    "{name}: block ({bx}, {by}) channel {c}: with {:.5e} +- {:.1e}, without {:.5e} +- {:.1e}",
                    a[c].0,
                    a[c].1,
                    b[c].0,
                    b[c].1
                );
                var_with += a[c].1.powi(2);
                var_without += b[c].1.powi(2);
                if a[c].0 > 1e-3 {
                    lit += 1;
                }
            }
        }
    }
    assert!(lit > 0, "{name}: nothing lit");
    var_without / var_with
}

/// (a) A procedural emissive cloud (emission proportional to its density)
/// over a diffuse floor, lit by nothing else.
#[test]
fn emissive_grid_over_a_floor_agrees_with_and_without_volume_light_sampling() {
    let scene = load(
        r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 1.6, 3], "target": [0, 0.3, 0], "fov_y": 45, "width": 16, "height": 16},
        "media": {"fire": {"type": "grid", "sigma_t": 6, "albedo": 0.5,
            "density": {"type": "procedural", "shape": "cloud", "seed": 2, "resolution": 24},
            "emission": {"L_ve": [4, 1.6, 0.4]},
            "to_world": {"scale": 1.2, "translate": [-0.6, 0.1, -0.6]}}},
        "shapes": [{"type": "box", "min": [-0.6, 0.1, -0.6], "max": [0.6, 1.3, 0.6], "interior": "fire"},
                   {"type": "rectangle", "to_world": {"scale": 1.6, "rotate_x": -90},
                    "bsdf": {"type": "diffuse", "reflectance": 0.6}}]}"#,
    );
    let n = if slow() { 64 } else { 16 };
    let ratio = assert_agree("emissive grid over a floor", &scene, 16, 64, n);
    eprintln!("emissive grid: variance without / with volume light sampling: {ratio:.2}");
}

/// (b) An emissive homogeneous sphere inside a scattering fog, both with
/// coefficients that differ per channel (one path per pixel sample with a
/// hero channel and spectral MIS over all three).
#[test]
fn emissive_sphere_in_scattering_fog_agrees_with_and_without_volume_light_sampling() {
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
    let ratio = assert_agree("emissive sphere in fog", &scene, 8, 8, n);
    eprintln!("emissive sphere in fog: variance without / with volume light sampling: {ratio:.2}");
}

/// (c) A heterogeneous emissive plume seen through a glass sphere, over a floor.
#[test]
fn emissive_grid_through_glass_agrees_with_and_without_volume_light_sampling() {
    let scene = load(
        r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 0.8, 4], "target": [0, 0.6, 0], "fov_y": 40, "width": 16, "height": 16},
        "media": {"plume": {"type": "grid", "sigma_t": 5, "albedo": 0.7,
            "density": {"type": "procedural", "shape": "plume", "seed": 5, "resolution": 24},
            "emission": {"L_ve": [3, 1.2, 0.3]},
            "to_world": {"scale": 1.2, "translate": [-0.6, 0, -1.2]}}},
        "ambient_medium": "plume",
        "shapes": [{"type": "sphere", "center": [0, 0.6, 1.2], "radius": 0.5, "bsdf": {"type": "dielectric"}},
                   {"type": "rectangle", "to_world": {"scale": 4, "rotate_x": -90},
                    "bsdf": {"type": "diffuse", "reflectance": 0.6}}]}"#,
    );
    let n = if slow() { 64 } else { 16 };
    // Free flight alone reaches the floor's light here mostly through rare
    // paths (hence its larger sample count): at 64 spp its batch means were
    // still skewed low in a block beside the sphere.
    let ratio = assert_agree("emissive grid through glass", &scene, 64, 512, n);
    eprintln!("emissive grid through glass: variance without / with volume light sampling: {ratio:.2}");
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
    // Midpoint rule (the integrand's square-root edge makes Simpson no better).
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

/// The floor under an emissive, purely absorbing sphere: its radiance is
/// `rho / pi` times the quadrature's irradiance, within 4 standard errors,
/// with volume light sampling (and without, at more samples).
#[test]
fn floor_under_an_emissive_absorbing_sphere_matches_the_quadrature() {
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
    for (on, spp) in [(true, 256), (false, 1024)] {
        let images = batches(&scene, &volpath(on), spp, n, if on { 1 } else { 7001 });
        let (mean, se) = block_stats(&images, 0, 0, 4)[1];
        let z = (mean - expected) / se;
        eprintln!("volume light sampling {on}: {mean:.6} +- {se:.1e} vs quadrature {expected:.6} (z = {z:.2})");
        assert!(z.abs() < 4.0, "volume light sampling {on}: {mean} +- {se} vs {expected}");
        if on {
            // Light sampling must actually help here: the relative error is small.
            assert!(se < 0.01 * expected, "se {se} vs {expected}");
        }
    }
}

/// The light distribution's density: the pdf it reports for each drawn point
/// equals the density it evaluates there, and it integrates to one over the
/// emitters (uniform points in a box holding them: the mean of `pdf` times
/// the box volume is 1 within 4 standard errors); no point of a medium is
/// drawn for another.
#[test]
fn volume_light_density_is_normalized_and_consistent() {
    check_density(
        r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 1, 5], "target": [0, 0.5, 0], "width": 8, "height": 8},
        "media": {"fire": {"type": "grid", "sigma_t": 6, "albedo": 0.5,
            "density": {"type": "procedural", "shape": "cloud", "seed": 2, "resolution": 16},
            "emission": {"L_ve": [4, 1.6, 0.4]},
            "to_world": {"scale": [1.2, 0.8, 1.0], "rotate_y": 30, "translate": [-1.5, 0.1, -0.6]}},
                  "glow": {"type": "homogeneous", "sigma_t": 2, "albedo": 0.2, "emission": {"L_ve": 1}}},
        "shapes": [{"type": "sphere", "center": [1, 0.5, 0], "radius": 0.5, "interior": "glow"}]}"#,
    );
}

/// The same checks on a grid whose majorant grid is coarse (4^3 cells, each
/// split into 8^3 light cells), where the light cells' pdf varies within a
/// majorant cell (a dim sphere beside it, so that most points are the
/// grid's): besides, the frequency with which points land in each of
/// the 4^3 octants of the grid's box equals the pdf's integral over it
/// (within 4 standard errors of both).
#[test]
fn subdivided_light_cells_follow_their_density() {
    let scene = check_density(
        r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 1, 5], "target": [0, 0.5, 0], "width": 8, "height": 8},
        "media": {"fire": {"type": "grid", "sigma_t": 6, "albedo": 0.5, "majorant_resolution": 4,
            "density": {"type": "procedural", "shape": "cloud", "seed": 5, "resolution": 32},
            "emission": {"L_ve": [4, 1.6, 0.4]},
            "to_world": {"scale": [1.2, 0.8, 1.0], "rotate_y": 30, "translate": [-1.5, 0.1, -0.6]}},
                  "glow": {"type": "homogeneous", "sigma_t": 2, "albedo": 0.2, "emission": {"L_ve": 0.02}}},
        "shapes": [{"type": "sphere", "center": [1, 0.5, 0], "radius": 0.5, "interior": "glow"}]}"#,
    );
    let niebla::medium::Medium::Grid(g) = &scene.media[0] else { panic!("a grid medium") };
    assert_eq!(g.majorant.res(), [4, 4, 4]);
    let lights = VolumeLights::new(&scene);
    let fire = niebla::medium::MediumId(0);
    let (lo, hi) = g.majorant.bounds();
    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
    let to_world = g.world_to_grid.inverse();
    let octant = |q: Vec3| -> usize {
        let f = ((q - lo) / (hi - lo) * 4.0).clamp(Vec3::ZERO, Vec3::splat(3.999));
        (f.z as usize * 4 + f.y as usize) * 4 + f.x as usize
    };
    let mut s = PixelSampler::from_key(11);
    // Frequencies of drawn points (of the grid medium) per octant.
    let draws = 200_000;
    let mut count = [0u32; 64];
    let mut fire_draws = 0u32;
    for _ in 0..draws {
        let v = lights.sample(s.next_1d(), [s.next_1d(), s.next_1d(), s.next_1d()]).unwrap();
        if v.medium == fire {
            fire_draws += 1;
            count[octant(g.world_to_grid.transform_point3(v.p))] += 1;
        }
    }
    // The pdf's integral per octant, by uniform points in grid space.
    let det = to_world.matrix3.determinant().abs() as f64;
    let box_volume = ((hi - lo).x * (hi - lo).y * (hi - lo).z) as f64 * det;
    let per = 20_000;
    let mut varied = 0;
    for (o, &drawn_here) in count.iter().enumerate() {
        let c = Vec3::new((o % 4) as f32, ((o / 4) % 4) as f32, (o / 16) as f32);
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        let mut values = Vec::with_capacity(per);
        for _ in 0..per {
            let q = lo + (hi - lo) * (c + Vec3::new(s.next_1d(), s.next_1d(), s.next_1d())) / 4.0;
            let f = lights.pdf(fire, to_world.transform_point3(q)) as f64 * box_volume / 64.0;
            sum += f;
            sum2 += f * f;
            values.push(f);
        }
        let mean = sum / per as f64;
        let se = ((sum2 / per as f64 - mean * mean) / per as f64).sqrt();
        let (min, max) = values.iter().fold((f64::MAX, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
        if max > 2.0 * min && mean > 1e-3 {
            varied += 1;
        }
        let p = drawn_here as f64 / draws as f64;
        let se_p = (p * (1.0 - p) / draws as f64).sqrt();
        let combined = (se * se + se_p * se_p).sqrt();
        assert!(
            (p - mean).abs() <= 4.0 * combined + 1e-6,
            "octant {o}: frequency {p} vs integral {mean} +- {combined}"
        );
    }
    assert!(fire_draws > draws / 2, "the grid is drawn most: {fire_draws}");
    assert!(varied >= 4, "the pdf varies within majorant cells in {varied} of them");
}

/// Sampled densities equal evaluated ones, the density integrates to one
/// over a box holding the emitters, and no point of one medium has density
/// in the other; the scene, for further checks.
fn check_density(text: &str) -> Scene {
    let scene = load(text);
    let lights = VolumeLights::new(&scene);
    assert!(!lights.is_empty());
    let mut s = PixelSampler::from_key(3);
    let ids = [niebla::medium::MediumId(0), niebla::medium::MediumId(1)];
    let mut drawn = [0u32; 2];
    for _ in 0..20_000 {
        let v = lights.sample(s.next_1d(), [s.next_1d(), s.next_1d(), s.next_1d()]).unwrap();
        let k = ids.iter().position(|&id| id == v.medium).unwrap();
        drawn[k] += 1;
        let other = ids[1 - k];
        let pdf = lights.pdf(v.medium, v.p);
        assert!((pdf - v.pdf).abs() <= 1e-3 * v.pdf, "{pdf} vs {}", v.pdf);
        assert_eq!(lights.pdf(other, v.p), 0.0, "a point of one medium has no density in the other");
    }
    assert!(drawn[0] > 0 && drawn[1] > 0);
    // Integral over a box holding both emitters, per medium.
    let (lo, hi) = (Vec3::new(-3.0, -1.5, -2.5), Vec3::new(2.0, 2.5, 2.0));
    let volume = (hi - lo).x * (hi - lo).y * (hi - lo).z;
    let n = 400_000;
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let p = lo + (hi - lo) * Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
        let f = (ids.iter().map(|&id| lights.pdf(id, p)).sum::<f32>() * volume) as f64;
        sum += f;
        sum2 += f * f;
    }
    let mean = sum / n as f64;
    let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
    assert!((mean - 1.0).abs() < 4.0 * se, "integral {mean} +- {se}");
    scene
}

/// The setting: parsed with its default, refused with its name when not a
/// boolean, named in the stable key only when off; the distribution's memory
/// is reported to `--max-memory` (16 bytes per light cell of an emissive
/// grid) only when it is on.
#[test]
fn volume_light_sampling_setting_parses_keys_and_counts_memory() {
    use niebla::integrator::{precompute_memory, registry};
    let parse = |v: serde_json::Value| registry::parse(v.as_object().unwrap());
    let on = parse(serde_json::json!({"type": "volpath", "max_depth": 64})).unwrap();
    assert_eq!(on, volpath(true));
    assert_eq!(on.key(), "volpath(max_depth=64)");
    let off = parse(serde_json::json!({"type": "volpath", "max_depth": 64, "volume_light_sampling": false})).unwrap();
    assert_eq!(off, volpath(false));
    assert_eq!(off.key(), "volpath(max_depth=64, volume_light_sampling=false)");
    let e = parse(serde_json::json!({"type": "volpath", "volume_light_sampling": "yes"})).unwrap_err();
    assert!(e.path.contains("volume_light_sampling") || e.message.contains("volume_light_sampling"), "{e:?}");
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
    // 16 bytes per light cell; each of the 4096 majorant cells is split
    // 2x2x2 (the finest split within 2^15 light cells).
    let m = precompute_memory(&on, &scene).expect("an estimate with light sampling on");
    assert_eq!((m.bytes, m.field), (16 * 8 * cells, "volume_light_sampling"));
    assert_eq!(precompute_memory(&off, &scene), None);
}
