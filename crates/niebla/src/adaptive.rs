//! Adaptive sampling without bias: pixels whose estimated relative error
//! is below a threshold stop receiving samples, and the image still has
//! the expectation of the plain render.
//!
//! **Schedule.** Passes end at the sample counts 1, 2, 3, 4, 6, 8, 12, 16,
//! 24, ... (powers of two and 1.5 times powers of two, [`schedule`]), then
//! at `spp`; sample indices continue across passes. A pixel takes a pass
//! only while it is active, and once stopped it stays so. (The render
//! loop joins the passes between two decisions into one, keeping the sums
//! of each pass a later decision separates apart: the sums, hence the
//! image, are those of the pass-by-pass loop, bit for bit.)
//!
//! **Layers.** With `AdaptiveOptions::layers`, every layer channel of a
//! pixel (split radiance, alpha, albedo, normal, depth and coverage sums)
//! takes the value rule of the beauty below, with the same decisions: it
//! is linear in the samples, so the argument holds channel by channel and
//! the split layers still add up to the beauty.
//!
//! **Decisions see the first half.** Before the pass that starts after
//! `t` samples, the decisions use the samples `< d` of every pixel, with
//! `d` the largest pass end `<= t / 2` ([`cutoff`]). A pixel `p` stopping
//! there gets the value
//! `(S_{<d} + M_{[d, t)} (N - d)) / N`: the sum of its decided samples plus
//! the mean of its samples `d .. t` standing in for every sample from `d`
//! to the schedule's `N`. Unbiased: write the value as `sum_j (n_j / N) Z_j`
//! over the schedule's passes, `Z_j` being pass `j`'s mean where `p` took
//! it and the stand-in mean where it did not. Whether `p` is active at pass
//! `j` depends on samples `< d(b_j) < b_j` only, independent of pass `j`'s
//! samples, so `E[Z_j 1{active}] = mu P(active)`; the event "`p` stops
//! before the pass starting at `t`" depends on samples `< d(t)` only, and
//! the stand-in samples `d(t) .. t` are independent of them, so
//! `E[M 1{stop at t}] = mu P(stop at t)`. Hence `E[Z_j] = mu` for every
//! `j`. (The same holds for any stopping rule that is a function of the
//! pixel's decided samples and of other pixels' samples, such as the cost
//! rule. Averaging all the samples a pixel took until it looked converged
//! would not be unbiased: a pixel whose first samples happened to be bright
//! shows a lower relative error and stops sooner.) The image mean used for
//! the error floor and a neighbour's decision use other pixels' samples,
//! which are independent of `p`'s.
//!
//! **Error measure.** From the decided samples of a pixel, per channel,
//! the per-sample relative variance `s^2 / (m^2 + eps)` with
//! `eps = (0.01 mean(image))^2` (the weights of `Image::relative_mse`),
//! averaged over the channels, times the factor by which stopping now
//! scales it, `(d + (N - d)^2 / (t - d)) / N^2`: the predicted relative
//! variance of the pixel's value if it stops now. A pixel is *converged*
//! when that is below `threshold^2`, at least [`MIN_DECIDED`] samples are
//! decided, and every channel with light rests on at least
//! [`MIN_EFFECTIVE`] effective samples (`S^2 / Q`, sum squared over sum of
//! squares: about the number of nonzero samples; a mean carried by one
//! rare bright sample has a sample variance that is not to be trusted). A
//! pixel stops when it and its eight neighbours are converged (stopped
//! neighbours count as converged): an isolated noisy pixel keeps its
//! neighbourhood sampling.
//!
//! **Cost rule** ([`StopRule::Cost`]). The threshold rule equalises the
//! pixels' errors; the image's relative MSE `mean_p v_p / n_p` for a given
//! time `sum_p c_p n_p` (`c_p` the cost of a sample of pixel `p`) is least
//! at `n_p ~ sqrt(v_p / c_p)` (Cauchy-Schwarz), where every pixel's
//! marginal error reduction per unit cost, `v_p / (c_p n_p^2)`, is the
//! same. So a pixel is converged when the relative variance the pass to
//! the next decision `t'` would remove, `v (f(d, t) - f(d', t'))` (`f` the
//! factor above, `d'` the cutoff at `t'`, `f = 1 / N` at `t' = N`), is
//! below `mu c_p (t' - t)`, the pass's cost at the common level
//! `mu = threshold^2 / (N c_mean)`; `c_mean` is the mean cost of the
//! image's decided samples. In the continuous limit a pixel stops after
//! `n` samples once its relative error is below
//! `threshold sqrt((n / N) (c_p / c_mean))`: a pixel of mean cost that
//! takes every sample is held to the threshold, a pixel that stops earlier
//! or costs less per sample to a lower error, a costlier one to a higher.
//! The cost of a sample is counted, not timed: [`COST_OFFSET`] plus the
//! random dimensions it drew (each tracker step, scattering vertex and
//! light sample draws some), a deterministic function of its numbers;
//! `c_p` is the mean over the pixel's decided samples. The decision still
//! depends on the pixel's samples `< d` only (its `v`, `c_p` and its share
//! of `c_mean`) and on other pixels' samples, so the argument above holds
//! unchanged.
//!
//! The argument needs the passes of a pixel to be independent, so adaptive
//! renders use the independent sampler: Owen-scrambled Sobol points of a
//! later pass fill the strata the earlier ones left, so its mean is not
//! independent of them (measured: with Sobol the adaptive image mean came
//! out 4.5 standard errors low on the test scene of `tests/adaptive.rs`).
//!
//! Decisions are made serially from exact per-pixel sums, so the image does
//! not depend on the thread count.

