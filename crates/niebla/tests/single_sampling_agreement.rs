//! The three sampling modes of `single` are independent estimators of the same
//! integral: ray marching with a shadow ray per step, equiangular sampling
//! toward point and spot lights (clipped to the spot cone), and MIS of
//! equiangular and distance sampling. On a scene with a spot light, a point
//! light, a directional light, an environment and a lit floor, their images
//! must agree block by block within the noise measured from independent
//! batches (different seeds).

use niebla::integrator::{IntegratorSettings, SingleSampling};
use niebla::render::{render, RenderOptions};
use niebla::scene::{build_scene, parse_scene_str};
use niebla::tracking::{MarchStep, TransmittanceMethod};

const SCENE: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1.5, 5], "target": [0, 1, 0], "fov_y": 50,
             "width": 16, "height": 16},
  "media": {"fog": {"sigma_t": [0.3, 0.35, 0.4], "albedo": 0.8, "phase": {"type": "hg", "g": 0.4}}},
  "shapes": [
    {"type": "box", "min": [-3, -0.5, -3], "max": [3, 4, 6], "interior": "fog"},
    {"type": "rectangle", "to_world": {"scale": 3, "rotate_x": -90}, "bsdf": {"type": "diffuse", "reflectance": 0.5}}
  ],
  "lights": [
    {"type": "spot", "position": [0.5, 3.5, 0], "target": [0, 0, 0], "intensity": 20, "cutoff_angle": 25, "beam_width": 15},
    {"type": "point", "position": [-1.5, 1, 1], "intensity": [1, 2, 3]},
    {"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": 0.5},
    {"type": "constant", "radiance": 0.05}
  ]
}"#;

/// Per 4x4 block and channel: mean over batches and standard error of that mean.
fn block_stats(sampling: SingleSampling, spp: u32, batches: u64) -> Vec<(f64, f64)> {
    let desc = parse_scene_str(SCENE, "agreement.json").unwrap();
    let built = build_scene(&desc, "agreement.json", std::path::Path::new(".")).unwrap();
    let settings = IntegratorSettings::Single {
        step: Some(MarchStep::Length(0.05)),
        sampling,
        transmittance: TransmittanceMethod::Analytic,
        volume_lights: false,
    };
    let mut per_batch: Vec<Vec<f64>> = Vec::new();
    for b in 0..batches {
        let options =
            RenderOptions { spp, seed: 1000 + b, first_sample: 0, threads: None, sampler: Default::default() };
        let image = render(&built.scene, &settings, &options, &|_, _| {}, None).unwrap();
        let mut blocks = vec![0.0f64; 16 * 3];
        for y in 0..16 {
            for x in 0..16 {
                let p = image.get(x, y);
                for c in 0..3 {
                    blocks[((y / 4) * 4 + x / 4) as usize * 3 + c] += p[c] as f64 / 16.0;
                }
            }
        }
        per_batch.push(blocks);
    }
    (0..48)
        .map(|k| {
            let n = batches as f64;
            let mean = per_batch.iter().map(|b| b[k]).sum::<f64>() / n;
            let var = per_batch.iter().map(|b| (b[k] - mean).powi(2)).sum::<f64>() / (n - 1.0);
            (mean, (var / n).sqrt())
        })
        .collect()
}

#[test]
fn march_equiangular_and_mis_agree_on_a_spot_lit_fog() {
    let march = block_stats(SingleSampling::March, 4, 12);
    let equiangular = block_stats(SingleSampling::Equiangular, 64, 12);
    let mis = block_stats(SingleSampling::Mis, 64, 12);
    let mut worst: f64 = 0.0;
    for k in 0..48 {
        for (name, other) in [("equiangular", &equiangular), ("mis", &mis)] {
            let (a, sa) = march[k];
            let (b, sb) = other[k];
            let z = (a - b) / (sa * sa + sb * sb).sqrt().max(1e-6 * a.abs());
            worst = worst.max(z.abs());
            // 96 comparisons: 4.5 standard errors keeps the family-wise false
            // alarm rate below 1e-3 for normal batch means.
            assert!(
                z.abs() < 4.5,
                "block {} channel {}: march {a:.5} +- {sa:.1e} vs {name} {b:.5} +- {sb:.1e}",
                k / 3,
                k % 3
            );
        }
    }
    assert!(march.iter().map(|m| m.0).sum::<f64>() > 0.0);
    println!("worst |z| = {worst:.2}");
}
