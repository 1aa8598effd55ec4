//! Renders with photon maps: `photon` (one map for the whole render) and
//! `ppm` (one map per sample index, shrinking radii, Knaus and Zwicker 2011).

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use super::emitters::Emitters;
use super::estimate::{Kernel, PhotonIntegrator};
use super::maps::{auto_radius, PhotonMaps};
use super::trace::photon_stream;
use super::{PhotonGather, PhotonSettings, PpmSettings, VolumeQuery};
use crate::film::SampleSums;
use crate::integrator::SingleIntegrator;
use crate::render::{render_sums_with, ProgressFn, RenderError, RenderOptions};
use crate::tracking::TransmittanceMethod;
use crate::world::Scene;

/// Pass index of the `photon` integrator's single map.
const PHOTON_PASS: u64 = u64::MAX;

/// `r_i / r_1` for pass `i` (1-based) of progressive photon mapping:
/// `r_{i+1}^d = r_i^d (i + alpha) / (i + 1)` (Knaus and Zwicker 2011, with
/// the kernel's dimension `d`), i.e.
/// `(Gamma(i + alpha) / (Gamma(1 + alpha) Gamma(i + 1)))^(1/d)`.
///
/// ```
/// use niebla::integrator::photon::ppm_radius_factor;
/// assert_eq!(ppm_radius_factor(1, 0.5, 2), 1.0);
/// // r_2^2 = r_1^2 (1 + 0.5) / 2
/// assert!((ppm_radius_factor(2, 0.5, 2) - 0.75f64.sqrt()).abs() < 1e-9);
/// ```
pub fn ppm_radius_factor(pass: u64, alpha: f64, dimension: u32) -> f64 {
    if pass <= 1 {
        return 1.0;
    }
    let i = pass as f64;
    let ln_ratio = ln_gamma(i + alpha) - ln_gamma(1.0 + alpha) - ln_gamma(i + 1.0);
    (ln_ratio / dimension as f64).exp()
}

/// `ln Gamma(x)` for `x > 0`, Lanczos approximation (g = 7, 9 terms;
/// relative error about 1e-15).
fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Gamma(x) Gamma(1 - x) = pi / sin(pi x).
        return (std::f64::consts::PI / (std::f64::consts::PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Run `f` on a pool of `threads` threads (or the current pool).
pub(super) fn with_pool<T: Send>(threads: Option<usize>, f: impl FnOnce() -> T + Send) -> Result<T, RenderError> {
    match threads {
        Some(threads) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|e| RenderError::ThreadPool { threads, message: e.to_string() })?;
            Ok(pool.install(f))
        }
        None => Ok(f()),
    }
}

fn single_of(settings: &PhotonSettings) -> SingleIntegrator {
    SingleIntegrator {
        step: settings.step,
        sampling: settings.sampling,
        transmittance: TransmittanceMethod::Analytic,
        volume_lights: None,
    }
}

/// Radius of a map from the settings or, when `None`, measured on it.
pub(super) fn radius_or_auto(radius: Option<f32>, measured: impl FnOnce() -> f32) -> f32 {
    radius.filter(|r| *r > 0.0 && r.is_finite()).unwrap_or_else(measured)
}

/// Render with the `photon` integrator: one photon map traced from `seed`
/// (the same for every pass of a progressive render), then `options.spp`
/// camera samples per pixel, returned as per-pixel fixed-point sums
/// (`film::SampleSums`). The image does not depend on the thread count.
pub fn render_photon(
    scene: &Scene,
    settings: &PhotonSettings,
    options: &RenderOptions,
    progress: ProgressFn,
    cancel: Option<&AtomicBool>,
) -> Result<SampleSums, RenderError> {
    with_pool(options.threads, || {
        let emitters = Emitters::new(scene);
        let mut maps = PhotonMaps::trace(scene, &emitters, settings, photon_stream(options.seed, PHOTON_PASS));
        let cap = scene.diagonal() / 16.0;
        let (volume_kernel, surface_kernel, beam_radius) = match settings.gather {
            PhotonGather::Nearest(k) => {
                let r_volume = radius_or_auto(settings.radius, || cap);
                let r_surface = radius_or_auto(settings.surface_radius, || cap);
                (
                    Kernel::Nearest { k: k.max(1) as usize, max_radius: r_volume },
                    Kernel::Nearest { k: k.max(1) as usize, max_radius: r_surface },
                    r_volume,
                )
            }
            PhotonGather::Radius => {
                let r_volume = radius_or_auto(settings.radius, || auto_radius(&maps.volume, true));
                let r_surface = radius_or_auto(settings.surface_radius, || auto_radius(&maps.surface, false));
                (Kernel::Radius(r_volume), Kernel::Radius(r_surface), r_volume)
            }
        };
        maps.prepare(settings, beam_radius);
        let integrator = PhotonIntegrator {
            maps: &maps,
            volume_kernel,
            surface_kernel,
            query: settings.query,
            step: settings.step,
            single: single_of(settings),
        };
        render_sums_with(scene, &integrator, &RenderOptions { threads: None, ..*options }, progress, cancel)
    })?
}

