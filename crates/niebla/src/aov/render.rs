//! The render loop with layers: the beauty sums of `render::pixel_sum` and,
//! per sample, the layers' channels.

use std::sync::atomic::AtomicBool;

use crate::film::{quantize_sample, SampleSums};
use crate::integrator::Integrator;
use crate::math::Ray;
use crate::render::{map_pixels, ProgressFn, RenderError, RenderOptions};
use crate::sampling::{PixelSampler, SamplerKind};
use crate::world::Scene;

use super::features::camera_features;
use super::{AovChannel, AovSample, AovSet, AovSums, LayerSplit};

/// Added to the seed of the features' random stream, so that it is
/// independent of the integrator's numbers (which it never changes).
const FEATURE_STREAM: u64 = 0x5bd1_e995_aa0f_7e31;

/// Sample `s` of pixel `(x, y)`: the camera ray, its radiance split into
/// the layers (`split`) or whole ([`LayerSplit::unsplit`]), and the number of
/// random dimensions the sample drew (its cost proxy, see
/// `crate::adaptive::COST_OFFSET`). A non-finite sample is dropped like the
/// beauty sample of a plain render: zero in every layer.
#[inline]
fn traced_sample<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    kind: SamplerKind,
    seed: u64,
    (x, y, s): (u32, u32, u64),
    split: bool,
) -> (Ray, LayerSplit, u64) {
    let mut sampler = PixelSampler::for_pixel(kind, seed, x, y, s);
    let ray = scene.camera.sample_ray(x, y, &mut sampler);
    let traced = if split {
        integrator.radiance_split(scene, ray, scene.camera_medium, &mut sampler)
    } else {
        LayerSplit::unsplit(integrator.radiance(scene, ray, scene.camera_medium, &mut sampler))
    };
    debug_assert!(traced.total.is_finite(), "non-finite radiance {:?} at pixel ({x}, {y}) sample {s}", traced.total);
    let dimensions = sampler.dimension();
    (ray, if traced.total.is_finite() { traced } else { Default::default() }, dimensions)
}

/// The beauty sums and the layer sums of `set` for samples
/// `options.first_sample .. + options.spp` with a concrete integrator. The
/// beauty sums equal [`crate::render::render_sums_with`]'s bit for bit: the
/// layers' features draw from a stream of their own (independent numbers,
/// seeded by `(seed, x, y, sample)`, whatever the render's sampler).
pub fn render_aov_sums_with<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    options: &RenderOptions,
    set: AovSet,
    progress: ProgressFn,
    cancel: Option<&AtomicBool>,
) -> Result<(SampleSums, AovSums), RenderError> {
    render_aov_sums_masked_with(scene, integrator, options, set, None, progress, cancel)
}

/// [`render_aov_sums_with`] for the pixels whose `active` flag is set
/// (`active[y * width + x]`; all when `None`): the others take no sample
/// and their sums are zero.
pub fn render_aov_sums_masked_with<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    options: &RenderOptions,
    set: AovSet,
    active: Option<&[bool]>,
    progress: ProgressFn,
    cancel: Option<&AtomicBool>,
) -> Result<(SampleSums, AovSums), RenderError> {
    let width = scene.camera.width as usize;
    let channels = AovSums::channels_for(set);
    let k = channels.len();
    let needs_features =
        channels.iter().any(|c| !matches!(c, super::AovChannel::Split(..) | super::AovChannel::Square(_)));
    let pixels = map_pixels(scene, options, progress, cancel, |x, y| {
        let mut beauty = [0i128; 3];
        let mut layers = vec![0i128; k];
        if active.is_some_and(|a| !a[y as usize * width + x as usize]) {
            return (beauty, layers);
        }
        for s in options.first_sample..options.first_sample + options.spp as u64 {
            let (ray, split, _) = traced_sample(scene, integrator, options.sampler, options.seed, (x, y, s), true);
            for (sum, v) in beauty.iter_mut().zip(split.total.0) {
                *sum += quantize_sample(v);
            }
            let features = if needs_features {
                let mut own = PixelSampler::for_pixel(
                    SamplerKind::Independent,
                    options.seed.wrapping_add(FEATURE_STREAM),
                    x,
                    y,
                    s,
                );
                camera_features(scene, ray, scene.camera_medium, &mut own)
            } else {
                Default::default()
            };
            AovSums::accumulate(&channels, &AovSample { split, features }, &mut layers);
        }
        (beauty, layers)
    })?;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut sums = SampleSums::new(w, h);
    let mut aov = AovSums::new(w, h, set);
    for (i, (beauty, layers)) in pixels.into_iter().enumerate() {
        sums.sums[i] = beauty;
        aov.values[i * k..(i + 1) * k].copy_from_slice(&layers);
    }
    Ok((sums, aov))
}

/// The layer channels [`render_segment_sums_with`] sums for `set`: those of
/// [`AovSums::channels_for`] without the beauty's squares (always summed).
pub fn segment_channels(set: AovSet) -> Vec<AovChannel> {
    AovSums::channels_for(set).into_iter().filter(|c| !matches!(c, AovChannel::Square(_))).collect()
}

