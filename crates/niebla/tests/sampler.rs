//! The Owen-scrambled Sobol sampler (`SamplerKind::Sobol`): its power-of-two
//! prefixes are (0, k, 2)-nets in every pair of dimensions, its numbers are
//! uniform and independent across pixels, a constant integrand renders its
//! exact value, and it integrates a smooth function with a much lower error
//! than independent numbers.

use std::path::Path;

use niebla::integrator::IntegratorSettings;
use niebla::render::{render, RenderOptions};
use niebla::sampling::{PixelSampler, SamplerKind};
use niebla::scene::{build_scene, parse_scene_str};

/// The first `n` samples of pixel `(x, y)`: dimensions 0 .. 6, drawn as
/// three 2D pairs.
fn points(seed: u64, x: u32, y: u32, n: u64) -> Vec<[f32; 6]> {
    (0..n)
        .map(|s| {
            let mut sampler = PixelSampler::for_pixel(SamplerKind::Sobol, seed, x, y, s);
            let (a, b, c) = (sampler.next_2d(), sampler.next_2d(), sampler.next_2d());
            [a.x, a.y, b.x, b.y, c.x, c.y]
        })
        .collect()
}

/// Whether every elementary interval `[i 2^-a, (i+1) 2^-a) x [j 2^-b, (j+1)
/// 2^-b)` with `a + b = k` holds exactly one of the `2^k` points.
fn is_net(points: &[(f32, f32)], k: u32) -> bool {
    assert_eq!(points.len(), 1 << k);
    (0..=k).all(|a| {
        let b = k - a;
        let mut seen = vec![false; 1 << k];
        points.iter().all(|&(u, v)| {
            let (i, j) = ((u * (1u32 << a) as f32) as usize, (v * (1u32 << b) as f32) as usize);
            !std::mem::replace(&mut seen[(i << b) | j], true)
        })
    })
}

#[test]
fn power_of_two_prefixes_are_nets_in_every_pair() {
    for seed in [0u64, 1, 12345] {
        for (x, y) in [(0u32, 0u32), (1, 0), (17, 3), (640, 480)] {
            let p = points(seed, x, y, 1 << 8);
            for k in 0..=8u32 {
                for pair in 0..3 {
                    let set: Vec<(f32, f32)> = p[..1 << k].iter().map(|q| (q[2 * pair], q[2 * pair + 1])).collect();
                    assert!(is_net(&set, k), "seed {seed}, pixel ({x}, {y}), pair {pair}: 2^{k} points are no net");
                }
            }
            // Also the aligned blocks a progressive render's passes add
            // ([2^k, 2^(k+1))) and a distributed chunk [64, 128).
            let set: Vec<(f32, f32)> = p[64..128].iter().map(|q| (q[0], q[1])).collect();
            assert!(is_net(&set, 6));
        }
    }
}

#[test]
fn one_d_draws_are_the_pairs_and_two_d_draws_align() {
    // next_1d six times gives the same numbers as next_2d three times, and
    // next_2d after an odd number of draws starts at the next pair.
    for s in 0..64 {
        let mut a = PixelSampler::for_pixel(SamplerKind::Sobol, 3, 5, 7, s);
        let ones: Vec<f32> = (0..6).map(|_| a.next_1d()).collect();
        assert_eq!(&ones[..], &points(3, 5, 7, 64)[s as usize][..]);
        let mut b = PixelSampler::for_pixel(SamplerKind::Sobol, 3, 5, 7, s);
        b.next_1d();
        let pair = b.next_2d();
        assert_eq!((pair.x, pair.y, b.dimension()), (ones[2], ones[3], 4));
    }
}

