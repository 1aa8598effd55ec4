//! Pilot-allocated sampling: samples per pixel decided once, from an
//! independent pilot render, in proportion to `sqrt(v_p / c_p)`.
//!
//! **Passes.** Pass 1 renders `pilot_spp` samples of every pixel with the
//! independent sampler and the seed [`pilot_seed`]`(seed)`, a fixed hash
//! of the render's seed: a stream independent of the main render's. From
//! its sums come, per pixel, the per-sample relative variance `v_p`
//! (`mean_c s_c^2 / (m_c^2 + eps)`, `eps = (0.01 mean(pilot image))^2`, the
//! weights of `Image::relative_mse`) and the cost `c_p` of a sample
//! ([`super::COST_OFFSET`] plus the random dimensions drawn, counted, not
//! timed). Both are box-averaged over a `(2 radius + 1)^2` neighbourhood
//! ([`smooth`], 5x5 by default, [`DEFAULT_RADIUS`] has the measurements):
//! an 8- or 16-sample variance is heavy-tailed (one bright sample makes
//! it), and neighbours mostly share their noise. Pass 2
//! renders `n_p` samples of pixel `p`, the samples `0 .. n_p` of the
//! plain render's per-pixel stream with the render's sampler and seed
//! (independent or Owen-scrambled Sobol), with `n_p` from [`allocate`]:
//! proportional to `sqrt(v_p / c_p)`, clamped to `[floor, ceiling]` and
//! scaled so that the mean over the pixels is `spp` exactly. That is the
//! time-optimal allocation for the image's relative MSE
//! `mean_p v_p / n_p` at a fixed time `sum_p c_p n_p` (Cauchy-Schwarz;
//! `super::cost_allocation_bound` is its gain over a uniform one). The
//! pilot's samples are spent on the decision only: the work of a render
//! is `pilot_spp + spp` samples per pixel on average.
//!
//! **Unbiased for any sampler.** A pixel's value is the mean of its `n_p`
//! pass-2 samples only. `n_p` is a function of the pilot's numbers, which
//! are independent of pass 2's, so conditioned on `n_p = n` the value is
//! the mean of the first `n` samples of the plain stream, whose
//! expectation is the pixel's: every sample of the independent sampler,
//! and every point of an Owen-scrambled Sobol sequence (the first `n` of
//! them included, for any `n`), is uniformly distributed. Hence
//! `E[value] = sum_n P(n_p = n) mu = mu`. (Unlike `super::render_adaptive`,
//! where the later samples' count depends on the earlier samples of the
//! same stream, which Sobol points are not independent of.) Combining the
//! pilot's samples with the pass-2 mean would keep this only with weights
//! fixed in advance; weights that depend on `n_p` (say `k / (k + n_p)`)
//! correlate with the pilot's mean and are biased, so the pilot is
//! discarded.
//!
//! **Layers** follow the same rule (each channel the mean of the pass-2
//! samples); depth is the ratio of the depth and coverage means.
//!
//! Sums are exact integers per pixel and the allocation is computed
//! serially, so the image does not depend on the thread count.

use std::sync::atomic::AtomicBool;

use super::{layer_image, to_f64, write_maps_exr, Moments, PixelMaps};
use crate::aov::{segment_channels, AovImage, AovSet};
use crate::color::Rgb;
use crate::film::Image;
use crate::integrator::{IntegratorSettings, PreparedIntegrator};
use crate::render::RenderError;
use crate::sampling::{hash_u64, SamplerKind};
use crate::world::Scene;

/// Pilot samples per pixel by default: enough that the smoothed variance
/// sorts the pixels, few enough to cost little next to the render.
pub const DEFAULT_PILOT_SPP: u32 = 8;

