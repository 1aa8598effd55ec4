//! BSDF sampling: energy of the dielectric, consistency of `sample`, `pdf` and
//! `eval`, slab and index-matched crossings, and a chi-square test of diffuse
//! sampling against `cos / pi`.

use niebla::bsdf::{fresnel_dielectric, Bsdf, BsdfSample, TransportMode};
use niebla::color::Rgb;
use niebla::math::{Frame, Vec2, Vec3, PI};
use niebla::sampling::{sample_uniform_sphere, PixelSampler};

/// A few normals, axis-aligned and tilted, to exercise the frames.
fn normals() -> [Vec3; 4] {
    [Vec3::Z, Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.3, -0.5, 0.81).normalize(), Vec3::new(-0.7, 0.1, -0.7).normalize()]
}

fn all_variants() -> [Bsdf; 7] {
    [
        Bsdf::Null,
        Bsdf::Diffuse { reflectance: Rgb::new(0.8, 0.5, 0.2) },
        Bsdf::Dielectric { eta: 1.5 },
        Bsdf::Dielectric { eta: 1.0 / 1.333 },
        Bsdf::Dielectric { eta: 1.0 },
        Bsdf::conductor_preset("gold").unwrap(),
        Bsdf::conductor_from_reflectance(Rgb::new(0.9, 0.9, 0.2)),
    ]
}

#[test]
fn dielectric_reflection_and_transmission_weights_sum_to_one() {
    // The lobe probabilities are the Fresnel weights R and T = 1 - R; the
    // weights f |cos| / pdf are 1 (reflection) and 1 / etap^2 (refraction),
    // so R * 1 + T * etap^2 * (1 / etap^2) = 1. f32 rounding: 1e-5.
    for eta in [1.5f32, 1.333, 1.0 / 1.5, 2.42] {
        let bsdf = Bsdf::Dielectric { eta };
        for i in 0..=180 {
            // Both sides: i < 90 outside, i > 90 inside (including past the critical angle).
            let theta = (i as f32 + 0.25).to_radians();
            let n = Vec3::Z;
            let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
            let r = fresnel_dielectric(wo.z, eta);
            let reflected = bsdf.sample(n, wo, 0.0, Vec2::ZERO);
            let transmitted = bsdf.sample(n, wo, 0.999_999_9, Vec2::ZERO).unwrap();
            let r_weight = reflected.map_or(0.0, |s| if s.is_transmission { 0.0 } else { s.pdf });
            if r == 1.0 {
                // Total internal reflection: every sample reflects with weight 1.
                assert!(!transmitted.is_transmission);
                assert!((transmitted.weight(n).r() - 1.0).abs() < 1e-5);
                continue;
            }
            assert!(transmitted.is_transmission, "eta {eta}, {i} deg");
            assert!((r_weight + transmitted.pdf - 1.0).abs() < 1e-6, "eta {eta}, {i} deg");
            let energy_r = reflected.map_or(0.0, |s| s.f.r() * s.wi.dot(n).abs());
            let energy_t = transmitted.f.r() * transmitted.wi.dot(n).abs() * transmitted.eta.powi(2);
            assert!((energy_r + energy_t - 1.0).abs() < 1e-5, "eta {eta}, {i} deg: {energy_r} + {energy_t}");
            // The refraction weight carries exactly the radiance factor 1 / etap^2.
            let expected_etap = if wo.z > 0.0 { eta } else { 1.0 / eta };
            assert!((transmitted.eta - expected_etap).abs() < 1e-6);
            assert!((transmitted.weight(n).r() * expected_etap.powi(2) - 1.0).abs() < 1e-5);
        }
    }
}

#[test]
fn dielectric_white_furnace_weight_is_one_without_eta_squared() {
    // Every sample's f |cos| / pdf times etap^2 is exactly 1 (to f32 rounding,
    // 1e-5), so its average over 100k random wo and lobe choices is 1.
    let mut sampler = PixelSampler::from_key(2024);
    let n_samples = 100_000;
    for eta in [1.5f32, 1.0 / 1.333] {
        let bsdf = Bsdf::Dielectric { eta };
        let mut sum = 0.0f64;
        for _ in 0..n_samples {
            let n = sample_uniform_sphere(sampler.next_2d());
            let wo = sample_uniform_sphere(sampler.next_2d());
            let Some(s) = bsdf.sample(n, wo, sampler.next_1d(), sampler.next_2d()) else { continue };
            let w = s.weight(n).g() * s.eta * s.eta;
            assert!((w - 1.0).abs() < 1e-5, "weight {w}");
            sum += w as f64;
        }
        assert!((sum / n_samples as f64 - 1.0).abs() < 1e-5);
    }
}