#[test]
fn numbers_are_uniform_and_pixels_uncorrelated() {
    // One pixel's 2^16 samples in dimensions 0 .. 6: mean 1/2 and variance
    // 1/12 per dimension (a scrambled net's mean errs far less than the
    // independent 5-sigma bound 5 sqrt(1/12/n) = 5.6e-3 used here), and
    // dimensions of different pairs uncorrelated (independent shuffles: the
    // correlation's standard error is 1/sqrt(n); 5 sigma bound).
    let n = 1u64 << 16;
    let p = points(9, 4, 2, n);
    for d in 0..6 {
        let mean = p.iter().map(|q| q[d] as f64).sum::<f64>() / n as f64;
        let var = p.iter().map(|q| (q[d] as f64 - mean).powi(2)).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 5.0 * (1.0 / 12.0 / n as f64).sqrt(), "dimension {d}: mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 5.0 * 2.7e-4 * (1e5 / n as f64).sqrt(), "dimension {d}: variance {var}");
    }
    for (d, e) in [(0, 2), (1, 3), (0, 5), (2, 4), (3, 5)] {
        let corr = p.iter().map(|q| (q[d] as f64 - 0.5) * (q[e] as f64 - 0.5)).sum::<f64>() / n as f64 * 12.0;
        assert!(corr.abs() < 5.0 / (n as f64).sqrt(), "dimensions {d}, {e}: correlation {corr}");
    }
    // Neighbouring pixels: their first draws at the same sample index are
    // uncorrelated (independent scrambles per pixel).
    let m = 100_000u32;
    for s in [0u64, 1, 37] {
        let mut sum_xy = 0.0;
        for i in 0..m {
            let a = PixelSampler::for_pixel(SamplerKind::Sobol, 1, i, 0, s).next_1d() as f64 - 0.5;
            let b = PixelSampler::for_pixel(SamplerKind::Sobol, 1, i + 1, 0, s).next_1d() as f64 - 0.5;
            sum_xy += a * b;
        }
        let corr = sum_xy / m as f64 * 12.0;
        assert!(corr.abs() < 5.0 / (m as f64).sqrt(), "sample {s}: neighbour correlation {corr}");
    }
}

/// RMSE over `pixels` pixels (independent replicates) of the `n`-sample
/// estimate of the integral of `f` over the pair of dimensions `pair`.
fn rmse(kind: SamplerKind, n: u64, pixels: u32, pair: usize, f: impl Fn(f64, f64) -> f64, exact: f64) -> f64 {
    let mut sum_sq = 0.0;
    for x in 0..pixels {
        let mut sum = 0.0;
        for s in 0..n {
            let mut sampler = PixelSampler::for_pixel(kind, 2, x, 1, s);
            for _ in 0..pair {
                sampler.next_2d();
            }
            let u = sampler.next_2d();
            sum += f(u.x as f64, u.y as f64);
        }
        sum_sq += (sum / n as f64 - exact).powi(2);
    }
    (sum_sq / pixels as f64).sqrt()
}

#[test]
fn smooth_integrands_converge_faster_than_with_independent_numbers() {
    // f(u, v) = exp(u) sin(pi v) integrates to 2 (e - 1) / pi. Independent
    // sampling's RMSE is sigma / sqrt(n); scrambled nets' falls as n^-1.5 for
    // smooth integrands (Owen 1997), so the ratio falls as 1/n. Measured over
    // 2000 replicates (which know each RMSE to a few percent): ratios 0.15,
    // 0.045 and 0.013 at 16, 64 and 256 samples, Sobol's RMSE falling by
    // 0.022 from 16 to 256 samples (16^-1.38). The bounds leave a factor 1.5.
    let f = |u: f64, v: f64| u.exp() * (std::f64::consts::PI * v).sin();
    let exact = 2.0 * (std::f64::consts::E - 1.0) / std::f64::consts::PI;
    for pair in [0usize, 2] {
        let mut sobol_rmse = Vec::new();
        for (n, bound) in [(16u64, 0.23), (64, 0.07), (256, 0.02)] {
            let sobol = rmse(SamplerKind::Sobol, n, 2000, pair, f, exact);
            let independent = rmse(SamplerKind::Independent, n, 2000, pair, f, exact);
            let ratio = sobol / independent;
            println!(
                "pair {pair}, {n} samples: RMSE sobol {sobol:.3e}, independent {independent:.3e}, ratio {ratio:.4}"
            );
            assert!(ratio < bound, "pair {pair}, {n} samples: RMSE ratio {ratio}");
            sobol_rmse.push(sobol);
        }
        let fall = sobol_rmse[2] / sobol_rmse[0];
        assert!(fall < 0.033, "pair {pair}: Sobol RMSE fell by only {fall} from 16 to 256 samples");
    }
    // A discontinuous integrand (the indicator of a disk, like an edge in a
    // pixel) converges as n^-0.75 with scrambled nets: at 256 samples the
    // RMSE ratio is of order 256^-0.25 = 1/4 (measured 0.26); bound 0.4.
    let disk = |u: f64, v: f64| if (u - 0.5).powi(2) + (v - 0.5).powi(2) < 0.16 { 1.0 } else { 0.0 };
    let exact = std::f64::consts::PI * 0.16;
    let ratio =
        rmse(SamplerKind::Sobol, 256, 1000, 0, disk, exact) / rmse(SamplerKind::Independent, 256, 1000, 0, disk, exact);
    println!("disk, 256 samples: RMSE ratio {ratio:.4}");
    assert!(ratio < 0.4, "disk: RMSE ratio {ratio}");
}