/// Default radius of the box that smooths the pilot's variance and cost
/// (2: the 5x5 neighbourhood). Measured by `niebla bench adaptive
/// --pilot-spp` (time gain of the allocation judged by a 256-spp render's
/// variance and cost, 48x48 images, 8 pilot samples): radius 0, 1, 2, 3
/// gave 0.77, 1.07, 1.13, 1.12x on fire, 0.36, 0.99, 1.09, 1.10x on
/// spot_haze and 0.74, 1.12, 1.15, 1.15x on milk_cube; smoothing
/// `sqrt v` instead of `v` lost 0.02-0.18x; the ceiling (4 or 8 times the
/// mean) changed nothing.
pub const DEFAULT_RADIUS: u32 = 2;

/// Default least samples of a pixel, as a fraction of the mean (at least
/// one sample): guards pixels whose pilot saw no light or no noise.
pub const DEFAULT_FLOOR: f64 = 0.125;

/// Default most samples of a pixel, as a multiple of the mean.
pub const DEFAULT_CEILING: f64 = 8.0;

/// Mixed into the render's seed to give the pilot's.
const PILOT_STREAM: u64 = 0x9e6c_63d0_676a_9a99;

/// How a pilot-allocated render runs.
#[derive(Clone, Copy, Debug)]
pub struct PilotOptions {
    /// Mean samples per pixel of pass 2 (the pilot's come on top).
    pub spp: u32,
    /// Samples per pixel of the pilot (at least 2).
    pub pilot_spp: u32,
    /// Seed of pass 2 (that of a plain render); the pilot's is [`pilot_seed`].
    pub seed: u64,
    /// Sampler of pass 2 (the pilot's is the independent sampler).
    pub sampler: SamplerKind,
    /// Worker threads (`None`: all cores).
    pub threads: Option<usize>,
    /// Layers (`crate::aov`) to render with the image ([`AovSet::EMPTY`]: none).
    pub layers: AovSet,
    /// Radius of the smoothing box, in pixels (0: none).
    pub radius: u32,
    /// Least samples of a pixel as a fraction of `spp` (at least 1 sample).
    pub floor: f64,
    /// Most samples of a pixel as a multiple of `spp`.
    pub ceiling: f64,
}

impl PilotOptions {
    /// Options with the defaults above for `spp`, `seed` and `sampler`: all
    /// cores, no layers.
    pub fn new(spp: u32, seed: u64, sampler: SamplerKind) -> PilotOptions {
        PilotOptions {
            spp,
            pilot_spp: DEFAULT_PILOT_SPP,
            seed,
            sampler,
            threads: None,
            layers: AovSet::EMPTY,
            radius: DEFAULT_RADIUS,
            floor: DEFAULT_FLOOR,
            ceiling: DEFAULT_CEILING,
        }
    }

    /// The least and the most samples of a pixel: `max(1, round(floor spp))`
    /// and `max(least, round(ceiling spp))`.
    pub fn bounds(&self) -> (u64, u64) {
        let spp = f64::from(self.spp);
        let least = ((self.floor * spp).round() as u64).max(1);
        (least, ((self.ceiling * spp).round() as u64).max(least))
    }
}

/// The result of a pilot-allocated render.
#[derive(Clone, Debug)]
pub struct PilotImage {
    /// The unbiased image (each pixel the mean of its pass-2 samples).
    pub image: Image,
    /// Pass-2 samples of each pixel (mean `spp`).
    pub spp: Vec<u64>,
    /// Estimated variance of each pixel's value, per channel.
    pub variance: Vec<Rgb>,
    /// The layers asked for (`None` if none), each channel by the rule of the image.
    pub layers: Option<AovImage>,
    /// The pilot's per-pixel per-sample relative variance, smoothed.
    pub pilot_variance: Vec<f64>,
    /// The pilot's per-pixel cost of a sample, smoothed.
    pub pilot_cost: Vec<f64>,
    /// Random dimensions each pixel drew, pilot and pass 2 together.
    pub dimensions: Vec<u64>,
    /// Pilot samples per pixel.
    pub pilot_spp: u32,
}

/// The pilot's seed for a render seeded `seed`: a fixed hash, so that the
/// pilot's numbers are independent of the render's.
pub fn pilot_seed(seed: u64) -> u64 {
    hash_u64(seed ^ PILOT_STREAM)
}

