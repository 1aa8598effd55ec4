//! `niebla bench emission`: efficiency of `volpath` with and without light
//! sampling of emissive media (`volume_light_sampling`), and with light
//! sampling but without guiding surface vertices toward the emitters
//! (`emitter_guiding`), on a fire scene.
//!
//! Pixels are split by whether the camera ray through their center crosses
//! the box of an emissive medium ("fire": the emitter seen directly, or
//! through its box) or not ("lit": the floor and the smoke lit by it). For
//! each setting, renders at doubling sample counts give the relative MSE of
//! each class against a reference (two independent high-spp renders with
//! volume light sampling, whose own estimated error is subtracted); the figures are the relative MSE times the render time at
//! the largest count (lower is better; its ratio is the ratio of relative
//! MSEs at equal time) and the time to reach `--target`.

use std::path::PathBuf;

use clap::Args;
use niebla::film::Image;
use niebla::integrator::IntegratorSettings;
use niebla::medium::Medium;
use niebla::sampling::PixelSampler;
use niebla::scene::Scene;

use crate::bench::{time_to_reach, timed};
use crate::error::CliError;
use crate::flags::ThreadsFlag;

/// Options of `niebla bench emission`.
#[derive(Args, Debug)]
pub struct EmissionBenchArgs {
    /// Scene with an emissive medium (default: scenes/fire.json).
    pub scene: Option<PathBuf>,
    /// Image width used for the measurements (height keeps the aspect ratio).
    #[arg(long, default_value_t = 96)]
    pub width: u32,
    /// Samples per pixel of each half of the reference.
    #[arg(long, default_value_t = 2048)]
    pub reference_spp: u32,
    /// Largest sample count tried per setting.
    #[arg(long, default_value_t = 64)]
    pub max_spp: u32,
    /// Target relative MSE.
    #[arg(long, default_value_t = 1e-2)]
    pub target: f64,
    /// Path depth of `volpath`.
    #[arg(long, default_value_t = 64)]
    pub max_depth: u32,
    /// `--threads`: worker threads.
    #[command(flatten)]
    pub threads: ThreadsFlag,
}

/// Which pixels see an emissive medium's box: true for "fire" pixels.
fn fire_mask(scene: &Scene) -> Vec<bool> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut sampler = PixelSampler::from_key(1);
    let mut mask = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let _ = sampler.next_1d();
            let ray = scene.camera.generate_ray(x, y, niebla::math::Vec2::splat(0.5));
            let sees = scene.media.iter().any(|m| match m {
                Medium::Grid(g) => m.is_emissive() && g.clip(&ray, 0.0, f32::INFINITY).is_some(),
                Medium::Homogeneous(_) => false,
            });
            mask.push(sees);
        }
    }
    mask
}

/// Relative MSE (as [`Image::relative_mse`], `eps` from the whole
/// reference's mean) over the pixels where `mask` equals `class`.
fn masked_relative_mse(image: &Image, reference: &Image, mask: &[bool], class: bool) -> f64 {
    let mean = reference.mean().average() as f64;
    let eps = (0.01 * mean).powi(2).max(f64::MIN_POSITIVE);
    let (mut sum, mut n) = (0.0f64, 0usize);
    for ((a, b), &m) in image.pixels.iter().zip(&reference.pixels).zip(mask) {
        if m != class {
            continue;
        }
        for c in 0..3 {
            let (x, r) = (a[c] as f64, b[c] as f64);
            sum += (x - r).powi(2) / (r * r + eps);
        }
        n += 3;
    }
    sum / n.max(1) as f64
}

/// `volpath`'s default for emissive media: `(volume_light_sampling, emitter_guiding)`.
const DEFAULT: (bool, bool) = (true, true);

/// The settings measured, with their labels: the default, volume light
/// sampling without emitter guiding, and free flight alone.
const SETTINGS: [((bool, bool), &str); 3] =
    [(DEFAULT, "light sampling + guiding"), ((true, false), "light sampling"), ((false, false), "free flight")];