#[test]
fn constant_integrand_renders_its_exact_value() {
    // A white furnace: a non-absorbing grey sphere of fog in a uniform sky.
    // Every volpath sample (any number of scattering events, each drawing
    // distances, events and directions from the sampler) returns exactly the
    // sky's radiance, so each pixel's mean is 0.5 up to f32 rounding.
    let text = r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 0, 4], "target": [0, 0, 0], "width": 16, "height": 16},
        "render": {"integrator": {"type": "volpath"}},
        "media": {"fog": {"sigma_t": 3, "albedo": 1, "phase": {"type": "hg", "g": 0.4}}},
        "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "interior": "fog"}],
        "lights": [{"type": "constant", "radiance": 0.5}]}"#;
    let built = build_scene(&parse_scene_str(text, "furnace").unwrap(), "furnace", Path::new(".")).unwrap();
    assert!(matches!(built.settings.integrator, IntegratorSettings::VolPath { .. }));
    let options = RenderOptions { spp: 64, seed: 4, first_sample: 0, threads: None, sampler: SamplerKind::Sobol };
    let image = render(&built.scene, &built.settings.integrator, &options, &|_, _| {}, None).unwrap();
    for p in &image.pixels {
        for c in 0..3 {
            assert!((p[c] - 0.5).abs() < 1e-5, "pixel {p:?}");
        }
    }
}

#[test]
fn draws_do_not_depend_on_the_order_of_1d_and_2d_draws() {
    // The sampler computes pairs ahead and keeps them; whatever the mix of
    // 1D and 2D draws, each dimension gets the same number, and a rewind
    // gives the same numbers again.
    for (s, x, y) in [(0u64, 0u32, 0u32), (5, 3, 9), (1 << 33, 7, 7)] {
        let mut a = PixelSampler::for_pixel(SamplerKind::Sobol, 11, x, y, s);
        let straight: Vec<f32> = (0..40).map(|_| a.next_1d()).collect();
        let mut b = PixelSampler::for_pixel(SamplerKind::Sobol, 11, x, y, s);
        let mut mixed = [f32::NAN; 40];
        while b.dimension() < 38 {
            let d = b.dimension() as usize;
            match d % 3 {
                0 => {
                    let v = b.next_2d();
                    let e = b.dimension() as usize;
                    (mixed[e - 2], mixed[e - 1]) = (v.x, v.y);
                }
                _ => mixed[d] = b.next_1d(),
            }
        }
        for (d, v) in mixed.iter().enumerate().filter(|(_, v)| !v.is_nan()) {
            assert_eq!(*v, straight[d], "sample {s}, dimension {d}");
        }
        b.rewind_for_another_estimate(2);
        assert_eq!((b.next_1d(), b.next_1d()), (straight[2], straight[3]));
    }
}