/// Box mean of `values` (a `width` x `height` image, row-major) over the
/// `(2 radius + 1)^2` pixels around each pixel, clipped at the borders.
pub fn smooth(values: &[f64], width: usize, height: usize, radius: usize) -> Vec<f64> {
    if radius == 0 {
        return values.to_vec();
    }
    let mut out = vec![0.0; values.len()];
    for y in 0..height {
        for x in 0..width {
            let (mut sum, mut n) = (0.0, 0usize);
            for yy in y.saturating_sub(radius)..(y + radius + 1).min(height) {
                for xx in x.saturating_sub(radius)..(x + radius + 1).min(width) {
                    sum += values[yy * width + xx];
                    n += 1;
                }
            }
            out[y * width + x] = sum / n as f64;
        }
    }
    out
}

/// Samples per pixel proportional to `weights` (`sqrt(v_p / c_p)`),
/// clamped to `[least, most]`, summing to `mean * weights.len()` exactly
/// when that lies between `least` and `most` times the pixel count (else
/// every pixel takes the nearer bound). The real allocation
/// `clamp(lambda w_p, least, most)` with `lambda` found by bisection is
/// rounded down and the remainder goes one sample each to the pixels of
/// largest fractional part (ties: lower index). All-zero weights give
/// every pixel `mean`.
pub fn allocate(weights: &[f64], mean: u64, least: u64, most: u64) -> Vec<u64> {
    let pixels = weights.len();
    let (lo, hi) = (least as f64, most.max(least) as f64);
    let total = mean as f64 * pixels as f64;
    if pixels == 0 {
        return Vec::new();
    }
    if total <= lo * pixels as f64 {
        return vec![least; pixels];
    }
    if total >= hi * pixels as f64 {
        return vec![most.max(least); pixels];
    }
    let top = weights.iter().copied().filter(|w| w.is_finite()).fold(0.0, f64::max);
    if top <= 0.0 {
        return vec![mean; pixels];
    }
    let w = |p: usize| if weights[p].is_finite() { weights[p].max(0.0) } else { top };
    let real = |lambda: f64| (0..pixels).map(|p| (lambda * w(p)).clamp(lo, hi)).collect::<Vec<f64>>();
    // `sum(real(lambda))` grows with lambda from `lo n` (lambda = 0) to
    // `hi n` (lambda = hi / min positive weight); bisect in between.
    let (mut a, mut b) = (0.0f64, 1.0f64);
    while real(b).iter().sum::<f64>() < total {
        b *= 2.0;
    }
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if real(m).iter().sum::<f64>() < total {
            a = m;
        } else {
            b = m;
        }
    }
    let x = real(b);
    let mut n: Vec<u64> = x.iter().map(|v| v.floor() as u64).collect();
    let target = mean * pixels as u64;
    let mut order: Vec<usize> = (0..pixels).collect();
    order.sort_by(|&p, &q| (x[q] - x[q].floor()).total_cmp(&(x[p] - x[p].floor())).then(p.cmp(&q)));
    let mut sum: u64 = n.iter().sum();
    // Add to the largest fractions first; take from the smallest (the
    // bisection leaves `sum(x)` within rounding of the target).
    while sum < target {
        let before = sum;
        for &p in &order {
            if sum < target && n[p] < most.max(least) {
                n[p] += 1;
                sum += 1;
            }
        }
        if sum == before {
            break;
        }
    }
    while sum > target {
        let before = sum;
        for &p in order.iter().rev() {
            if sum > target && n[p] > least {
                n[p] -= 1;
                sum -= 1;
            }
        }
        if sum == before {
            break;
        }
    }
    n
}

