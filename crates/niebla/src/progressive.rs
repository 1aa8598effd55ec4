//! Progressive rendering: passes that double the total sample count (1, 1, 2,
//! 4, ... samples per pixel per pass), with a callback after every pass (for
//! checkpoints and previews). A pass starting after `n` samples per pixel
//! renders sample indices `[n, n + max(n, 1))` (fewer when the budget ends
//! sooner), so the image after any number of passes estimates the same
//! pixel means as one render of that many samples, and it does not depend
//! on the thread count.
//!
//! **Exact continuation.** The accumulator holds the per-pixel exact
//! fixed-point sums of the samples rendered (`film::SampleSums`), which a
//! checkpoint EXR stores beside the mean image. Integer sums are exact and
//! associative, so the image after any passes, a render continued from a
//! checkpoint ([`resume_progressive`] with [`Accumulator::from_sums`]), and
//! sample ranges rendered apart and added up are all bit-identical to one
//! render of the same samples ([`crate::render::render`]).

use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use crate::aov::{AovImage, AovSet, AovSums};
use crate::film::{Image, SampleSums};
use crate::integrator::IntegratorSettings;
use crate::render::{RenderError, RenderOptions};
use crate::sampling::SamplerKind;
use crate::world::Scene;

/// When a progressive render stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// After this many samples per pixel.
    Samples(u32),
    /// Before a pass that would, at the measured speed, end after this much
    /// time (at least one sample per pixel is always rendered).
    Time(Duration),
}

/// The running per-pixel sums of a progressive render (exact fixed-point
/// sums, `film::SampleSums`), the range of sample indices they hold, and
/// their mean image.
///
/// ```
/// use niebla::film::{quantize_sample, SampleSums};
/// use niebla::progressive::Accumulator;
/// let pass = |v: f32, n: i128| SampleSums { width: 1, height: 1, sums: vec![[quantize_sample(v) * n; 3]] };
/// let mut acc = Accumulator::new(1, 1);
/// acc.add(&pass(1.0, 1), 1);
/// acc.add(&pass(4.0, 3), 3);
/// assert_eq!((acc.image().pixels[0][0], acc.spp), (3.25, 4));
/// // Continuing from the stored sums is the same arithmetic.
/// let mut resumed = Accumulator::from_sums(acc.sums().clone(), 0, 4);
/// resumed.add(&pass(0.5, 4), 4);
/// acc.add(&pass(0.5, 4), 4);
/// assert_eq!(resumed.image(), acc.image());
/// ```
#[derive(Clone, Debug)]
pub struct Accumulator {
    sums: SampleSums,
    /// The layers' sums of the same samples (`None`: a render without layers).
    aov: Option<AovSums>,
    /// Index of the first sample accumulated (samples `first_sample ..
    /// first_sample + spp` are in the sums; the next pass starts after them).
    pub first_sample: u64,
    /// Samples per pixel accumulated so far.
    pub spp: u64,
}

impl Accumulator {
    /// An empty accumulator for a `width` x `height` image, starting at
    /// sample index 0.
    pub fn new(width: u32, height: u32) -> Accumulator {
        Accumulator::starting_at(width, height, 0)
    }

    /// An empty accumulator whose first pass renders sample index
    /// `first_sample` (a render of a sample range, e.g. one machine's share).
    pub fn starting_at(width: u32, height: u32, first_sample: u64) -> Accumulator {
        Accumulator { sums: SampleSums::new(width, height), aov: None, first_sample, spp: 0 }
    }

    /// An accumulator continuing from `sums`, the sums of samples
    /// `first_sample .. first_sample + spp` (a checkpoint's sums).
    pub fn from_sums(sums: SampleSums, first_sample: u64, spp: u64) -> Accumulator {
        Accumulator { sums, aov: None, first_sample, spp }
    }

    /// An accumulator continuing from `mean`, the mean of samples `0 .. spp`
    /// (a checkpoint written before checkpoints stored sums). Not exact:
    /// the sums are recovered from the f32 mean, so the continued render
    /// may differ from an uninterrupted one in the last bits.
    pub fn from_mean(mean: Image, spp: u64) -> Accumulator {
        Accumulator { sums: SampleSums::from_mean(&mean, spp), aov: None, first_sample: 0, spp }
    }

    /// The accumulator with layer sums `aov` of the same samples (zero sums,
    /// `AovSums::new`, for a new render; a checkpoint's for a resumed one).
    ///
    /// # Panics
    /// If the image sizes differ.
    pub fn with_aovs(self, aov: AovSums) -> Accumulator {
        assert_eq!((aov.width, aov.height), (self.sums.width, self.sums.height), "layer sums of another size");
        Accumulator { aov: Some(aov), ..self }
    }

