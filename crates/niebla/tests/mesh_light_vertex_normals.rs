//! A mesh light with strongly bent vertex normals, in vacuum: one camera
//! ray onto a diffuse floor point under it, against a float64 quadrature
//! the renderer does not use, by three strategies that must all estimate
//! the same integral: light sampling only (`single`, whose surfaces are lit
//! by next-event estimation alone), BSDF sampling only (cosine-distributed
//! rays from the floor point that hit the mesh and see its emitted
//! radiance, through the scene's own intersection and emission code), and
//! `volpath`, which mixes the two by MIS.
//!
//! The light is the open roof of `scenes/mitsuba/data/tent.obj` (two
//! halves meeting at a ridge) turned by `flip_normals` to emit downward,
//! with vertex normals tilted up to 86 degrees off the triangles' normals.
//! A point emits toward the receiver when the direction lies on its
//! interpolated normal's side (7% of the roof's area does not, seen from
//! this floor point), and a surface element `dA` subtends `|cos_g| dA / r^2`
//! with the geometric normal. The floor point's irradiance is
//! `E = L * integral over the emitting points of cos_r |cos_g| / r^2 dA`
//! (every roof point is in view: a segment from the floor point, between
//! the eaves, to the far half passes under the near half), the pixel
//! `rho / pi * E`. With the interpolated normal's cosine in place of
//! `|cos_g|` (Mitsuba 3's emitter-sampling density) the integral is 13%
//! lower; the test asserts that it tells the two apart.

mod common;

use common::mean_se;
use niebla::integrator::{registry, IntegratorSettings};
use niebla::math::{Frame, Ray, Vec3};
use niebla::render::{render, RenderOptions};
use niebla::sampling::PixelSampler;
use niebla::scene::{build_scene, parse_scene_str, Scene};

fn slow() -> bool {
    std::env::var("NIEBLA_SLOW_TESTS").is_ok_and(|v| v == "1")
}

const RADIANCE: f64 = 4.0;
const ALBEDO: f64 = 0.5;
/// The roof's corners (object space; the scene moves them up by 1).
const POSITIONS: [[f64; 3]; 6] =
    [[-0.7, 0.0, -0.6], [-0.7, 0.0, 0.6], [0.0, 0.5, -0.6], [0.0, 0.5, 0.6], [0.7, 0.0, -0.6], [0.7, 0.0, 0.6]];
/// Its triangles, wound so that their normals point up (`flip_normals`
/// turns them down).
const INDICES: [[usize; 3]; 4] = [[0, 1, 3], [0, 3, 2], [2, 3, 5], [2, 5, 4]];
/// Vertex normals (before `flip_normals` negates them), tilted toward the
/// ridge at the eaves and toward +x at the ridge.
const NORMALS: [[f64; 3]; 6] =
    [[1.2, 1.0, -0.3], [1.2, 1.0, 0.3], [0.3, 1.0, -0.2], [0.3, 1.0, 0.2], [-1.2, 1.0, -0.3], [-1.2, 1.0, 0.3]];
/// The floor point the camera ray meets, under the right half of the roof.
const RECEIVER: [f64; 3] = [0.5, 0.0, 0.1];

fn scene() -> Scene {
    let json = |v: &[[f64; 3]]| serde_json::to_string(v).unwrap();
    let indices = serde_json::to_string(&INDICES).unwrap();
    // A 1-pixel, 0.01-degree view from (0.5, 0.5, 2.6) is one ray to the
    // receiver (it passes below the roof, whose eaves are at y = 1).
    let text = format!(
        r#"{{"version": 1,
        "camera": {{"type": "perspective", "position": [0.5, 0.5, 2.6], "target": [0.5, 0, 0.1], "fov_y": 0.01,
                   "width": 1, "height": 1}},
        "shapes": [{{"type": "rectangle", "to_world": {{"scale": 4, "rotate_x": -90}},
                    "bsdf": {{"type": "diffuse", "reflectance": {ALBEDO}}}}}],
        "lights": [{{"type": "area", "radiance": {RADIANCE}, "shape": {{"type": "mesh",
            "positions": {}, "indices": {indices}, "normals": {},
            "flip_normals": true, "to_world": {{"translate": [0, 1, 0]}}}}}}]}}"#,
        json(&POSITIONS),
        json(&NORMALS)
    );
    let desc = parse_scene_str(&text, "roof.json").unwrap_or_else(|e| panic!("{e}"));
    build_scene(&desc, "roof.json", ".".as_ref()).unwrap_or_else(|e| panic!("{e}")).scene
}

