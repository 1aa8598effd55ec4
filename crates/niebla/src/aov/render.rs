//! The render loop with layers: the beauty sums of `render::pixel_sum` and,
//! per sample, the layers' channels.

use std::sync::atomic::AtomicBool;

use crate::film::{quantize_sample, SampleSums};
use crate::integrator::Integrator;
use crate::render::{map_pixels, ProgressFn, RenderError, RenderOptions};
use crate::sampling::{PixelSampler, SamplerKind};
use crate::world::Scene;

use super::features::camera_features;
use super::{AovSample, AovSet, AovSums};

/// Added to the seed of the features' random stream, so that it is
/// independent of the integrator's numbers (which it never changes).
const FEATURE_STREAM: u64 = 0x5bd1_e995_aa0f_7e31;

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
            let mut sampler = PixelSampler::for_pixel(options.sampler, options.seed, x, y, s);
            let ray = scene.camera.sample_ray(x, y, &mut sampler);
            let mut split = integrator.radiance_split(scene, ray, scene.camera_medium, &mut sampler);
            debug_assert!(
                split.total.is_finite(),
                "non-finite radiance {:?} at pixel ({x}, {y}) sample {s}",
                split.total
            );
            if !split.total.is_finite() {
                // Dropped like the beauty sample (counted as zero in every split layer).
                split = Default::default();
            }
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