/// The per-pixel per-sample relative variance and cost of a pilot, from
/// its sums (`7` per pixel: R, G, B, their squares, dimensions) of `k`
/// samples, before smoothing.
fn pilot_estimates(sums: &[i128], k: u64, pixels: usize) -> (Vec<f64>, Vec<f64>) {
    let moments: Vec<Moments> = (0..pixels)
        .map(|i| {
            let cell = &sums[i * 7..][..7];
            Moments {
                sum: [cell[0], cell[1], cell[2]],
                square: [cell[3], cell[4], cell[5]],
                n: k,
                dimensions: cell[6] as u64,
            }
        })
        .collect();
    let image_mean =
        moments.iter().map(|m| (0..3).map(|c| m.mean(c)).sum::<f64>() / 3.0).sum::<f64>() / pixels.max(1) as f64;
    let eps = (0.01 * image_mean).powi(2).max(f64::MIN_POSITIVE);
    let v = moments
        .iter()
        .map(|m| (0..3).map(|c| m.sample_variance(c) / (m.mean(c).powi(2) + eps)).sum::<f64>() / 3.0)
        .collect();
    let c = moments.iter().map(Moments::cost).collect();
    (v, c)
}

/// A rayon pool of `threads` threads (`None`: the global pool).
fn thread_pool(threads: Option<usize>) -> Result<Option<rayon::ThreadPool>, RenderError> {
    threads
        .map(|threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|e| RenderError::ThreadPool { threads, message: e.to_string() })
        })
        .transpose()
}

/// Runs a render on `pool` (the global pool when `None`).
type Runner<'a> = dyn Fn(&(dyn Fn() -> Result<Vec<i128>, RenderError> + Sync)) -> Result<Vec<i128>, RenderError> + 'a;

/// The pilot pass: its sums (7 per pixel), its smoothed per-sample
/// relative variance and cost, and the allocation they give.
#[allow(clippy::type_complexity)]
fn pilot_pass(
    prepared: &PreparedIntegrator,
    scene: &Scene,
    options: &PilotOptions,
    run: &Runner,
    cancel: Option<&AtomicBool>,
) -> Result<(Vec<u64>, Vec<i128>, Vec<f64>, Vec<f64>), RenderError> {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let pixels = w * h;
    let k = u64::from(options.pilot_spp.max(2));
    let all: Vec<u32> = (0..pixels as u32).collect();
    let seed = pilot_seed(options.seed);
    let ranges = vec![(0, k); pixels];
    let pilot = run(&|| {
        prepared.render_range_sums(scene, SamplerKind::Independent, seed, AovSet::EMPTY, &all, &ranges, cancel)
    })?;
    let (v, c) = pilot_estimates(&pilot, k, pixels);
    let radius = options.radius as usize;
    let (v, c) = (smooth(&v, w, h, radius), smooth(&c, w, h, radius));
    let (least, most) = options.bounds();
    let spp = allocate(&weights(&v, &c), u64::from(options.spp), least, most);
    Ok((spp, pilot, v, c))
}

/// The allocation weights `sqrt(v_p / c_p)` of per-pixel per-sample
/// relative variances `v` and costs `c` (0 where `c` is not positive).
pub fn weights(v: &[f64], c: &[f64]) -> Vec<f64> {
    v.iter().zip(c).map(|(&v, &c)| if c > 0.0 { (v.max(0.0) / c).sqrt() } else { 0.0 }).collect()
}

/// A pilot's decision: what [`pilot_allocation`] returns.
#[derive(Clone, Debug)]
pub struct PilotAllocation {
    /// Samples each pixel takes in pass 2.
    pub spp: Vec<u64>,
    /// The pilot's per-pixel per-sample relative variance, before smoothing.
    pub variance: Vec<f64>,
    /// The pilot's per-pixel cost of a sample, before smoothing.
    pub cost: Vec<f64>,
}

