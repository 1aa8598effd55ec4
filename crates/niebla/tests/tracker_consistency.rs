//! The same heterogeneous scene rendered with delta, ratio and residual ratio
//! transmittance (camera and shadow rays) has the same mean, pixel block by
//! pixel block, within the noise measured from independent batches.

mod common;

use std::sync::Arc;

use common::scene;
use glam::Affine3A;
use niebla::color::Rgb;
use niebla::integrator::{IntegratorSettings, SingleSampling};
use niebla::light::{DirectionalLight, Light, PointLight};
use niebla::math::Vec3;
use niebla::medium::{DensityGrid, GridEmission, GridMedium, Medium, MediumId};
use niebla::phase::PhaseFunction;
use niebla::render::{render, RenderOptions};
use niebla::sampling::PixelSampler;
use niebla::tracking::TransmittanceMethod;
use niebla_volume::{DenseGrid, MajorantGrid};

fn smoke() -> Medium {
    let n = 16;
    let mut s = PixelSampler::from_key(8);
    let values: Vec<f32> = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, (i / n) % n, i / (n * n));
            let r2 = [x, y, z].iter().map(|&v| (v as f32 - 7.5).powi(2)).sum::<f32>();
            if r2 < 40.0 {
                3.0 * s.next_1d()
            } else {
                0.0
            }
        })
        .collect();
    let grid = DenseGrid::new([n, n, n], values, [3.0, -1.0, -1.0], [5.0, 1.0, 1.0]).unwrap();
    let majorant = MajorantGrid::from_dense(&grid, [4, 4, 4]);
    let minorant = MajorantGrid::minorant_from_dense(&grid, [4, 4, 4]);
    Medium::Grid(GridMedium::new(
        Rgb::new(0.2, 0.3, 0.4),
        Rgb::new(1.5, 1.2, 0.9),
        DensityGrid::Dense(Arc::new(grid)),
        Affine3A::IDENTITY,
        majorant,
        Some(minorant),
        GridEmission::None,
        PhaseFunction::hg(0.4),
    ))
}

#[test]
fn delta_ratio_and_residual_ratio_render_the_same_mean() {
    let lights = vec![
        Light::Directional(DirectionalLight {
            direction: Vec3::new(0.2, -1.0, 0.1).normalize(),
            irradiance: Rgb::splat(4.0),
        }),
        Light::Point(PointLight { position: Vec3::new(4.0, 0.0, 2.0), intensity: Rgb::splat(3.0) }),
    ];
    let s = scene(common::camera_along_x(8, 8, 30.0), vec![], vec![smoke()], lights, Some(MediumId(0)));
    let batches = 10u64;
    let stats = |method: TransmittanceMethod| -> Vec<(f64, f64)> {
        let settings = IntegratorSettings::Single {
            step: None,
            sampling: SingleSampling::Mis,
            transmittance: method,
            volume_lights: false,
        };
        let images: Vec<_> = (0..batches)
            .map(|b| {
                render(
                    &s,
                    &settings,
                    &RenderOptions {
                        spp: 32,
                        seed: 500 + b,
                        first_sample: 0,
                        threads: None,
                        sampler: Default::default(),
                    },
                    &|_, _| {},
                    None,
                )
                .unwrap()
            })
            .collect();
        // 2x2 pixel blocks, green channel.
        (0..16)
            .map(|blk| {
                let (bx, by) = ((blk % 4) * 2, (blk / 4) * 2);
                let vals: Vec<f64> = images
                    .iter()
                    .map(|im| (0..4).map(|k| im.get(bx + k % 2, by + k / 2).g() as f64).sum::<f64>() / 4.0)
                    .collect();
                let m = vals.iter().sum::<f64>() / batches as f64;
                let v = vals.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (batches as f64 - 1.0);
                (m, (v / batches as f64).sqrt())
            })
            .collect()
    };
    let ratio = stats(TransmittanceMethod::Ratio);
    let mut worst: f64 = 0.0;
    for (name, method) in
        [("delta", TransmittanceMethod::Delta), ("residual ratio", TransmittanceMethod::ResidualRatio)]
    {
        let other = stats(method);
        for k in 0..16 {
            let ((a, sa), (b, sb)) = (ratio[k], other[k]);
            let z = (a - b) / ((sa * sa + sb * sb).sqrt() + 1e-9);
            worst = worst.max(z.abs());
            // 32 comparisons: 4 standard errors.
            assert!(z.abs() < 4.0, "block {k}: ratio {a:.5} +- {sa:.1e} vs {name} {b:.5} +- {sb:.1e}");
        }
    }
    assert!(ratio.iter().map(|r| r.0).sum::<f64>() > 0.0);
    println!("worst |z| = {worst:.2}");
}