pub mod pilot;

use std::collections::VecDeque;
use std::sync::atomic::AtomicBool;

use crate::aov::{segment_channels, Aov, AovChannel, AovImage, AovLayer, AovSet};
use crate::color::Rgb;
use crate::film::{Image, FRACTION_BITS};
use crate::integrator::{IntegratorSettings, PreparedIntegrator};
use crate::render::RenderError;
use crate::world::Scene;

/// Decided samples a pixel needs before it may stop (so the earliest stop
/// is after 16 samples).
pub const MIN_DECIDED: u64 = 8;

/// Effective samples (`S^2 / Q` of a channel's decided samples) every
/// channel with light needs before its pixel may stop (below
/// [`MIN_DECIDED`], so that equal samples pass despite rounding).
pub const MIN_EFFECTIVE: f64 = 6.0;

/// Cost of a sample in units of one random dimension drawn, added to the
/// dimensions a sample drew to give its cost proxy: the work of a sample
/// that draws none (camera ray, first intersection, film). Counted, not
/// timed, so that decisions and images do not depend on the machine or
/// the thread count. `niebla bench adaptive` prints the least-squares fit
/// of measured time per sample against dimensions per sample: on fire,
/// spot_haze and milk_cube the time is close to proportional (r = 0.93 to
/// 0.999, intercepts between -1.3 and +1.5 dimensions against 2 to 50
/// dimensions per sample), so the offset is small; 1 keeps the cost of a
/// sample positive.
pub const COST_OFFSET: f64 = 1.0;

/// When a pixel of an adaptive render stops (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StopRule {
    /// Once the predicted relative standard error of its value is below
    /// the threshold (equal error per pixel, whatever a sample costs).
    #[default]
    Error,
    /// Once the predicted relative variance a further pass would remove,
    /// per unit of its cost, is below the common level
    /// `threshold^2 / (N c_mean)`: the allocation that minimises the image's
    /// relative MSE for the time spent (`n_p ~ sqrt(v_p / c_p)`).
    Cost,
}

impl StopRule {
    /// The rule's name (`error`, `cost`), as written in the EXR header.
    pub fn name(self) -> &'static str {
        match self {
            StopRule::Error => "error",
            StopRule::Cost => "cost",
        }
    }
}

/// The result of an adaptive render.
#[derive(Clone, Debug)]
pub struct AdaptiveImage {
    /// The unbiased image.
    pub image: Image,
    /// Samples each pixel took.
    pub spp: Vec<u64>,
    /// Estimated variance of each pixel's value, per channel.
    pub variance: Vec<Rgb>,
    /// Samples of the schedule (what every pixel of a plain render takes).
    pub total_spp: u64,
    /// The layers asked for (`AdaptiveOptions::layers`; `None` if none):
    /// each channel a pixel's value by the rule of the image, the variance
    /// layer [`AdaptiveImage::variance`].
    pub layers: Option<AovImage>,
    /// The rule the pixels stopped by.
    pub rule: StopRule,
    /// Random dimensions each pixel's samples drew (the cost proxy of
    /// [`StopRule::Cost`]; about proportional to the time they took).
    pub dimensions: Vec<u64>,
}