#[test]
fn dielectric_radiance_weight_averages_to_fresnel_prediction() {
    // At a fixed wo the expected weight is R + T / etap^2 and the reflected
    // fraction is R; both means are checked within 5 standard errors
    // estimated from the same 200k samples.
    let bsdf = Bsdf::Dielectric { eta: 1.5 };
    let n = Vec3::Z;
    let mut sampler = PixelSampler::from_key(7);
    for theta_deg in [10.0f32, 60.0, 85.0] {
        let theta = theta_deg.to_radians();
        let wo = Vec3::new(theta.sin(), 0.0, theta.cos());
        let r = fresnel_dielectric(wo.z, 1.5) as f64;
        let expected = r + (1.0 - r) / 2.25;
        let count = 200_000;
        let (mut sum, mut sum2, mut reflections) = (0.0f64, 0.0f64, 0usize);
        for _ in 0..count {
            let s = bsdf.sample(n, wo, sampler.next_1d(), sampler.next_2d()).unwrap();
            let w = s.weight(n).r() as f64;
            sum += w;
            sum2 += w * w;
            reflections += usize::from(!s.is_transmission);
        }
        let mean = sum / count as f64;
        let standard_error = ((sum2 / count as f64 - mean * mean).max(0.0) / count as f64).sqrt();
        assert!((mean - expected).abs() < 5.0 * standard_error + 1e-6, "{theta_deg} deg: {mean} vs {expected}");
        let fraction = reflections as f64 / count as f64;
        let fraction_error = (r * (1.0 - r) / count as f64).sqrt();
        assert!((fraction - r).abs() < 5.0 * fraction_error, "{theta_deg} deg: reflected {fraction} vs R {r}");
    }
}

#[test]
fn importance_transport_omits_the_radiance_factor() {
    let bsdf = Bsdf::Dielectric { eta: 1.5 };
    let wo = Vec3::new(0.6, 0.0, 0.8);
    let radiance = bsdf.sample_with_mode(Vec3::Z, wo, 0.9, Vec2::ZERO, TransportMode::Radiance).unwrap();
    let importance = bsdf.sample_with_mode(Vec3::Z, wo, 0.9, Vec2::ZERO, TransportMode::Importance).unwrap();
    assert_eq!(radiance.wi, importance.wi);
    assert!((importance.weight(Vec3::Z).r() - 1.0).abs() < 1e-6);
    assert!((radiance.weight(Vec3::Z).r() * 2.25 - 1.0).abs() < 1e-6);
}

#[test]
fn nonspecular_sample_pdf_matches_pdf_function() {
    // Exact equality: the sampler computes its pdf as `pdf` does.
    let mut sampler = PixelSampler::from_key(5);
    let bsdf = Bsdf::Diffuse { reflectance: Rgb::splat(0.7) };
    for n in normals() {
        for _ in 0..20_000 {
            let wo = sample_uniform_sphere(sampler.next_2d());
            let Some(s) = bsdf.sample(n, wo, sampler.next_1d(), sampler.next_2d()) else { continue };
            assert!(!s.is_specular && !s.is_transmission);
            assert_eq!(bsdf.pdf(n, wo, s.wi), s.pdf);
            assert_eq!(bsdf.eval(n, wo, s.wi), s.f);
            // Same side as wo, and the throughput is the reflectance.
            assert!(n.dot(wo) * n.dot(s.wi) > 0.0);
            assert!((s.weight(n).r() - 0.7).abs() < 1e-5);
        }
    }
}

#[test]
fn specular_samples_have_zero_pdf_and_are_flagged() {
    let mut sampler = PixelSampler::from_key(6);
    for bsdf in all_variants() {
        if !bsdf.is_specular() {
            continue;
        }
        for n in normals() {
            for _ in 0..2_000 {
                let wo = sample_uniform_sphere(sampler.next_2d());
                let Some(s) = bsdf.sample(n, wo, sampler.next_1d(), sampler.next_2d()) else { continue };
                assert!(s.is_specular, "{bsdf:?}");
                assert_eq!(bsdf.pdf(n, wo, s.wi), 0.0);
                assert!(bsdf.eval(n, wo, s.wi).is_black());
                assert!(s.pdf > 0.0 && s.pdf <= 1.0, "lobe probability {}", s.pdf);
                assert!((s.wi.length() - 1.0).abs() < 1e-5);
                // Reflection stays on the side of wo, transmission crosses.
                let crosses = n.dot(wo) * n.dot(s.wi) < 0.0;
                assert_eq!(crosses, s.is_transmission, "{bsdf:?}");
                assert!(s.weight(n).is_finite());
            }
        }
    }
    assert!(!Bsdf::Diffuse { reflectance: Rgb::ONE }.is_specular());
}

