//! Adaptive sampling without bias: pixels whose estimated relative error
//! is below a threshold stop receiving samples, and the image still has
//! the expectation of the plain render.
//!
//! Passes follow the progressive schedule (1, 1, 2, 4, ... samples per
//! pixel, sample indices continuing), and a pixel takes a pass only while
//! it is active. **Decisions lag one pass**: whether pixel `p` takes pass
//! `k` is decided from the samples of passes `< k - 1` alone (of any pixel),
//! and once inactive a pixel stays so. If `p` stops before pass `K`, its
//! value is
//! `(S_{<K-1} + M_{K-1} (N - n_{<K-1})) / N`: the sum of its passes before
//! the last, plus the mean `M_{K-1}` of its last pass standing in for every
//! sample it did not take (`N` the samples of the whole schedule). Writing
//! the value as `sum_i (n_i / N) Z_i` over the schedule's passes, with `Z_i`
//! the pass mean where `p` took pass `i` and `M_{K-1}` where it did not:
//! `E[Z_i 1{active at i}] = mu P(active at i)` because the decision uses
//! passes `< i - 1` only, and `E[M_{K-1} 1{K = k}] = mu P(K = k)` because
//! the event `K = k` is decided from passes `< k - 1`, which pass `k - 1`'s
//! samples are independent of. So `E[Z_i] = mu` for every `i` and the
//! image is unbiased. (Averaging all the samples a pixel took until it
//! looked converged would not be: a pixel whose first samples happened to
//! be bright shows a lower relative error and stops sooner.)
//!
//! The argument needs the passes of a pixel to be independent, so adaptive
//! renders use the independent sampler: Owen-scrambled Sobol points of a
//! later pass fill the strata the earlier ones left, so its mean is not
//! independent of them (measured: with Sobol the adaptive image mean came
//! out 4.5 standard errors low on the test scene of `tests/adaptive.rs`).
//!
//! A pixel may stop only once its decisions see `spp / 8` samples (at
//! least 8). The error of a pixel is the standard error of its channel-averaged mean,
//! from the samples' sums and sums of squares, over that mean (floored at
//! 1% of the image's mean, so black pixels do not run forever).

use std::sync::atomic::AtomicBool;

use crate::aov::{Aov, AovSet};
use crate::color::Rgb;
use crate::film::{mean_of_sum, Image, FRACTION_BITS};
use crate::integrator::{IntegratorSettings, PreparedIntegrator};
use crate::render::{RenderError, RenderOptions};
use crate::sampling::SamplerKind;
use crate::world::Scene;

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
}

/// How an adaptive render runs.
#[derive(Clone, Copy, Debug)]
pub struct AdaptiveOptions {
    /// Samples per pixel of the schedule (the most a pixel takes).
    pub spp: u32,
    /// Relative standard error below which a pixel stops, in (0, 1).
    pub threshold: f32,
    /// Sampler seed.
    pub seed: u64,
    /// Worker threads (`None`: all cores).
    pub threads: Option<usize>,
}

/// Per-pixel running sums (fixed point, as `film::SampleSums`).
#[derive(Clone, Copy, Default)]
struct PixelState {
    /// Sums and squares of the samples of all passes taken.
    sum: [i128; 3],
    square: [i128; 3],
    n: u64,
    /// The same, up to the pass before the last one taken (what decisions see
    /// of this pixel after the last pass is in).
    lagged: ([i128; 3], [i128; 3], u64),
    /// Sums of the last pass taken, and its size.
    last: [i128; 3],
    last_n: u64,
    active: bool,
}

fn to_f64(v: i128) -> f64 {
    v as f64 * (2f64).powi(-FRACTION_BITS)
}

/// Relative standard error of the channel-averaged mean of `n` samples with
/// sums `sum` and sums of squares `square`, against `floor`.
fn relative_error(sum: [i128; 3], square: [i128; 3], n: u64, floor: f64) -> f64 {
    if n < 2 {
        return f64::INFINITY;
    }
    let nf = n as f64;
    let mut mean = 0.0;
    let mut var = 0.0;
    for c in 0..3 {
        let m = to_f64(sum[c]) / nf;
        mean += m / 3.0;
        var += ((to_f64(square[c]) - nf * m * m) / (nf * (nf - 1.0))).max(0.0) / 9.0;
    }
    var.sqrt() / mean.abs().max(floor)
}