/// How an adaptive render runs.
#[derive(Clone, Copy, Debug)]
pub struct AdaptiveOptions {
    /// Samples per pixel of the schedule (the most a pixel takes).
    pub spp: u32,
    /// Relative standard error of a pixel's value below which it stops, in (0, 1).
    pub threshold: f32,
    /// Sampler seed.
    pub seed: u64,
    /// Worker threads (`None`: all cores).
    pub threads: Option<usize>,
    /// Layers (`crate::aov`) to render with the image ([`AovSet::EMPTY`]: none).
    pub layers: AovSet,
    /// When a pixel stops.
    pub rule: StopRule,
}

/// The sample counts at which the passes of an adaptive render of `spp`
/// samples per pixel end: 1, 2, 3, 4, 6, 8, 12, ... below `spp`, then `spp`
/// (empty for 0).
pub fn schedule(spp: u64) -> Vec<u64> {
    let mut ends = Vec::new();
    let mut p = 1u64;
    while p < spp {
        ends.push(p);
        if p >= 2 && p + p / 2 < spp {
            ends.push(p + p / 2);
        }
        p *= 2;
    }
    if spp > 0 {
        ends.push(spp);
    }
    ends
}

/// The decision cutoff before the pass starting after `t` samples: the
/// largest pass end of `ends` (a [`schedule`]) that is at most `t / 2` (0 if none).
pub fn cutoff(ends: &[u64], t: u64) -> u64 {
    ends.iter().copied().filter(|&b| 2 * b <= t).max().unwrap_or(0)
}

/// Sums and sums of squares (fixed point, as `film::SampleSums`) of `n`
/// samples of one pixel.
#[derive(Clone, Copy, Default, Debug)]
struct Moments {
    sum: [i128; 3],
    square: [i128; 3],
    n: u64,
    /// Random dimensions the `n` samples drew.
    dimensions: u64,
}

impl Moments {
    fn add(&mut self, other: &Moments) {
        for c in 0..3 {
            self.sum[c] += other.sum[c];
            self.square[c] += other.square[c];
        }
        self.n += other.n;
        self.dimensions += other.dimensions;
    }

    /// Cost per sample ([`COST_OFFSET`] plus the mean dimensions drawn;
    /// [`COST_OFFSET`] without samples).
    fn cost(&self) -> f64 {
        COST_OFFSET + if self.n == 0 { 0.0 } else { self.dimensions as f64 / self.n as f64 }
    }

    /// Mean of channel `c` (0 without samples).
    fn mean(&self, c: usize) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            to_f64(self.sum[c]) / self.n as f64
        }
    }

    /// Unbiased sample variance of channel `c` (0 below two samples).
    fn sample_variance(&self, c: usize) -> f64 {
        if self.n < 2 {
            return 0.0;
        }
        let n = self.n as f64;
        let m = self.mean(c);
        ((to_f64(self.square[c]) - n * m * m) / (n - 1.0)).max(0.0)
    }

    /// `S^2 / Q` of channel `c`: the number of equal samples that would
    /// give these sums (`None` for a channel without light).
    fn effective_samples(&self, c: usize) -> Option<f64> {
        let (s, q) = (to_f64(self.sum[c]), to_f64(self.square[c]));
        (q > 0.0).then(|| s * s / q)
    }
}

fn to_f64(v: i128) -> f64 {
    v as f64 * (2f64).powi(-FRACTION_BITS)
}

/// The factor by which a pixel's per-sample variance becomes the variance
/// of its value when it stops with `d` decided samples and `t` taken, of a
/// schedule of `n` samples: `(d + (n - d)^2 / (t - d)) / n^2`.
pub fn stop_variance_factor(d: u64, t: u64, n: u64) -> f64 {
    let (d, t, n) = (d as f64, t as f64, n as f64);
    (d + (n - d) * (n - d) / (t - d)) / (n * n)
}

/// The value and variance of a pixel with `decided` samples `< d` and
/// `standin` samples `d .. t` whose standin mean stands in for samples
/// `d .. n` (`standin` empty: the pixel took all `n` samples, all in `decided`).
fn pixel_value(decided: &Moments, standin: &Moments, n: u64) -> (Rgb, Rgb) {
    let mut all = *decided;
    all.add(standin);
    let nf = n.max(1) as f64;
    let (mut value, mut variance) = (Rgb::ZERO, Rgb::ZERO);
    for c in 0..3 {
        let s2 = all.sample_variance(c);
        if standin.n == 0 {
            value[c] = all.mean(c) as f32;
            variance[c] = (s2 / all.n.max(1) as f64) as f32;
        } else {
            let v = (to_f64(decided.sum[c]) + standin.mean(c) * (n - decided.n) as f64) / nf;
            value[c] = v as f32;
            variance[c] = (s2 * stop_variance_factor(decided.n, all.n, n)) as f32;
        }
    }
    (value, variance)
}