#[test]
fn every_variant_weight_stays_within_energy_bounds() {
    // No variant creates energy: f |cos| / pdf <= 1 per channel for reflectances
    // <= 1, except the refraction factor 1 / etap^2 > 1 when leaving a denser
    // medium, which is bounded by eta_max^2.
    let mut sampler = PixelSampler::from_key(8);
    for bsdf in all_variants() {
        for n in normals() {
            for _ in 0..2_000 {
                let wo = sample_uniform_sphere(sampler.next_2d());
                let Some(s) = bsdf.sample(n, wo, sampler.next_1d(), sampler.next_2d()) else { continue };
                let w = s.weight(n).max_channel() * s.eta * s.eta;
                assert!((0.0..=1.0 + 1e-5).contains(&w), "{bsdf:?}: {w}");
            }
        }
    }
}

#[test]
fn refracting_twice_through_a_flat_slab_returns_the_original_direction() {
    // A glass slab with parallel faces: the top face's outward normal is n,
    // the bottom face's is -n. Entering and leaving restores the direction,
    // and the radiance factors cancel (1 / 1.5^2 * 1.5^2), leaving T_in T_out
    // with T_in = T_out (Fresnel transmittance is reciprocal). f32: 1e-5.
    let eta = 1.5f32;
    let bsdf = Bsdf::Dielectric { eta };
    let mut sampler = PixelSampler::from_key(9);
    for n in normals() {
        for _ in 0..1_000 {
            // A ray travelling downward into the top face.
            let mut d = sample_uniform_sphere(sampler.next_2d());
            if d.dot(n) > 0.0 {
                d = -d;
            }
            if d.dot(n) > -1e-3 {
                continue;
            }
            let u_transmit = 0.999_999;
            let enter = bsdf.sample(n, -d, u_transmit, Vec2::ZERO).unwrap();
            assert!(enter.is_transmission && enter.eta == eta);
            // The path continues along enter.wi and meets the bottom face from inside.
            let exit = bsdf.sample(-n, -enter.wi, u_transmit, Vec2::ZERO).unwrap();
            assert!(exit.is_transmission && (exit.eta - 1.0 / eta).abs() < 1e-6);
            // It leaves travelling along the original direction. Each refraction
            // rounds at ~1e-7 and the exit cosine sqrt(1 - sin^2) amplifies that
            // by ~1 / cos toward grazing: error * cos <= 4e-7 observed over these
            // 4000 paths, so the bound is 1e-6 / cos.
            let tolerance = 1e-6 / d.dot(n).abs();
            assert!((exit.wi - d).length() < tolerance, "{:?} vs {:?}", exit.wi, d);
            // Throughput with lobe choice: (T_in / 1.5^2) / T_in * (T_out 1.5^2) / T_out = 1.
            let w = enter.weight(n).r() * exit.weight(-n).r();
            assert!((w - 1.0).abs() < 1e-5, "slab throughput {w}");
            // Radiance transmitted through both faces: f |cos| products to T_in T_out.
            let energy = enter.f.r() * enter.wi.dot(n).abs() * exit.f.r() * exit.wi.dot(n).abs();
            let expected = enter.pdf * exit.pdf;
            assert!((energy - expected).abs() < 1e-5, "slab transmittance {energy} vs T_in T_out {expected}");
            // Reciprocity T_in = T_out. The inside direction carries ~1e-7 rounding and
            // near grazing dT/d(direction) grows like 1 / cos, so the f32 error is about
            // 1e-6 / cos (7e-7 / cos observed at worst over these 4000 paths): 2e-6 / cos.
            let tolerance = 2e-6 / d.dot(n).abs();
            assert!((enter.pdf - exit.pdf).abs() < tolerance, "T_in {} vs T_out {}", enter.pdf, exit.pdf);
        }
    }
}

#[test]
fn index_matched_interfaces_pass_straight_through_with_weight_one() {
    let mut sampler = PixelSampler::from_key(10);
    for bsdf in [Bsdf::Dielectric { eta: 1.0 }, Bsdf::Null] {
        for n in normals() {
            for _ in 0..2_000 {
                let wo = sample_uniform_sphere(sampler.next_2d());
                let Some(s) = bsdf.sample(n, wo, sampler.next_1d(), sampler.next_2d()) else { continue };
                assert_eq!(s.wi, -wo);
                assert!(s.is_transmission && s.is_specular && s.eta == 1.0 && s.pdf == 1.0);
                assert!((s.weight(n) - Rgb::ONE).max_channel().abs() < 1e-6);
            }
        }
    }
    assert_eq!(fresnel_dielectric(0.5, 1.0), 0.0);
}

