//! Mesh area lights in the integrators other than `volpath`, each checked
//! against `volpath` (which shares with them only the light's own sampling
//! code) on a small scene: an open roof of 4 triangles (no vertex normals,
//! turned by `flip_normals` to emit downward; non-convex, so it hides parts
//! of itself) over a diffuse floor inside a fog box.
//!
//! - `single` and `analytic` (area lights by distance sampling) against
//!   `volpath` at `max_depth = 1` (emission seen directly, and one
//!   scattering event, in the fog or on the floor, lit by next-event
//!   estimation: the light transport both compute);
//! - `emission` against `volpath` at `max_depth = 1` with the fog purely
//!   absorbing (`emission` has no in-scattering; the floor is lit directly);
//! - `photon` against full `volpath`: the same per-block test, plus an
//!   allowance for the density estimate's bias (stated below);
//! - `single` against `volpath` at `max_depth = 1` on the same roof with
//!   Mitsuba's computed vertex normals (`compute_normals`), where light
//!   sampling alone (`single`) and `volpath`'s MIS of light and BSDF
//!   sampling agree only if both strategies estimate one integral.
//!
//! Every 4x4 block mean and channel of independent renders (batch means,
//! so each side's standard error is measured) within 4 combined standard
//! errors. More batches with `NIEBLA_SLOW_TESTS=1`.

mod common;

use common::block_stats;
use niebla::film::Image;
use niebla::integrator::{registry, IntegratorSettings};
use niebla::light::Light;
use niebla::render::{render, RenderOptions};
use niebla::scene::{build_scene, parse_scene_str, Scene};

fn slow() -> bool {
    std::env::var("NIEBLA_SLOW_TESTS").is_ok_and(|v| v == "1")
}

/// The roof in fog of albedo `albedo` (extinction 0.4, HG 0.3).
fn roof_in_fog(albedo: f64) -> Scene {
    roof_in_fog_with(albedo, false)
}

/// [`roof_in_fog`], the roof with computed vertex normals if `normals`.
fn roof_in_fog_with(albedo: f64, normals: bool) -> Scene {
    let text = format!(
        r#"{{"version": 1,
        "camera": {{"type": "perspective", "position": [0, 1.2, 4.2], "target": [0, 0.8, 0], "fov_y": 45,
                   "width": 16, "height": 16}},
        "media": {{"fog": {{"type": "homogeneous", "sigma_t": 0.4, "albedo": {albedo}, "phase": {{"type": "hg", "g": 0.3}}}}}},
        "shapes": [{{"type": "box", "min": [-2, -0.05, -2], "max": [2, 2.5, 2], "interior": "fog"}},
                   {{"type": "rectangle", "to_world": {{"scale": 2, "rotate_x": -90}},
                    "bsdf": {{"type": "diffuse", "reflectance": 0.5}}}}],
        "lights": [{{"type": "area", "radiance": [3, 2, 1], "shape": {{"type": "mesh",
            "positions": [[-0.7, 0, -0.6], [-0.7, 0, 0.6], [0, 0.5, -0.6], [0, 0.5, 0.6], [0.7, 0, -0.6], [0.7, 0, 0.6]],
            "indices": [[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]],
            "flip_normals": true, "compute_normals": {normals},
            "to_world": {{"rotate_y": 25, "translate": [0.1, 1.3, -0.2]}}}}}}]}}"#
    );
    let desc = parse_scene_str(&text, "roof.json").unwrap_or_else(|e| panic!("{e}"));
    let scene = build_scene(&desc, "roof.json", ".".as_ref()).unwrap_or_else(|e| panic!("{e}")).scene;
    assert!(matches!(&scene.lights[..], [Light::Area(a)] if a.shape.is_mesh()));
    scene
}

fn volpath(max_depth: u32) -> IntegratorSettings {
    IntegratorSettings::VolPath { max_depth, volume_light_sampling: true, emitter_guiding: true }
}

/// `n` independent renders (seeds `seed..seed + n`).
fn batches(scene: &Scene, settings: &IntegratorSettings, spp: u32, n: u64, seed: u64) -> Vec<Image> {
    (0..n)
        .map(|b| {
            let options =
                RenderOptions { spp, seed: seed + b, first_sample: 0, threads: None, sampler: Default::default() };
            render(scene, settings, &options, &|_, _| {}, None).unwrap_or_else(|e| panic!("{e}"))
        })
        .collect()
}

