//! Progressive rendering: passes that double the total sample count (1, 1, 2,
//! 4, ... samples per pixel per pass), accumulated exactly, with a callback
//! after every pass (for checkpoints and previews). Pass `k` renders sample
//! indices `[n_k, n_k + size_k)`, so the image after any number of passes is
//! the same as one render of that many samples would give up to the order of
//! summation, and it does not depend on the thread count.

use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

use crate::color::Rgb;
use crate::film::Image;
use crate::integrator::IntegratorSettings;
use crate::render::{render, RenderError, RenderOptions};
use crate::scene::Scene;

/// When a progressive render stops.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// After this many samples per pixel.
    Samples(u32),
    /// Before a pass that would, at the measured speed, end after this much
    /// time (at least one sample per pixel is always rendered).
    Time(Duration),
}

/// Running per-pixel sums of a progressive render, in f64.
#[derive(Clone, Debug)]
pub struct Accumulator {
    width: u32,
    height: u32,
    sum: Vec<[f64; 3]>,
    /// Samples per pixel accumulated so far.
    pub spp: u64,
}

impl Accumulator {
    /// An empty accumulator for a `width` x `height` image.
    pub fn new(width: u32, height: u32) -> Accumulator {
        Accumulator { width, height, sum: vec![[0.0; 3]; width as usize * height as usize], spp: 0 }
    }

    /// Add a pass image that is the mean of `spp` samples per pixel.
    pub fn add(&mut self, pass: &Image, spp: u64) {
        for (s, p) in self.sum.iter_mut().zip(&pass.pixels) {
            for c in 0..3 {
                s[c] += p[c] as f64 * spp as f64;
            }
        }
        self.spp += spp;
    }

    /// The mean image so far.
    pub fn image(&self) -> Image {
        let n = self.spp.max(1) as f64;
        Image {
            width: self.width,
            height: self.height,
            pixels: self
                .sum
                .iter()
                .map(|s| Rgb::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32))
                .collect(),
        }
    }
}

/// What a finished pass reports.
#[derive(Clone, Copy, Debug)]
pub struct PassInfo {
    /// Pass number, from 0.
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

/// Render progressively until `budget` is spent. `progress(done, total)` sees
/// pixel samples within the current pass; `on_pass(image, info)` runs after
/// every pass and may stop the render by returning `false`.
#[allow(clippy::too_many_arguments)]
pub fn render_progressive(
    scene: &Scene,
    settings: &IntegratorSettings,
    seed: u64,
    threads: Option<usize>,
    budget: Budget,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: Option<&AtomicBool>,
    mut on_pass: impl FnMut(&Image, PassInfo) -> bool,
) -> Result<Image, RenderError> {
    let start = Instant::now();
    let mut acc = Accumulator::new(scene.camera.width, scene.camera.height);
    let mut k = 0u32;
    let mut seconds_per_spp = 0.0f64;
    loop {
        let mut size = pass_size(k);
        match budget {
            Budget::Samples(total) => {
                let left = total as u64 - acc.spp;
                if left == 0 {
                    break;
                }
                size = size.min(left);
            }
            Budget::Time(limit) => {
                let elapsed = start.elapsed().as_secs_f64();
                if acc.spp > 0 && elapsed + seconds_per_spp * size as f64 > limit.as_secs_f64() {
                    break;
                }
            }
        }
        let options = RenderOptions { spp: size as u32, seed, first_sample: acc.spp, threads };
        let pass_start = Instant::now();
        let image = render(scene, settings, &options, progress, cancel)?;
        seconds_per_spp = pass_start.elapsed().as_secs_f64() / size as f64;
        acc.add(&image, size);
        let info = PassInfo { pass: k, spp: acc.spp, elapsed: start.elapsed() };
        if !on_pass(&acc.image(), info) {
            break;
        }
        k += 1;
    }
    Ok(acc.image())
}