/// Render `scene` adaptively (see the module documentation). `threshold`
/// must lie in (0, 1); `photon`, `ppm` and `ppb` are not supported (no per-pixel
/// sample sums of their own). `progress` is told the samples taken after
/// each pass, out of `spp` per pixel.
///
/// Passes run only between decisions (the first one covers samples
/// `0 .. 16`, before which no pixel can stop); each pass renders only the
/// pixels still active, in chunks of pixels on one thread pool, and keeps
/// the sums of every sample range a later decision needs apart.
pub fn render_adaptive(
    scene: &Scene,
    settings: &IntegratorSettings,
    options: &AdaptiveOptions,
    progress: crate::render::ProgressFn,
    cancel: Option<&AtomicBool>,
) -> Result<AdaptiveImage, RenderError> {
    let prepared = PreparedIntegrator::new(scene, settings);
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let pixels = w * h;
    let total = u64::from(options.spp);
    let ends = schedule(total);
    let threshold2 = (options.threshold as f64).powi(2);
    let channels = segment_channels(options.layers);
    let k = channels.len();
    let stride = 7 + k;
    // Sample counts at which pixels may stop, and the boundaries of the
    // sample ranges whose sums stay apart (every cutoff of a decision is
    // one of them).
    let decisions: Vec<u64> = ends.iter().copied().filter(|&t| t < total && cutoff(&ends, t) >= MIN_DECIDED).collect();
    let bounds: Vec<u64> = ends.iter().copied().filter(|&b| b >= MIN_DECIDED || b == total).collect();
    let pool = match options.threads {
        Some(threads) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|e| RenderError::ThreadPool { threads, message: e.to_string() })?,
        ),
        None => None,
    };
    let mut active = vec![true; pixels];
    let mut decided = vec![Moments::default(); pixels];
    let mut decided_layers = vec![0i128; pixels * k];
    let mut taken = vec![0u64; pixels];
    let mut drawn = vec![0u64; pixels];
    let mut value = vec![Rgb::ZERO; pixels];
    let mut variance = vec![Rgb::ZERO; pixels];
    let mut layer_means = vec![0f64; pixels * k];
    // Sample ranges after the cutoff, per pixel (zero where inactive).
    let mut pending: VecDeque<Segment> = VecDeque::new();
    let mut converged = vec![false; pixels];
    let mut t = 0u64;
    for &end in decisions.iter().chain(std::iter::once(&total)) {
        if t > 0 {
            let d = cutoff(&ends, t);
            while pending.front().is_some_and(|s| s.start < d) {
                let segment = pending.pop_front().expect("checked");
                for i in (0..pixels).filter(|&i| active[i]) {
                    decided[i].add(&segment.moments[i]);
                    for j in 0..k {
                        decided_layers[i * k + j] += segment.layers[i * k + j];
                    }
                }
            }
            let image_mean = (0..pixels)
                .map(|i| {
                    if active[i] {
                        (0..3).map(|c| decided[i].mean(c)).sum::<f64>() / 3.0
                    } else {
                        value[i].average() as f64
                    }
                })
                .sum::<f64>()
                / pixels.max(1) as f64;
            let eps = (0.01 * image_mean).powi(2).max(f64::MIN_POSITIVE);
            let factor = stop_variance_factor(d, t, total);
            // The cost rule: the relative variance the pass to `end` would
            // remove (stopping there instead of now), against its cost at the
            // level `threshold^2 / (N c_mean)`.
            let removed = factor - stop_variance_factor(cutoff(&ends, end), end, total);
            let (dimensions, decided_samples) =
                decided.iter().fold((0u64, 0u64), |(a, b), m| (a + m.dimensions, b + m.n));
            let mean_cost = COST_OFFSET + dimensions as f64 / decided_samples.max(1) as f64;
            let level = threshold2 / (total as f64 * mean_cost) * (end - t) as f64;
            for i in 0..pixels {
                converged[i] = !active[i] || {
                    let m = &decided[i];
                    let relative: f64 =
                        (0..3).map(|c| m.sample_variance(c) / (m.mean(c).powi(2) + eps)).sum::<f64>() / 3.0;
                    let trusted = (0..3).all(|c| m.effective_samples(c).is_none_or(|e| e >= MIN_EFFECTIVE));
                    trusted
                        && match options.rule {
                            StopRule::Error => relative * factor < threshold2,
                            StopRule::Cost => relative * removed < level * m.cost(),
                        }
                };
            }
            for y in 0..h {
                for x in 0..w {
                    let i = y * w + x;
                    if !active[i] {
                        continue;
                    }
                    let mut all = true;
                    for yy in y.saturating_sub(1)..(y + 2).min(h) {
                        for xx in x.saturating_sub(1)..(x + 2).min(w) {
                            all &= converged[yy * w + xx];
                        }
                    }
                    if all {
                        let mut standin = Moments::default();
                        let mut standin_layers = vec![0i128; k];
                        for segment in &pending {
                            standin.add(&segment.moments[i]);
                            for (sum, v) in standin_layers.iter_mut().zip(&segment.layers[i * k..(i + 1) * k]) {
                                *sum += v;
                            }
                        }
                        (value[i], variance[i]) = pixel_value(&decided[i], &standin, total);
                        for j in 0..k {
                            layer_means[i * k + j] = stopped_mean(
                                decided_layers[i * k + j],
                                decided[i].n,
                                standin_layers[j],
                                standin.n,
                                total,
                            );
                        }
                        active[i] = false;
                    }
                }
            }
        }
        let list: Vec<u32> = (0..pixels).filter(|&i| active[i]).map(|i| i as u32).collect();
        if list.is_empty() {
            break;
        }
        let mut segments = Vec::new();
        let mut start = t;
        for &b in bounds.iter().filter(|&&b| b > t && b <= end) {
            segments.push((start, b));
            start = b;
        }
        let render = || prepared.render_segment_sums(scene, options.seed, options.layers, &list, &segments, cancel);
        let sums = match &pool {
            Some(pool) => pool.install(render),
            None => render(),
        }?;
        for (g, &(start, b)) in segments.iter().enumerate() {
            let size = b - start;
            let mut segment = Segment { start, moments: vec![Moments::default(); pixels], layers: vec![0; pixels * k] };
            for (j, &i) in list.iter().enumerate() {
                let i = i as usize;
                let cell = &sums[(j * segments.len() + g) * stride..][..stride];
                segment.moments[i] = Moments {
                    sum: [cell[0], cell[1], cell[2]],
                    square: [cell[3], cell[4], cell[5]],
                    n: size,
                    dimensions: cell[6] as u64,
                };
                segment.layers[i * k..(i + 1) * k].copy_from_slice(&cell[7..]);
                taken[i] += size;
                drawn[i] += cell[6] as u64;
            }
            pending.push_back(segment);
        }
        progress(taken.iter().sum(), pixels as u64 * total);
        t = end;
    }
    // Pixels that took every sample: the mean of all of them.
    for i in (0..pixels).filter(|&i| active[i]) {
        let mut all = decided[i];
        let mut all_layers = decided_layers[i * k..(i + 1) * k].to_vec();
        for segment in &pending {
            all.add(&segment.moments[i]);
            for (sum, v) in all_layers.iter_mut().zip(&segment.layers[i * k..(i + 1) * k]) {
                *sum += v;
            }
        }
        (value[i], variance[i]) = pixel_value(&all, &Moments::default(), total);
        for j in 0..k {
            layer_means[i * k + j] = stopped_mean(all_layers[j], all.n, 0, 0, total);
        }
    }
    let layers =
        (!options.layers.is_empty()).then(|| layer_image(options.layers, &channels, w, h, &layer_means, &variance));
    let mut image = Image::new(w as u32, h as u32);
    image.pixels = value;
    Ok(AdaptiveImage { image, spp: taken, variance, total_spp: total, layers, rule: options.rule, dimensions: drawn })
}