    /// The layers' sums, if the render has layers.
    pub fn aov_sums(&self) -> Option<&AovSums> {
        self.aov.as_ref()
    }

    /// The layer images so far (`None` without layers).
    pub fn aov_image(&self) -> Option<AovImage> {
        self.aov.as_ref().map(|a| a.layers(&self.sums, self.spp))
    }

    /// Add the sums of the `spp` samples per pixel of a pass (exact).
    pub fn add(&mut self, pass: &SampleSums, spp: u64) {
        self.sums.add(pass);
        self.spp += spp;
    }

    /// The mean image so far (`film::mean_of_sum` per pixel and channel).
    pub fn image(&self) -> Image {
        self.sums.mean(self.spp)
    }

    /// The sums so far.
    pub fn sums(&self) -> &SampleSums {
        &self.sums
    }

    /// The sample index the next pass starts at.
    pub fn next_sample(&self) -> u64 {
        self.first_sample + self.spp
    }
}

/// What a finished pass reports.
#[derive(Clone, Copy, Debug)]
pub struct PassInfo {
    /// Pass number within this call, from 0.
    pub pass: u32,
    /// Samples per pixel accumulated after this pass.
    pub spp: u64,
    /// Time since the render started.
    pub elapsed: Duration,
}

/// Size of pass `k`: 1, 1, 2, 4, ... so that the total doubles every pass.
#[inline]
pub fn pass_size(k: u32) -> u64 {
    if k == 0 {
        1
    } else {
        1u64 << (k - 1).min(40)
    }
}

/// Size of the pass that follows `spp_done` samples per pixel: as many
/// again (at least 1, at most 2^31 - 1 as one pass renders a `u32` count),
/// so that the schedule 1, 1, 2, 4, ... ([`pass_size`]) depends only on the
/// samples done and a resumed render follows it too.
#[inline]
pub fn next_pass_size(spp_done: u64) -> u64 {
    spp_done.clamp(1, u32::MAX as u64 / 2)
}

/// How a progressive render runs: the integrator, its seed, the threads,
/// when to stop, and whom to tell about progress.
///
/// ```
/// use niebla::progressive::{Budget, ProgressiveOptions};
/// let settings = niebla::integrator::IntegratorSettings::Analytic;
/// let options = ProgressiveOptions { threads: Some(2), ..ProgressiveOptions::new(&settings, 7, Budget::Samples(4)) };
/// assert_eq!((options.seed, options.threads, options.cancel.is_none()), (7, Some(2), true));
/// ```
#[derive(Clone, Copy)]
pub struct ProgressiveOptions<'a> {
    /// The integrator and its parameters.
    pub settings: &'a IntegratorSettings,
    /// Sampler seed; sample indices continue across passes, so one seed
    /// covers the whole render.
    pub seed: u64,
    /// Worker threads (`None`: all cores). The image does not depend on it.
    pub threads: Option<usize>,
    /// The numbers of the camera samples (independent or Sobol).
    pub sampler: SamplerKind,
    /// When the render stops.
    pub budget: Budget,
    /// `progress(done, total)`: pixel samples done within the current pass.
    pub progress: &'a (dyn Fn(u64, u64) + Sync),
    /// Set to stop the render between two pixel blocks (the render then
    /// returns [`RenderError::Cancelled`]).
    pub cancel: Option<&'a AtomicBool>,
    /// Layers rendered beside the beauty (`crate::aov`); the accumulator
    /// must carry their sums ([`Accumulator::with_aovs`]) when not empty.
    pub aovs: AovSet,
}

impl<'a> ProgressiveOptions<'a> {
    /// `settings`, `seed` and `budget` on all cores with the default
    /// sampler, no progress callback and no cancellation.
    pub fn new(settings: &'a IntegratorSettings, seed: u64, budget: Budget) -> ProgressiveOptions<'a> {
        let sampler = SamplerKind::default();
        ProgressiveOptions {
            settings,
            seed,
            threads: None,
            sampler,
            budget,
            progress: &no_progress,
            cancel: None,
            aovs: AovSet::EMPTY,
        }
    }
}

impl std::fmt::Debug for ProgressiveOptions<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProgressiveOptions")
            .field("settings", self.settings)
            .field("seed", &self.seed)
            .field("threads", &self.threads)
            .field("sampler", &self.sampler)
            .field("budget", &self.budget)
            .field("cancel", &self.cancel)
            .field("aovs", &self.aovs)
            .finish_non_exhaustive()
    }
}