/// Render `scene` adaptively (see the module documentation). `threshold`
/// must lie in (0, 1); `photon`, `ppm` and `ppb` are not supported (no per-pixel
/// sample sums of their own).
pub fn render_adaptive(
    scene: &Scene,
    settings: &IntegratorSettings,
    options: &AdaptiveOptions,
    progress: crate::render::ProgressFn,
    cancel: Option<&AtomicBool>,
) -> Result<AdaptiveImage, RenderError> {
    let prepared = PreparedIntegrator::new(scene, settings);
    let (w, h) = (scene.camera.width, scene.camera.height);
    let pixels = w as usize * h as usize;
    let mut state = vec![PixelState { active: true, ..Default::default() }; pixels];
    let set = AovSet::EMPTY.with(Aov::Variance);
    let total = u64::from(options.spp);
    let mut done = 0u64;
    // A stopped pixel's last pass (as many samples as it had before it)
    // stands in for all it skips, so a rare bright sample there is scaled
    // up by up to `total / n`: decisions wait for `total / 8` samples (at
    // least 8), which bounds that factor by 8 and keeps sample variances
    // of heavy-tailed pixels from looking converged too early.
    let min_lagged = (total / 8).max(8);
    while done < total {
        let size = crate::progressive::next_pass_size(done).min(total - done);
        // Decide from what every pixel had before its last pass.
        let image_mean: f64 = state
            .iter()
            .map(|p| {
                if p.lagged.2 > 0 {
                    (0..3).map(|c| to_f64(p.lagged.0[c])).sum::<f64>() / (3.0 * p.lagged.2 as f64)
                } else {
                    0.0
                }
            })
            .sum::<f64>()
            / pixels.max(1) as f64;
        let floor = (0.01 * image_mean).max(1e-12);
        for p in state.iter_mut().filter(|p| p.active) {
            let (sum, square, n) = p.lagged;
            if n >= min_lagged && relative_error(sum, square, n, floor) < options.threshold as f64 {
                p.active = false;
            }
        }
        let active: Vec<bool> = state.iter().map(|p| p.active).collect();
        if !active.iter().any(|&a| a) {
            break;
        }
        let pass = RenderOptions {
            spp: size as u32,
            seed: options.seed,
            first_sample: done,
            threads: options.threads,
            sampler: SamplerKind::Independent,
        };
        let (sums, squares) = prepared.render_aov_sums_masked(scene, &pass, set, Some(&active), progress, cancel)?;
        for (i, p) in state.iter_mut().enumerate().filter(|(_, p)| p.active) {
            p.lagged = (p.sum, p.square, p.n);
            p.last = sums.sums[i];
            p.last_n = size;
            for c in 0..3 {
                p.sum[c] += sums.sums[i][c];
                p.square[c] += squares.values[i * 3 + c];
            }
            p.n += size;
        }
        done += size;
    }
    let n_total = done.max(1) as f64;
    let mut image = Image::new(w, h);
    let mut variance = Vec::with_capacity(pixels);
    for (i, p) in state.iter().enumerate() {
        // Samples of the schedule this pixel did not take, stood in for by its last pass.
        let missing = (done - p.n) as f64;
        let before_last = p.n - p.last_n;
        let mut value = Rgb::ZERO;
        let mut var = Rgb::ZERO;
        for c in 0..3 {
            let last_mean = if p.last_n > 0 { to_f64(p.last[c]) / p.last_n as f64 } else { 0.0 };
            let v = if missing > 0.0 {
                (to_f64(p.sum[c] - p.last[c]) + last_mean * (p.last_n as f64 + missing)) / n_total
            } else {
                mean_of_sum(p.sum[c], p.n) as f64
            };
            value[c] = v as f32;
            // Sample variance of the pixel's samples, propagated through the weights.
            let n = p.n as f64;
            let s2 = if p.n > 1 {
                ((to_f64(p.square[c]) - n * (to_f64(p.sum[c]) / n).powi(2)) / (n - 1.0)).max(0.0)
            } else {
                0.0
            };
            let w_last = p.last_n as f64 + missing;
            let weight = if p.last_n > 0 { before_last as f64 + w_last * w_last / p.last_n as f64 } else { 0.0 };
            var[c] = (s2 * weight / (n_total * n_total)) as f32;
        }
        image.pixels[i] = value;
        variance.push(var);
    }
    Ok(AdaptiveImage { image, spp: state.iter().map(|p| p.n).collect(), variance, total_spp: done })
}

/// Writes an adaptive render as an EXR: the image (`R`, `G`, `B`), the
/// samples each pixel took (`spp.Z`) and the variance of each pixel's value
/// (`variance.R/G/B`), with the threshold and the schedule's spp as header
/// attributes. Not a checkpoint: an adaptive render cannot be resumed.
pub fn write_adaptive_exr(
    result: &AdaptiveImage,
    threshold: f32,
    path: &std::path::Path,
) -> Result<(), crate::film::OutputError> {
    use exr::prelude::*;
    let encode = |message: String| crate::film::OutputError::Encode { path: path.to_path_buf(), message };
    let image = &result.image;
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        list.push(AnyChannel::new(*name, FlatSamples::F32(image.pixels.iter().map(|p| p[c]).collect())));
        let variance = result.variance.iter().map(|v| v[c]).collect();
        list.push(AnyChannel::new(format!("variance.{name}").as_str(), FlatSamples::F32(variance)));
    }
    list.push(AnyChannel::new("spp.Z", FlatSamples::F32(result.spp.iter().map(|&n| n as f32).collect())));
    let mut attributes = LayerAttributes::default();
    for (name, value) in
        [("nieblaAdaptiveThreshold", threshold.to_string()), ("nieblaSpp", result.total_spp.to_string())]
    {
        attributes.other.insert(Text::from(name), AttributeValue::Text(Text::from(value.as_str())));
    }
    let size = (image.width as usize, image.height as usize);
    let layer = Layer::new(size, attributes, Encoding::SMALL_LOSSLESS, AnyChannels::sort(list));
    let mut bytes = Vec::new();
    exr::image::Image::from_layer(layer)
        .write()
        .non_parallel()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .map_err(|e| encode(e.to_string()))?;
    crate::film::write_atomically(path, &bytes)
}