/// The per-pixel sums of one range of sample indices.
struct Segment {
    /// First sample index of the range.
    start: u64,
    /// Beauty sums per pixel.
    moments: Vec<Moments>,
    /// Layer channel sums, `layers[pixel * k + j]`.
    layers: Vec<i128>,
}

/// The value of one channel of a pixel, from the fixed-point sum `decided`
/// of its `d` decided samples and `standin` of `m` samples standing in for
/// the samples `d .. n` (`m` = 0: `decided` holds all `n` samples):
/// `(S_decided + S_standin (n - d) / m) / n`, the rule of the image.
fn stopped_mean(decided: i128, d: u64, standin: i128, m: u64, n: u64) -> f64 {
    let n_f = n.max(1) as f64;
    if m == 0 {
        to_f64(decided) / n_f
    } else {
        (to_f64(decided) + to_f64(standin) / m as f64 * (n - d) as f64) / n_f
    }
}

/// The layer images of an adaptive render from each pixel's channel values
/// `means[pixel * k + j]` (channel `channels[j]`) and the variance of its
/// value (the variance layer): as `AovSums::layers` makes them from sums,
/// with depth the ratio of the depth and coverage values.
fn layer_image(set: AovSet, channels: &[AovChannel], w: usize, h: usize, means: &[f64], variance: &[Rgb]) -> AovImage {
    let k = channels.len();
    let pixels = w * h;
    let get = |i: usize, ch: AovChannel| channels.iter().position(|&c| c == ch).map_or(0.0, |j| means[i * k + j]);
    let mut layers = Vec::new();
    for aov in set.iter() {
        let components = match aov {
            Aov::Alpha | Aov::Depth => 1,
            _ => 3,
        };
        let mut data = Vec::with_capacity(pixels * components);
        for (i, pixel_variance) in variance.iter().enumerate().take(pixels) {
            match aov {
                Aov::Alpha => data.push(get(i, AovChannel::Alpha) as f32),
                Aov::Direct | Aov::Indirect | Aov::Emission | Aov::Surface => {
                    let l = aov as usize - Aov::Direct as usize;
                    data.extend((0..3).map(|c| get(i, AovChannel::Split(l, c)) as f32));
                }
                Aov::Albedo => data.extend((0..3).map(|c| get(i, AovChannel::Albedo(c)) as f32)),
                Aov::Normal => data.extend((0..3).map(|c| get(i, AovChannel::Normal(c)) as f32)),
                Aov::Depth => {
                    let hits = get(i, AovChannel::Coverage);
                    data.push(if hits > 0.0 { (get(i, AovChannel::DepthSum) / hits) as f32 } else { 0.0 });
                }
                Aov::Variance => data.extend(pixel_variance.0),
            }
        }
        layers.push(AovLayer { aov, components, data });
    }
    AovImage { width: w as u32, height: h as u32, layers }
}