#[test]
fn conductor_weight_is_fresnel_reflectance_and_huge_k_is_a_mirror() {
    let gold = Bsdf::conductor_preset("gold").unwrap();
    let Bsdf::Conductor { eta, k } = gold else { unreachable!() };
    let mirror = Bsdf::Conductor { eta: Rgb::ONE, k: Rgb::splat(1e6) };
    for n in normals() {
        for side in [1.0f32, -1.0] {
            let wo = Frame::from_z(n * side).to_world(Vec3::new(0.6, 0.0, 0.8));
            let s = gold.sample(n, wo, 0.3, Vec2::ZERO).unwrap();
            assert!(!s.is_transmission && s.pdf == 1.0);
            assert!((s.wi.dot(n) - wo.dot(n)).abs() < 1e-5, "mirror angle");
            let expected = niebla::bsdf::fresnel_complex(0.8, eta, k);
            assert!((s.weight(n) - expected).max_channel().abs() < 1e-5);
            let m = mirror.sample(n, wo, 0.3, Vec2::ZERO).unwrap();
            assert!((m.weight(n) - Rgb::ONE).max_channel().abs() < 1e-5);
        }
    }
}

#[test]
fn null_and_diffuse_keep_their_eval_meaning() {
    let diffuse = Bsdf::Diffuse { reflectance: Rgb::splat(0.5) };
    let (n, wo) = (Vec3::Z, Vec3::new(0.0, 0.6, 0.8));
    assert_eq!(diffuse.eval(n, wo, Vec3::new(0.6, 0.0, 0.8)), Rgb::splat(0.5 / PI));
    assert_eq!(diffuse.eval(-n, wo, Vec3::new(0.6, 0.0, 0.8)), Rgb::splat(0.5 / PI));
    assert_eq!(diffuse.eval(n, wo, Vec3::new(0.6, 0.0, -0.8)), Rgb::ZERO);
    assert_eq!(Bsdf::Null.eval(n, wo, -wo), Rgb::ZERO);
    assert!(Bsdf::Null.is_null() && !diffuse.is_null() && !Bsdf::Dielectric { eta: 1.0 }.is_null());
}

/// Chi-square statistic of directions (in the local frame of the sampling
/// hemisphere) binned in (cos theta, phi) against `cos / pi`, whose mass on a
/// bin `[c0, c1] x [phi0, phi1]` is `(c1^2 - c0^2) / 2 * (phi1 - phi0) / pi`.
fn chi2_cosine(local: &[Vec3], cos_bins: usize, phi_bins: usize) -> f64 {
    let mut observed = vec![0f64; cos_bins * phi_bins];
    for d in local {
        let c = ((d.z * cos_bins as f32) as usize).min(cos_bins - 1);
        let phi = d.y.atan2(d.x).rem_euclid(2.0 * PI);
        let p = ((phi / (2.0 * PI) * phi_bins as f32) as usize).min(phi_bins - 1);
        observed[c * phi_bins + p] += 1.0;
    }
    let n = local.len() as f64;
    let mut chi2 = 0.0;
    for c in 0..cos_bins {
        let (c0, c1) = (c as f64 / cos_bins as f64, (c + 1) as f64 / cos_bins as f64);
        let mass = (c1 * c1 - c0 * c0) / 2.0 * (2.0 / phi_bins as f64);
        for p in 0..phi_bins {
            let expected = n * mass;
            chi2 += (observed[c * phi_bins + p] - expected).powi(2) / expected;
        }
    }
    chi2
}

#[test]
fn diffuse_sampling_matches_cosine_over_pi() {
    // 10 x 20 bins, 200k samples (smallest bin expects 100): chi-square with
    // 199 degrees of freedom has a 99.9% quantile of 266 (Wilson-Hilferty).
    let bsdf = Bsdf::Diffuse { reflectance: Rgb::ONE };
    let mut sampler = PixelSampler::from_key(11);
    for n in normals() {
        for side in [1.0f32, -1.0] {
            let frame = Frame::from_z(n * side);
            let wo = frame.to_world(Vec3::new(0.3, 0.4, 0.866).normalize());
            let local: Vec<Vec3> = (0..200_000)
                .map(|_| {
                    let s: BsdfSample = bsdf.sample(n, wo, sampler.next_1d(), sampler.next_2d()).unwrap();
                    frame.to_local(s.wi)
                })
                .collect();
            assert!(local.iter().all(|d| d.z > 0.0), "a sample left the side of wo");
            let chi2 = chi2_cosine(&local, 10, 20);
            assert!(chi2 < 266.0, "normal {n:?} side {side}: chi2 = {chi2}");
        }
    }
    // Power check: uniform hemisphere samples (the wrong pdf) fail by far.
    let uniform: Vec<Vec3> = (0..200_000)
        .map(|_| {
            let d = sample_uniform_sphere(sampler.next_2d());
            Vec3::new(d.x, d.y, d.z.abs())
        })
        .collect();
    assert!(chi2_cosine(&uniform, 10, 20) > 10.0 * 266.0);
}