/// The pilot of a pilot-allocated render without pass 2: the samples of
/// each pixel [`render_pilot`] would take, and the pilot's per-sample
/// relative variance and cost per pixel before smoothing (what the
/// allocation is made of, to try other smoothings on).
pub fn pilot_allocation(
    scene: &Scene,
    settings: &IntegratorSettings,
    options: &PilotOptions,
    cancel: Option<&AtomicBool>,
) -> Result<PilotAllocation, RenderError> {
    let prepared = PreparedIntegrator::new(scene, settings);
    let pool = thread_pool(options.threads)?;
    let run = |render: &(dyn Fn() -> Result<Vec<i128>, RenderError> + Sync)| match &pool {
        Some(pool) => pool.install(render),
        None => render(),
    };
    let (spp, pilot, _, _) = pilot_pass(&prepared, scene, options, &run, cancel)?;
    let pixels = spp.len();
    let (variance, cost) = pilot_estimates(&pilot, u64::from(options.pilot_spp.max(2)), pixels);
    Ok(PilotAllocation { spp, variance, cost })
}

/// Render `scene` with samples allocated by an independent pilot (see the
/// module documentation). `photon`, `ppm` and `ppb` are not supported (no
/// per-pixel sample sums). `spp` and `pilot_spp` must be at least 1 and 2.
pub fn render_pilot(
    scene: &Scene,
    settings: &IntegratorSettings,
    options: &PilotOptions,
    cancel: Option<&AtomicBool>,
) -> Result<PilotImage, RenderError> {
    let prepared = PreparedIntegrator::new(scene, settings);
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let pixels = w * h;
    let k = u64::from(options.pilot_spp.max(2));
    let pool = thread_pool(options.threads)?;
    let run = |render: &(dyn Fn() -> Result<Vec<i128>, RenderError> + Sync)| match &pool {
        Some(pool) => pool.install(render),
        None => render(),
    };
    let (spp, pilot, v, c) = pilot_pass(&prepared, scene, options, &run, cancel)?;
    let all: Vec<u32> = (0..pixels as u32).collect();
    let ranges: Vec<(u64, u64)> = spp.iter().map(|&n| (0, n)).collect();
    let channels = segment_channels(options.layers);
    let stride = 7 + channels.len();
    let sums = run(&|| {
        prepared.render_range_sums(scene, options.sampler, options.seed, options.layers, &all, &ranges, cancel)
    })?;
    let mut value = vec![Rgb::ZERO; pixels];
    let mut variance = vec![Rgb::ZERO; pixels];
    let mut dimensions = vec![0u64; pixels];
    let mut means = vec![0f64; pixels * channels.len()];
    for i in 0..pixels {
        let cell = &sums[i * stride..][..stride];
        let n = spp[i];
        let m = Moments { sum: [cell[0], cell[1], cell[2]], square: [cell[3], cell[4], cell[5]], n, dimensions: 0 };
        let p = &pilot[i * 7..][..7];
        let pilot_m = Moments { sum: [p[0], p[1], p[2]], square: [p[3], p[4], p[5]], n: k, dimensions: 0 };
        for ch in 0..3 {
            value[i][ch] = m.mean(ch) as f32;
            // One sample has no variance of its own: the pilot's stands in.
            let s2 = if n >= 2 { m.sample_variance(ch) } else { pilot_m.sample_variance(ch) };
            variance[i][ch] = (s2 / n.max(1) as f64) as f32;
        }
        for (j, sum) in cell[7..].iter().enumerate() {
            means[i * channels.len() + j] = to_f64(*sum) / n.max(1) as f64;
        }
        dimensions[i] = cell[6] as u64 + p[6] as u64;
    }
    let layers = (!options.layers.is_empty()).then(|| layer_image(options.layers, &channels, w, h, &means, &variance));
    let mut image = Image::new(w as u32, h as u32);
    image.pixels = value;
    Ok(PilotImage { image, spp, variance, layers, pilot_variance: v, pilot_cost: c, dimensions, pilot_spp: k as u32 })
}