/// Writes an adaptive render as an EXR: the image (`R`, `G`, `B`), the
/// samples each pixel took (`spp.Z`), the variance of each pixel's value
/// (`variance.R/G/B`) and the layers rendered (channels named as those of
/// `niebla render --aovs`), with the threshold, the schedule's spp and the
/// layers (`nieblaAovs`, so `aov::read_aov_exr` reads them) and the stop
/// rule (`nieblaAdaptiveRule`: `error` or `cost`) as header attributes.
/// Not a checkpoint: an adaptive render cannot be resumed.
pub fn write_adaptive_exr(
    result: &AdaptiveImage,
    threshold: f32,
    path: &std::path::Path,
) -> Result<(), crate::film::OutputError> {
    let attributes = [
        ("nieblaAdaptiveThreshold", threshold.to_string()),
        ("nieblaAdaptiveRule", result.rule.name().to_string()),
        ("nieblaSpp", result.total_spp.to_string()),
    ];
    let maps = PixelMaps { image: &result.image, spp: &result.spp, variance: &result.variance };
    write_maps_exr(&maps, result.layers.as_ref(), &attributes, path)
}

/// What every adaptive EXR holds per pixel: the image, the samples taken
/// and the variance of the value.
struct PixelMaps<'a> {
    image: &'a Image,
    spp: &'a [u64],
    variance: &'a [Rgb],
}

/// Writes `R G B`, `spp.Z`, `variance.R/G/B` and the `layers` (channels
/// named as those of `niebla render --aovs`) as an EXR, with the header
/// attributes `attributes` and `nieblaAovs` (the layers recorded, so
/// `aov::read_aov_exr` reads them).
fn write_maps_exr(
    maps: &PixelMaps,
    layers: Option<&AovImage>,
    attributes: &[(&str, String)],
    path: &std::path::Path,
) -> Result<(), crate::film::OutputError> {
    use exr::prelude::*;
    let encode = |message: String| crate::film::OutputError::Encode { path: path.to_path_buf(), message };
    let image = maps.image;
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        list.push(AnyChannel::new(*name, FlatSamples::F32(image.pixels.iter().map(|p| p[c]).collect())));
        let variance = maps.variance.iter().map(|v| v[c]).collect();
        list.push(AnyChannel::new(format!("variance.{name}").as_str(), FlatSamples::F32(variance)));
    }
    list.push(AnyChannel::new("spp.Z", FlatSamples::F32(maps.spp.iter().map(|&n| n as f32).collect())));
    let mut recorded = AovSet::EMPTY.with(Aov::Variance);
    for layer in layers.iter().flat_map(|l| &l.layers).filter(|l| l.aov != Aov::Variance) {
        recorded = recorded.with(layer.aov);
        for (c, name) in layer.channel_names().iter().enumerate() {
            let values = layer.data.iter().skip(c).step_by(layer.components).copied().collect();
            list.push(AnyChannel::new(name.as_str(), FlatSamples::F32(values)));
        }
    }
    let recorded = recorded.iter().map(|a| a.name()).collect::<Vec<_>>().join(",");
    let mut header = LayerAttributes::default();
    for (name, value) in attributes.iter().map(|(n, v)| (*n, v.as_str())).chain([("nieblaAovs", recorded.as_str())]) {
        header.other.insert(Text::from(name), AttributeValue::Text(Text::from(value)));
    }
    let size = (image.width as usize, image.height as usize);
    let layer = Layer::new(size, header, Encoding::SMALL_LOSSLESS, AnyChannels::sort(list));
    let mut bytes = Vec::new();
    exr::image::Image::from_layer(layer)
        .write()
        .non_parallel()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .map_err(|e| encode(e.to_string()))?;
    crate::film::write_atomically(path, &bytes)
}