/// Every block and channel of `images` against `reference`: |difference| <
/// 4 combined standard errors plus `bias` times the reference's block mean.
/// Prints the largest block |z| (difference over combined SE) and the image
/// means with their standard errors; at least 25 block channels must be lit.
fn compare(name: &str, images: &[Image], reference: &[Image], bias: f64) {
    let mut z_max = 0.0f64;
    let mut lit = 0;
    for by in 0..4 {
        for bx in 0..4 {
            let (a, b) = (block_stats(images, bx * 4, by * 4, 4), block_stats(reference, bx * 4, by * 4, 4));
            for c in 0..3 {
                let se = (a[c].1.powi(2) + b[c].1.powi(2)).sqrt();
                let z = (a[c].0 - b[c].0) / (se + 1e-12);
                assert!(
                    (a[c].0 - b[c].0).abs() <= 4.0 * se + bias * b[c].0,
                    "{name}: block ({bx}, {by}) channel {c}: {:.5e} +- {:.1e} vs volpath {:.5e} +- {:.1e} (z {z:.2})",
                    a[c].0,
                    a[c].1,
                    b[c].0,
                    b[c].1
                );
                z_max = z_max.max(z.abs());
                if b[c].0 > 1e-3 {
                    lit += 1;
                }
            }
        }
    }
    // The image means (all channels) with their standard errors.
    let image_mean = |ims: &[Image]| {
        let v: Vec<f64> = ims
            .iter()
            .map(|im| im.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / (3 * im.pixels.len()) as f64)
            .collect();
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
        (m, (var / v.len() as f64).sqrt())
    };
    let ((ma, sa), (mb, sb)) = (image_mean(images), image_mean(reference));
    eprintln!(
        "{name}: largest block |z| {z_max:.2}; image mean {ma:.5} +- {sa:.1e} vs volpath {mb:.5} +- {sb:.1e} (z {:.2})",
        (ma - mb) / (sa * sa + sb * sb).sqrt()
    );
    assert!(lit > 24, "{name}: only {lit} of 48 block channels lit");
}

#[test]
fn single_and_analytic_with_a_mesh_light_equal_volpath_at_depth_one() {
    let scene = roof_in_fog(0.8);
    let n = if slow() { 64 } else { 16 };
    let reference = batches(&scene, &volpath(1), 64, n, 1000);
    for name in ["single", "analytic"] {
        let settings = registry::defaults(name).unwrap();
        let images = batches(&scene, &settings, 16, n, 1);
        compare(name, &images, &reference, 0.0);
    }
}

#[test]
fn emission_with_a_mesh_light_equals_volpath_at_depth_one_in_an_absorbing_fog() {
    let scene = roof_in_fog(0.0);
    let n = if slow() { 64 } else { 16 };
    let reference = batches(&scene, &volpath(1), 64, n, 1000);
    let images = batches(&scene, &registry::defaults("emission").unwrap(), 16, n, 1);
    compare("emission", &images, &reference, 0.0);
}

/// `photon` (single scattering by shadow rays, the rest from a photon map
/// of 200 000 photons emitted from the mesh light's surface, 50 nearest
/// neighbours) against full `volpath`. The photon map's density estimate is
/// biased (it blurs the multiply scattered light over the gather radius);
/// the allowance is 3% of each block's mean on top of 4 combined standard
/// errors.
#[test]
fn photon_with_a_mesh_light_agrees_with_volpath() {
    let scene = roof_in_fog(0.8);
    let n = if slow() { 32 } else { 8 };
    let reference = batches(&scene, &volpath(1024), 64, n, 1000);
    let images = batches(&scene, &registry::defaults("photon").unwrap(), 4, n, 1);
    compare("photon", &images, &reference, 0.03);
}

/// `single` (light sampling alone) against `volpath` at `max_depth = 1`
/// (MIS of light and BSDF sampling) with the roof's computed vertex
/// normals (at the ridge 36 degrees off each half's triangles).
#[test]
fn single_with_a_vertex_normal_mesh_light_equals_volpath_at_depth_one() {
    let scene = roof_in_fog_with(0.8, true);
    let n = if slow() { 64 } else { 16 };
    let reference = batches(&scene, &volpath(1), 64, n, 1000);
    let images = batches(&scene, &registry::defaults("single").unwrap(), 16, n, 1);
    compare("single, vertex normals", &images, &reference, 0.0);
}