/// Fixed-point sums of sample ranges of some pixels, the render loop of
/// adaptive sampling (`crate::adaptive`). For each pixel `pixels[j]`
/// (index `y * width + x`) and each range `segments[g] = (start, end)` of
/// sample indices, `7 + k` sums at `out[(j * segments.len() + g) * (7 + k)..]`:
/// the beauty's R, G, B, their squares, the random dimensions the samples
/// drew (an integer count, the cost proxy of `crate::adaptive`), and the `k`
/// channels of [`segment_channels`]`(set)`. Independent sampler; every sample is that of
/// [`render_aov_sums_with`] with the same seed and index (the beauty's bit
/// for bit: without split layers it calls `radiance`, whose value
/// `radiance_split` reproduces). Runs on the current rayon pool in chunks
/// of pixels; the sums do not depend on the chunking or the thread count.
pub fn render_segment_sums_with<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    seed: u64,
    set: AovSet,
    pixels: &[u32],
    segments: &[(u64, u64)],
    cancel: Option<&AtomicBool>,
) -> Result<Vec<i128>, RenderError> {
    use rayon::prelude::*;
    use std::sync::atomic::Ordering;
    let channels = segment_channels(set);
    let stride = 7 + channels.len();
    let per_pixel = stride * segments.len();
    let width = scene.camera.width;
    // Small chunks balance uneven pixels (stopped neighbours leave few
    // active pixels per tile); large enough to keep rayon's cost negligible.
    let chunk = (pixels.len() / (rayon::current_num_threads() * 16)).clamp(1, 256);
    let chunks: Vec<Option<Vec<i128>>> = pixels
        .par_chunks(chunk)
        .map(|list| {
            if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                return None;
            }
            let mut out = vec![0i128; list.len() * per_pixel];
            for (j, &i) in list.iter().enumerate() {
                let (x, y) = (i % width, i / width);
                for (g, &range) in segments.iter().enumerate() {
                    let cell = &mut out[j * per_pixel + g * stride..][..stride];
                    sum_samples(scene, integrator, SamplerKind::Independent, seed, &channels, (x, y), range, cell);
                }
            }
            Some(out)
        })
        .collect();
    if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) || chunks.iter().any(Option::is_none) {
        return Err(RenderError::Cancelled);
    }
    Ok(chunks.into_iter().flatten().flatten().collect())
}

/// Adds to `cell` (`7 + channels.len()` sums, the layout of
/// [`render_segment_sums_with`]) the samples `start .. end` of pixel
/// `(x, y)` drawn by sampler `kind` with `seed`.
#[allow(clippy::too_many_arguments)]
#[inline]
fn sum_samples<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    kind: SamplerKind,
    seed: u64,
    channels: &[AovChannel],
    (x, y): (u32, u32),
    (start, end): (u64, u64),
    cell: &mut [i128],
) {
    let needs_split = channels.iter().any(|c| matches!(c, AovChannel::Split(..)));
    let needs_features = channels.iter().any(|c| !matches!(c, AovChannel::Split(..)));
    for s in start..end {
        let (ray, split, dimensions) = traced_sample(scene, integrator, kind, seed, (x, y, s), needs_split);
        for (c, v) in split.total.0.into_iter().enumerate() {
            cell[c] += quantize_sample(v);
            cell[3 + c] += quantize_sample(v * v);
        }
        cell[6] += dimensions as i128;
        if channels.is_empty() {
            continue;
        }
        let features = if needs_features {
            let mut own = PixelSampler::for_pixel(SamplerKind::Independent, seed.wrapping_add(FEATURE_STREAM), x, y, s);
            camera_features(scene, ray, scene.camera_medium, &mut own)
        } else {
            Default::default()
        };
        AovSums::accumulate(channels, &AovSample { split, features }, &mut cell[7..]);
    }
}

/// Fixed-point sums of one range of sample indices per pixel, drawn by
/// sampler `kind`: for pixel `pixels[j]` (index `y * width + x`) the
/// samples `ranges[j].0 .. ranges[j].1`, summed as one segment of
/// [`render_segment_sums_with`] (`7 + k` sums at `out[j * (7 + k)..]`). Each
/// sample is that of a plain render with the same sampler, seed and index.
/// The render loop of pilot-allocated sampling (`crate::adaptive_pilot`);
/// runs on the current rayon pool in chunks of pixels, and the sums do not
/// depend on the chunking or the thread count.
#[allow(clippy::too_many_arguments)]
pub fn render_range_sums_with<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    kind: SamplerKind,
    seed: u64,
    set: AovSet,
    pixels: &[u32],
    ranges: &[(u64, u64)],
    cancel: Option<&AtomicBool>,
) -> Result<Vec<i128>, RenderError> {
    use rayon::prelude::*;
    use std::sync::atomic::Ordering;
    assert_eq!(pixels.len(), ranges.len(), "one sample range per pixel");
    let channels = segment_channels(set);
    let stride = 7 + channels.len();
    let width = scene.camera.width;
    // Pixels differ in their sample counts: small chunks keep the threads busy.
    let chunk = (pixels.len() / (rayon::current_num_threads() * 16)).clamp(1, 64);
    let chunks: Vec<Option<Vec<i128>>> = pixels
        .par_chunks(chunk)
        .zip(ranges.par_chunks(chunk))
        .map(|(list, ranges)| {
            if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                return None;
            }
            let mut out = vec![0i128; list.len() * stride];
            for (j, (&i, &range)) in list.iter().zip(ranges).enumerate() {
                let cell = &mut out[j * stride..][..stride];
                sum_samples(scene, integrator, kind, seed, &channels, (i % width, i / width), range, cell);
            }
            Some(out)
        })
        .collect();
    if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) || chunks.iter().any(Option::is_none) {
        return Err(RenderError::Cancelled);
    }
    Ok(chunks.into_iter().flatten().flatten().collect())
}