/// Per-sample relative variance of each pixel: `spp * var_c / (r_c^2 + eps)`
/// averaged over the channels, with `var_c` the variance of the pixel's value
/// in a render of `spp` samples (`variance(i)`), `r` the `reference` pixel
/// and `eps = (0.01 mean(reference))^2` (the weights of
/// [`Image::relative_mse`]). Its mean over the pixels is the relative MSE of
/// a one-sample render.
pub fn per_sample_relative_variance(reference: &Image, spp: u64, variance: impl Fn(usize) -> Rgb) -> Vec<f64> {
    let eps = (0.01 * reference.mean().average() as f64).powi(2).max(f64::MIN_POSITIVE);
    (0..reference.pixels.len())
        .map(|i| {
            let (r, v) = (reference.pixels[i], variance(i));
            (0..3).map(|c| spp as f64 * v[c] as f64 / ((r[c] as f64).powi(2) + eps)).sum::<f64>() / 3.0
        })
        .collect()
}

/// The most any allocation of samples over the pixels can gain over a
/// uniform one for relative MSE (ratio of total samples to reach equal
/// error): `mean(v) / mean(sqrt v)^2` for per-sample relative variances `v`
/// ([`per_sample_relative_variance`]). Minimising `sum v_p / n_p` at a fixed
/// `sum n_p` gives `n_p` proportional to `sqrt v_p` (Cauchy-Schwarz). At
/// least 1; 1 for empty or all-zero input.
pub fn allocation_bound(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let mean_sqrt = v.iter().map(|x| x.max(0.0).sqrt()).sum::<f64>() / n;
    if v.is_empty() || mean_sqrt <= 0.0 {
        1.0
    } else {
        mean / (mean_sqrt * mean_sqrt)
    }
}