type V = glam::DVec3;

/// The receiver's irradiance by the midpoint rule, `m x m` points of equal
/// area per triangle: with the geometric cosine (the physical value), and
/// with the interpolated normal's; the second value's only use is to show
/// that the estimates tell the two apart.
fn irradiance(m: usize) -> (f64, f64) {
    let lift = V::new(0.0, 1.0, 0.0);
    // flip_normals: the winding (here b and c swapped) and the vertex
    // normals reversed.
    let triangles: Vec<_> = INDICES
        .iter()
        .map(|&[i0, i1, i2]| {
            let tri = [i0, i2, i1];
            (tri.map(|i| V::from(POSITIONS[i]) + lift), tri.map(|i| -V::from(NORMALS[i]).normalize()))
        })
        .collect();
    let (geometric, shading) = common::smooth_mesh_irradiance(&triangles, V::from(RECEIVER), V::Y, m);
    (RADIANCE * geometric, RADIANCE * shading)
}

/// The pixel (green) of `batches` independent renders of `spp`.
fn pixels(scene: &Scene, settings: &IntegratorSettings, spp: u32, batches: u64) -> Vec<f64> {
    (0..batches)
        .map(|b| {
            let options =
                RenderOptions { spp, seed: 70 + b, first_sample: 0, threads: None, sampler: Default::default() };
            let image = render(scene, settings, &options, &|_, _| {}, None).unwrap_or_else(|e| panic!("{e}"));
            image.pixels[0][1] as f64
        })
        .collect()
}

#[test]
fn every_strategy_sees_one_integral_from_a_mesh_light_with_vertex_normals() {
    // 300^2 midpoints per triangle are within 3e-5 relative of 1500^2
    // (E = 0.718014 in a float64 script; the side cut makes the rule
    // converge as 1/m).
    let (e, e_shading) = irradiance(300);
    assert!((e - 0.718014 * RADIANCE).abs() < 1e-4 * e, "quadrature {e}");
    let exact = ALBEDO / std::f64::consts::PI * e;
    let scene = scene();
    let batches = if slow() { 64 } else { 16 };
    // Measured standard errors of the mean of 16 batches of 4096: 0.012%
    // (light sampling), 0.02% (MIS), 0.6% (BSDF sampling alone), so the
    // 13% gap to the shading-cosine value is over 20 se for each.
    let mut results = Vec::new();
    for (name, settings) in [
        ("single (light sampling)", registry::defaults("single").unwrap()),
        (
            "volpath (MIS)",
            IntegratorSettings::VolPath { max_depth: 1, volume_light_sampling: true, emitter_guiding: true },
        ),
    ] {
        let (mean, se) = mean_se(&pixels(&scene, &settings, 4096, batches));
        results.push((name, mean, se));
    }
    // BSDF sampling alone at the receiver: cosine-weighted directions
    // traced to the first hit, pi L_e on average, times rho / pi.
    let p = Vec3::new(RECEIVER[0] as f32, RECEIVER[1] as f32, RECEIVER[2] as f32);
    let origin = p + Vec3::Y * 1e-4;
    let frame = Frame::from_z(Vec3::Y);
    let mut rng = PixelSampler::from_key(77);
    let n = 4096 * batches as usize;
    let hits: Vec<f64> = (0..n)
        .map(|_| {
            let w = frame.to_world(niebla::sampling::sample_cosine_hemisphere(rng.next_2d()));
            let ray = Ray::new(origin, w);
            scene
                .intersect(&ray, 0.0, f32::INFINITY)
                .map_or(0.0, |hit| scene.emitted_radiance(&hit, -w).map_or(0.0, |(le, _)| le.g() as f64 * ALBEDO))
        })
        .collect();
    // Batch means of 4096, as for the renders.
    let hit_batches: Vec<f64> = hits.chunks(4096).map(|c| c.iter().sum::<f64>() / c.len() as f64).collect();
    let (mean, se) = mean_se(&hit_batches);
    results.push(("BSDF sampling (hits)", mean, se));
    let shading = ALBEDO / std::f64::consts::PI * e_shading;
    for (name, mean, se) in results {
        eprintln!(
            "{name}: {mean:.6} +- {se:.1e} (z {:.2}); quadrature {exact:.6}, with the shading cosine {shading:.6}",
            (mean - exact) / se
        );
        assert!((mean - exact).abs() < 4.0 * se + 1e-4 * exact, "{name}: {mean} vs {exact} (se {se})");
        assert!((mean - shading).abs() > 10.0 * se, "{name}: does not tell the conventions apart");
    }
}