/// The progress callback of [`ProgressiveOptions::new`]: does nothing.
fn no_progress(_done: u64, _total: u64) {}

/// Render `scene` progressively until `options.budget` is spent.
/// `on_pass(image, info)` runs after every pass with the mean image so far
/// and may stop the render by returning `false`.
pub fn render_progressive(
    scene: &Scene,
    options: &ProgressiveOptions,
    on_pass: impl FnMut(&Image, PassInfo) -> bool,
) -> Result<Image, RenderError> {
    let start = Accumulator::new(scene.camera.width, scene.camera.height);
    resume_progressive(scene, options, start, on_pass)
}

/// [`resume_progressive_sums`] with `on_pass` seeing the mean image so far
/// and the result being the final mean image.
pub fn resume_progressive(
    scene: &Scene,
    options: &ProgressiveOptions,
    acc: Accumulator,
    mut on_pass: impl FnMut(&Image, PassInfo) -> bool,
) -> Result<Image, RenderError> {
    let acc = resume_progressive_sums(scene, options, acc, |acc, info| on_pass(&acc.image(), info))?;
    Ok(acc.image())
}

/// [`render_progressive`] continuing from `acc` (for instance
/// [`Accumulator::from_sums`] of a checkpoint), with `on_pass` seeing the
/// accumulator and the final accumulator returned: sample indices continue
/// at `acc.next_sample()`, `Budget::Samples(total)` counts the samples
/// already in `acc`,
/// and `Budget::Time` counts from this call. With the same scene, settings
/// and seed, the result is bit-identical to an uninterrupted render that
/// passed through the same `acc`.
pub fn resume_progressive_sums(
    scene: &Scene,
    options: &ProgressiveOptions,
    acc: Accumulator,
    on_pass: impl FnMut(&Accumulator, PassInfo) -> bool,
) -> Result<Accumulator, RenderError> {
    let prepared = crate::render::PreparedIntegrator::new(scene, options.settings);
    resume_progressive_sums_prepared(scene, &prepared, options, acc, on_pass)
}

/// [`resume_progressive_sums`] with the integrator's precomputation done
/// by the caller: `prepared` must be `PreparedIntegrator::new(scene,
/// options.settings)` or equal to it for rendering (brought up to date
/// with [`crate::render::PreparedIntegrator::update`]); the result is then
/// the same. A live viewer keeps it across edits.
pub fn resume_progressive_sums_prepared(
    scene: &Scene,
    prepared: &crate::render::PreparedIntegrator,
    options: &ProgressiveOptions,
    mut acc: Accumulator,
    mut on_pass: impl FnMut(&Accumulator, PassInfo) -> bool,
) -> Result<Accumulator, RenderError> {
    let ProgressiveOptions { settings: _, seed, threads, sampler, budget, progress, cancel, aovs } = *options;
    if !aovs.is_empty() && acc.aov.as_ref().is_none_or(|a| a.set != aovs) {
        let (w, h) = (acc.sums.width, acc.sums.height);
        assert!(acc.spp == 0, "resuming a render with layers needs the checkpoint's layer sums");
        acc = acc.with_aovs(AovSums::new(w, h, aovs));
    }
    let start = Instant::now();
    let mut k = 0u32;
    let mut seconds_per_spp = 0.0f64;
    let mut rendered = 0u64;
    loop {
        let mut size = next_pass_size(acc.spp);
        match budget {
            Budget::Samples(total) => {
                let left = (total as u64).saturating_sub(acc.spp);
                if left == 0 {
                    break;
                }
                size = size.min(left);
            }
            Budget::Time(limit) => {
                let elapsed = start.elapsed().as_secs_f64();
                if rendered > 0 && elapsed + seconds_per_spp * size as f64 > limit.as_secs_f64() {
                    break;
                }
            }
        }
        let pass = RenderOptions { spp: size as u32, seed, first_sample: acc.next_sample(), threads, sampler };
        let pass_start = Instant::now();
        if aovs.is_empty() {
            let sums = prepared.render_sums(scene, &pass, progress, cancel)?;
            acc.add(&sums, size);
        } else {
            let (sums, layers) = prepared.render_aov_sums(scene, &pass, aovs, progress, cancel)?;
            acc.add(&sums, size);
            acc.aov.as_mut().expect("set above").add(&layers);
        }
        seconds_per_spp = pass_start.elapsed().as_secs_f64() / size as f64;
        rendered += size;
        let info = PassInfo { pass: k, spp: acc.spp, elapsed: start.elapsed() };
        if !on_pass(&acc, info) {
            break;
        }
        k += 1;
    }
    Ok(acc)
}