/// Writes a pilot-allocated render as an EXR: `R G B`, `spp.Z` (pass-2
/// samples of each pixel), `variance.R/G/B` and the layers, as
/// `super::write_adaptive_exr` does, with the header attributes
/// `nieblaAdaptiveRule = pilot`, `nieblaPilotSpp`, `nieblaSpp` (the mean
/// pass-2 samples per pixel) and `nieblaAovs`.
pub fn write_pilot_exr(result: &PilotImage, path: &std::path::Path) -> Result<(), crate::film::OutputError> {
    let mean = result.spp.iter().sum::<u64>() / result.spp.len().max(1) as u64;
    let attributes = [
        ("nieblaAdaptiveRule", "pilot".to_string()),
        ("nieblaPilotSpp", result.pilot_spp.to_string()),
        ("nieblaSpp", mean.to_string()),
    ];
    let maps = PixelMaps { image: &result.image, spp: &result.spp, variance: &result.variance };
    write_maps_exr(&maps, result.layers.as_ref(), &attributes, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn allocation_keeps_the_mean_and_the_bounds() {
        // Weights spanning four decades, mean 32, bounds [4, 256].
        let weights: Vec<f64> = (0..1000).map(|i| 10f64.powf(i as f64 / 250.0)).collect();
        let n = allocate(&weights, 32, 4, 256);
        assert_eq!(n.iter().sum::<u64>(), 32_000);
        assert!(n.iter().all(|&s| (4..=256).contains(&s)), "{:?}", (n.iter().min(), n.iter().max()));
        // Both bounds bind, and between them n follows the weights.
        assert_eq!(n[0], 4);
        assert_eq!(n[999], 256);
        assert!(n.windows(2).all(|p| p[0] <= p[1]));
        // Where neither bound binds, n / w is one constant (to rounding).
        let free: Vec<usize> = (0..1000).filter(|&p| n[p] > 8 && n[p] < 200).collect();
        let ratios: Vec<f64> = free.iter().map(|&p| n[p] as f64 / weights[p]).collect();
        let (lo, hi) = ratios.iter().fold((f64::MAX, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
        assert!(free.len() > 100 && hi / lo < 1.0 + 1.0 / 8.0, "{} free, ratios {lo}..{hi}", free.len());
    }

    #[test]
    fn allocation_of_sqrt_ratios_matches_the_proportional_split() {
        // v / c = (1, 4, 16, 64): sqrt = (1, 2, 4, 8), mean 15 -> 4, 8, 16, 32.
        assert_eq!(allocate(&[1.0, 2.0, 4.0, 8.0], 15, 1, 1000), vec![4, 8, 16, 32]);
        // Zero weights take the floor, the rest the remainder.
        assert_eq!(allocate(&[0.0, 0.0, 1.0, 1.0], 10, 2, 100), vec![2, 2, 18, 18]);
        // All zero: uniform. Infeasible bounds: the nearer bound.
        assert_eq!(allocate(&[0.0; 3], 7, 1, 100), vec![7; 3]);
        assert_eq!(allocate(&[1.0, 2.0], 3, 5, 10), vec![5, 5]);
        assert_eq!(allocate(&[1.0, 2.0], 30, 5, 10), vec![10, 10]);
        // A ceiling that binds hands its excess to the others.
        assert_eq!(allocate(&[1.0, 1.0, 100.0], 10, 1, 12), vec![9, 9, 12]);
    }

    #[test]
    fn smoothing_is_a_clipped_box_mean() {
        let v = [0.0, 0.0, 9.0, 0.0, 0.0, 0.0];
        // 3x2 image, radius 1: corner (0, 0) sees 4 pixels, (1, 0) sees 6.
        let s = smooth(&v, 3, 2, 1);
        assert_eq!(s, vec![0.0, 1.5, 2.25, 0.0, 1.5, 2.25]);
        assert_eq!(smooth(&v, 3, 2, 0), v.to_vec());
    }

    #[test]
    fn bounds_are_fractions_of_the_mean() {
        let mut o = PilotOptions::new(64, 1, SamplerKind::Independent);
        assert_eq!(o.bounds(), (8, 512));
        o.spp = 4;
        assert_eq!(o.bounds(), (1, 32));
        assert_ne!(pilot_seed(1), 1);
        assert_ne!(pilot_seed(1), pilot_seed(2));
    }
}