/// Render with `ppm`: every sample index `s` in
/// `first_sample .. first_sample + spp` is one pass with its own photon map
/// (stream `(seed, s)`) and radii `r_0 ppm_radius_factor(s + 1, alpha, d)`;
/// each pass renders one sample per pixel and the result is the per-pixel
/// fixed-point sum over the passes (`film::SampleSums`). A progressive render therefore continues the radius sequence
/// across its passes, and the image does not depend on the thread count.
pub fn render_ppm(
    scene: &Scene,
    settings: &PpmSettings,
    options: &RenderOptions,
    progress: ProgressFn,
    cancel: Option<&AtomicBool>,
) -> Result<SampleSums, RenderError> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let pixels = w as u64 * h as u64;
    let total = pixels * options.spp as u64;
    let done = AtomicU64::new(0);
    with_pool(options.threads, || {
        let mut sum = SampleSums::new(w, h);
        let photon = settings.photon;
        let alpha = settings.alpha.clamp(1e-3, 1.0) as f64;
        let volume_dimension = if photon.query == VolumeQuery::Beam { 2 } else { 3 };
        let emitters = Emitters::new(scene);
        for s in options.first_sample..options.first_sample + options.spp as u64 {
            if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                return Err(RenderError::Cancelled);
            }
            let mut maps = PhotonMaps::trace(scene, &emitters, &photon, photon_stream(options.seed, s));
            let r_volume = radius_or_auto(photon.radius, || auto_radius(&maps.volume, true))
                * ppm_radius_factor(s + 1, alpha, volume_dimension) as f32;
            let r_surface = radius_or_auto(photon.surface_radius, || auto_radius(&maps.surface, false))
                * ppm_radius_factor(s + 1, alpha, 2) as f32;
            let pass_settings = PhotonSettings { gather: PhotonGather::Radius, ..photon };
            maps.prepare(&pass_settings, r_volume);
            let integrator = PhotonIntegrator {
                maps: &maps,
                volume_kernel: Kernel::Radius(r_volume),
                surface_kernel: Kernel::Radius(r_surface),
                query: photon.query,
                step: photon.step,
                single: single_of(&photon),
            };
            let pass_options = RenderOptions { spp: 1, first_sample: s, threads: None, ..*options };
            let base = done.load(Ordering::Relaxed);
            let pass_progress = |d: u64, _: u64| progress(base + d, total);
            let pass = render_sums_with(scene, &integrator, &pass_options, &pass_progress, cancel)?;
            done.fetch_add(pixels, Ordering::Relaxed);
            sum.add(&pass);
        }
        Ok(sum)
    })?
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_factor_matches_the_recurrence() {
        for (alpha, d) in [(2.0 / 3.0, 3u32), (0.5, 2), (0.9, 3)] {
            let mut r_d = 1.0f64;
            for i in 1..2000u64 {
                let factor = ppm_radius_factor(i, alpha, d);
                assert!((factor.powi(d as i32) - r_d).abs() < 1e-10 * r_d.max(1e-3), "alpha {alpha} pass {i}");
                r_d *= (i as f64 + alpha) / (i as f64 + 1.0);
            }
        }
        // It goes to zero: r_i^d ~ i^(alpha - 1) / Gamma(1 + alpha).
        assert!(ppm_radius_factor(1_000_000, 2.0 / 3.0, 3) < 0.25);
    }

    #[test]
    fn ln_gamma_matches_factorials() {
        let mut f = 1.0f64;
        for n in 1..30u32 {
            assert!((ln_gamma(n as f64) - f.ln()).abs() < 1e-12 * f.ln().abs().max(1.0), "n {n}");
            f *= n as f64;
        }
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-13);
    }
}