/// The most any allocation of samples over the pixels can gain over a
/// uniform one in time for relative MSE (ratio of the time to reach equal
/// error) when a sample of pixel `p` costs `c[p]`:
/// `mean(v) mean(c) / mean(sqrt(v c))^2`. Minimising `sum v_p / n_p` at a
/// fixed `sum c_p n_p` gives `n_p` proportional to `sqrt(v_p / c_p)`
/// (Cauchy-Schwarz). At least 1; 1 for empty or all-zero input. With equal
/// costs it is [`allocation_bound`].
pub fn cost_allocation_bound(v: &[f64], c: &[f64]) -> f64 {
    let n = v.len().min(c.len()) as f64;
    let mean_v = v.iter().sum::<f64>() / n;
    let mean_c = c.iter().sum::<f64>() / n;
    let mean_sqrt = v.iter().zip(c).map(|(v, c)| (v.max(0.0) * c.max(0.0)).sqrt()).sum::<f64>() / n;
    if n == 0.0 || mean_sqrt <= 0.0 {
        1.0
    } else {
        mean_v * mean_c / (mean_sqrt * mean_sqrt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schedule_ends_at_powers_of_two_and_their_halves() {
        assert_eq!(schedule(64), vec![1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64]);
        assert_eq!(schedule(20), vec![1, 2, 3, 4, 6, 8, 12, 16, 20]);
        assert_eq!(schedule(1), vec![1]);
        assert!(schedule(0).is_empty());
        let ends = schedule(64);
        // The cutoff is a pass end at most half the samples taken.
        assert_eq!([16, 24, 32, 48].map(|t| cutoff(&ends, t)), [8, 12, 16, 24]);
        assert_eq!(cutoff(&ends, 1), 0);
    }

    #[test]
    fn stop_variance_factor_limits() {
        // Standing in with every remaining sample is the plain mean: 1 / N.
        assert!((stop_variance_factor(8, 64, 64) - 1.0 / 64.0).abs() < 1e-15);
        // 8 decided, 8 standing in for 56 of 64: (8 + 56^2 / 8) / 64^2.
        assert!((stop_variance_factor(8, 16, 64) - 400.0 / 4096.0).abs() < 1e-15);
    }

    #[test]
    fn a_stopped_pixel_scales_its_standin_mean() {
        let q = |v: f64| (v * (2f64).powi(FRACTION_BITS)) as i128;
        // 4 decided samples of value 1, 4 standin samples of value 3, schedule 16.
        let decided = Moments { sum: [q(4.0); 3], square: [q(4.0); 3], n: 4, dimensions: 0 };
        let standin = Moments { sum: [q(12.0); 3], square: [q(36.0); 3], n: 4, dimensions: 0 };
        let (value, variance) = pixel_value(&decided, &standin, 16);
        // (4 + 3 * 12) / 16 = 2.5.
        assert!((value[0] - 2.5).abs() < 1e-6, "{value:?}");
        // Sample variance of four 1s and four 3s: 8 / 7; factor (4 + 144 / 4) / 256.
        let expected = 8.0 / 7.0 * 40.0 / 256.0;
        assert!((variance[1] as f64 - expected).abs() < 1e-6, "{variance:?}");
    }

    #[test]
    fn allocation_bound_is_the_cauchy_schwarz_ratio() {
        // Equal variances: nothing to gain.
        assert!((allocation_bound(&[2.0; 10]) - 1.0).abs() < 1e-15);
        // v = 1 and 4: mean 2.5, mean sqrt 1.5, bound 2.5 / 2.25.
        assert!((allocation_bound(&[1.0, 4.0]) - 2.5 / 2.25).abs() < 1e-15);
        // Brute force over allocations n_1 + n_2 = 3000 for v = (1, 4):
        // uniform error (1 + 4) / 1500; the best allocation's error times
        // the bound equals it.
        let (v1, v2, total) = (1.0f64, 4.0f64, 3000u32);
        let best = (1..total).map(|n1| v1 / n1 as f64 + v2 / (total - n1) as f64).fold(f64::INFINITY, f64::min);
        let uniform = (v1 + v2) / (total as f64 / 2.0);
        assert!((uniform / best - allocation_bound(&[v1, v2])).abs() < 1e-5, "{}", uniform / best);
        assert_eq!(allocation_bound(&[]), 1.0);
        assert_eq!(allocation_bound(&[0.0, 0.0]), 1.0);
    }

    #[test]
    fn cost_allocation_bound_is_the_brute_force_optimum() {
        // Equal costs: the sample bound.
        let v = [1.0, 4.0, 9.0];
        assert!((cost_allocation_bound(&v, &[3.0; 3]) - allocation_bound(&v)).abs() < 1e-12);
        // v = (1, 4), c = (1, 16): sqrt(v c) = (1, 8); bound 2.5 * 8.5 / 4.5^2.
        let (v, c) = ([1.0f64, 4.0], [1.0f64, 16.0]);
        assert!((cost_allocation_bound(&v, &c) - 2.5 * 8.5 / 20.25).abs() < 1e-12);
        // Brute force at a time budget of 17000 (uniform: 1000 samples each):
        // uniform error / best error equals the bound.
        let budget = 17_000.0;
        let uniform = (v[0] + v[1]) / (budget / (c[0] + c[1]));
        let best = (1..17_000)
            .map(|n1| n1 as f64)
            .filter(|n1| n1 * c[0] < budget)
            .map(|n1| v[0] / n1 + v[1] / ((budget - n1 * c[0]) / c[1]))
            .fold(f64::INFINITY, f64::min);
        assert!((uniform / best - cost_allocation_bound(&v, &c)).abs() < 1e-4, "{}", uniform / best);
        assert_eq!(cost_allocation_bound(&[], &[]), 1.0);
    }

    #[test]
    fn per_sample_relative_variance_of_a_flat_image() {
        // Reference 2 in every channel, variance of the value 0.04 at 16 spp:
        // 16 * 0.04 / (4 + (0.02)^2).
        let reference = Image { width: 2, height: 1, pixels: vec![Rgb::splat(2.0); 2] };
        let v = per_sample_relative_variance(&reference, 16, |_| Rgb::splat(0.04));
        let expected = 16.0 * 0.04f32 as f64 / (4.0 + 0.0004);
        assert!(v.iter().all(|x| (x - expected).abs() < 1e-9), "{v:?}");
    }
}