/// `niebla bench emission`.
pub fn run(args: &EmissionBenchArgs) -> Result<(), CliError> {
    let default = PathBuf::from("scenes/fire.json");
    let path = args.scene.clone().unwrap_or(default);
    let (built, _) = crate::load::load(Some(&path))?;
    let mut scene = built.scene;
    if args.width == 0 || args.width > 16384 {
        return Err(CliError::invalid_option("--width", "must be between 1 and 16384"));
    }
    if !scene.media.iter().any(Medium::is_emissive) {
        return Err(CliError::invalid_option("scene", "needs an emissive medium"));
    }
    let aspect = scene.camera.height as f64 / scene.camera.width as f64;
    scene.camera.width = args.width;
    scene.camera.height = ((args.width as f64 * aspect).round() as u32).max(1);
    let threads = args.threads.threads;
    let settings = |(volume_light_sampling, emitter_guiding): (bool, bool)| IntegratorSettings::VolPath {
        max_depth: args.max_depth,
        volume_light_sampling,
        emitter_guiding,
    };
    let mask = fire_mask(&scene);
    let fire_pixels = mask.iter().filter(|&&m| m).count();
    println!(
        "scene {}: {}x{}, {} pixels see an emitter's box, {} do not (floor, smoke)",
        path.display(),
        scene.camera.width,
        scene.camera.height,
        fire_pixels,
        mask.len() - fire_pixels
    );
    // The reference: two independent halves with volume light sampling (an
    // unbiased estimator, like the other setting; independent seeds, so the
    // settings measured share no noise with it). Its own relative MSE, a
    // quarter of the halves' (each half is twice as noisy as their mean, and
    // their difference adds both), is subtracted from the figures below.
    let (a, ta) = timed(&scene, &settings(DEFAULT), args.reference_spp, 900_001, threads)?;
    let (b, tb) = timed(&scene, &settings(DEFAULT), args.reference_spp, 900_002, threads)?;
    let pixels = a.pixels.iter().zip(&b.pixels).map(|(x, y)| (*x + *y) * 0.5).collect();
    let reference = Image { width: a.width, height: a.height, pixels };
    let noise = [masked_relative_mse(&a, &b, &mask, false) / 4.0, masked_relative_mse(&a, &b, &mask, true) / 4.0];
    println!(
        "reference: 2 x {} spp with volume light sampling ({ta:.1} s + {tb:.1} s); its own relative MSE: lit {:.2e}, fire {:.2e}",
        args.reference_spp, noise[0], noise[1],
    );
    let mut products = [[0.0f64; 2]; 3];
    for (k, (on, label)) in SETTINGS.into_iter().enumerate() {
        let mut lit_curve = Vec::new();
        let mut fire_curve = Vec::new();
        let mut spp = 1;
        while spp <= args.max_spp {
            let (image, seconds) = timed(&scene, &settings(on), spp, 7 + spp as u64, threads)?;
            let lit = (masked_relative_mse(&image, &reference, &mask, false) - noise[0]).max(0.0);
            let fire = (masked_relative_mse(&image, &reference, &mask, true) - noise[1]).max(0.0);
            println!("{label:<24} {spp:>5} spp {seconds:>8.3} s  rel MSE lit {lit:.3e}  fire {fire:.3e}");
            lit_curve.push((seconds, lit));
            fire_curve.push((seconds, fire));
            products[k] = [lit * seconds, fire * seconds];
            spp *= 2;
        }
        let reach = |c: &[(f64, f64)]| {
            time_to_reach(c, args.target).map_or_else(|| "not reached".to_string(), |t| format!("{t:.3} s"))
        };
        println!(
            "{label}: rel MSE x time at {} spp: lit {:.3e} s, fire {:.3e} s; time to {:.0e}: lit {}, fire {}",
            spp / 2,
            products[k][0],
            products[k][1],
            args.target,
            reach(&lit_curve),
            reach(&fire_curve)
        );
    }
    for (k, (_, label)) in SETTINGS.into_iter().enumerate().skip(1) {
        println!(
            "equal-time relative MSE, {label} / {}: lit {:.2}x, fire {:.2}x",
            SETTINGS[0].1,
            products[k][0] / products[0][0],
            products[k][1] / products[0][1]
        );
    }
    Ok(())
}
