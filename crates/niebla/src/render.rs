//! The render loop: 16x16 tiles on rayon, a counter-based sampler per pixel
//! sample, progress reported per finished tile. The image depends only on the
//! scene, seed and sample count, never on thread count or tile order.
//!
//! Each pixel accumulates the exact fixed-point sum of its samples
//! (`film::SampleSums`); the image is `film::mean_of_sum` of it. So the
//! sums of disjoint sample ranges add up exactly to the sum of their union,
//! and an image assembled from ranges rendered apart (passes, checkpoints,
//! machines) is bit-identical to one render of all its samples.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use crate::color::Rgb;
use crate::film::{mean_of_sum, quantize_sample, Image, SampleSums};
pub use crate::integrator::PreparedIntegrator;
use crate::integrator::{Integrator, IntegratorSettings};
use crate::sampling::{PixelSampler, SamplerKind};
use crate::world::Scene;

/// Tile edge length in pixels.
pub const TILE_SIZE: u32 = 16;

/// Parameters of one render.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Samples per pixel (>= 1).
    pub spp: u32,
    /// Seed of the counter-based sampler.
    pub seed: u64,
    /// Index of the first sample (lets passes continue a render: samples
    /// `first_sample .. first_sample + spp`).
    pub first_sample: u64,
    /// Worker threads; `None` uses rayon's default (all cores).
    pub threads: Option<usize>,
    /// The numbers of the camera samples (independent or Sobol).
    pub sampler: SamplerKind,
}

/// The text a checkpoint records for a render's integrator settings and
/// sampler: the settings' stable key, followed by `"; sampler=sobol"` for
/// Sobol renders with dimensions in draw order ([`SamplerKind::SobolSequential`],
/// which is what `sobol` meant in checkpoints written before integrators had
/// a dimension layout) and, for [`SamplerKind::Sobol`], `"; sampler=sobol;
/// layout=camera-ray"` for the integrators with the camera-ray layout
/// (`single`, `emission`, `analytic`) and `"; sampler=sobol;
/// layout=per-vertex"` for the others (`volpath`'s per-bounce layout; the
/// rest draw in order). Checkpoints of `single`, `emission` and `analytic`
/// written with `layout=per-vertex` were made before those integrators had a
/// layout, so they read as [`SamplerKind::SobolSequential`]. Independent
/// renders record the bare key, as checkpoints written before samplers had
/// kinds do. So an old Sobol checkpoint continues only with the sampler
/// whose numbers it was made with.
///
/// ```
/// use niebla::render::{recorded_key, split_recorded_key};
/// use niebla::sampling::SamplerKind;
/// let s = niebla::integrator::registry::defaults("volpath").unwrap();
/// let key = recorded_key(&s, SamplerKind::Sobol);
/// assert_eq!(key, "volpath(max_depth=1024); sampler=sobol; layout=per-vertex");
/// assert_eq!(split_recorded_key(&key), ("volpath(max_depth=1024)", Some(SamplerKind::Sobol)));
/// assert_eq!(split_recorded_key("volpath(max_depth=1024); sampler=sobol"), ("volpath(max_depth=1024)", Some(SamplerKind::SobolSequential)));
/// assert_eq!(split_recorded_key("volpath(max_depth=1024)"), ("volpath(max_depth=1024)", Some(SamplerKind::Independent)));
/// let a = niebla::integrator::registry::defaults("analytic").unwrap();
/// assert_eq!(recorded_key(&a, SamplerKind::Sobol), "analytic; sampler=sobol; layout=camera-ray");
/// assert_eq!(split_recorded_key("analytic; sampler=sobol; layout=camera-ray"), ("analytic", Some(SamplerKind::Sobol)));
/// assert_eq!(split_recorded_key("analytic; sampler=sobol; layout=per-vertex"), ("analytic", Some(SamplerKind::SobolSequential)));
/// ```
pub fn recorded_key(settings: &IntegratorSettings, sampler: SamplerKind) -> String {
    let key = settings.key();
    match sampler {
        SamplerKind::Independent => key,
        SamplerKind::SobolSequential => format!("{key}; sampler=sobol"),
        SamplerKind::Sobol if has_camera_ray_layout(&key) => format!("{key}; sampler=sobol{CAMERA_RAY_SUFFIX}"),
        SamplerKind::Sobol => format!("{key}; sampler=sobol{LAYOUT_SUFFIX}"),
    }
}

/// What [`recorded_key`] appends to a laid-out Sobol sampler's name.
const LAYOUT_SUFFIX: &str = "; layout=per-vertex";

/// What [`recorded_key`] appends for the integrators with the camera-ray layout.
const CAMERA_RAY_SUFFIX: &str = "; layout=camera-ray";

/// Whether the integrator of settings key `key` has the camera-ray
/// dimension layout (`single`, `emission`, `analytic`).
fn has_camera_ray_layout(key: &str) -> bool {
    key == "analytic" || key.starts_with("single(") || key.starts_with("emission(")
}

/// The integrator key and sampler of a [`recorded_key`] (`None`: a sampler
/// name this build does not know).
pub fn split_recorded_key(recorded: &str) -> (&str, Option<SamplerKind>) {
    for (suffix, camera_ray) in [(CAMERA_RAY_SUFFIX, true), (LAYOUT_SUFFIX, false)] {
        if let Some(rest) = recorded.strip_suffix(suffix) {
            return match rest.rsplit_once("; sampler=") {
                Some((key, "sobol")) if camera_ray == has_camera_ray_layout(key) => (key, Some(SamplerKind::Sobol)),
                // Made before these integrators had a layout: draw order.
                Some((key, "sobol")) if !camera_ray => (key, Some(SamplerKind::SobolSequential)),
                Some((key, _)) => (key, None),
                None => (rest, None),
            };
        }
    }
    match recorded.rsplit_once("; sampler=") {
        Some((key, "sobol")) => (key, Some(SamplerKind::SobolSequential)),
        Some((key, name)) => (key, SamplerKind::parse(name)),
        None => (recorded, Some(SamplerKind::Independent)),
    }
}

/// Why a render did not produce an image.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The thread pool could not be created.
    #[error("could not start {threads} render threads: {message}")]
    ThreadPool {
        /// Requested thread count.
        threads: usize,
        /// Cause.
        message: String,
    },
    /// The cancel flag was raised.
    #[error("render cancelled")]
    Cancelled,
    /// The integrator cannot render this scene.
    #[error("{integrator} cannot render this scene: {reason}")]
    Unsupported {
        /// The integrator's name.
        integrator: &'static str,
        /// What in the scene it does not support, and what to use instead.
        reason: String,
    },
}

/// Progress of a render: called after each tile with (pixel samples done, total).
pub type ProgressFn<'a> = &'a (dyn Fn(u64, u64) + Sync);

/// Render `scene` with the integrator described by `settings` (its
/// precomputation included).
pub fn render(
    scene: &Scene,
    settings: &IntegratorSettings,
    options: &RenderOptions,
    progress: ProgressFn,
    cancel: Option<&AtomicBool>,
) -> Result<Image, RenderError> {
    PreparedIntegrator::new(scene, settings).render(scene, options, progress, cancel)
}

/// [`render`], returning the per-pixel fixed-point sums of samples
/// `options.first_sample .. options.first_sample + options.spp` instead of
/// their mean (what a distributed render adds up).
pub fn render_sums(
    scene: &Scene,
    settings: &IntegratorSettings,
    options: &RenderOptions,
    progress: ProgressFn,
    cancel: Option<&AtomicBool>,
) -> Result<SampleSums, RenderError> {
    PreparedIntegrator::new(scene, settings).render_sums(scene, options, progress, cancel)
}

/// Render with a concrete integrator type (monomorphized per integrator):
/// the mean of the sums of [`render_sums_with`].
pub fn render_with<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    options: &RenderOptions,
    progress: ProgressFn,
    cancel: Option<&AtomicBool>,
) -> Result<Image, RenderError> {
    Ok(render_sums_with(scene, integrator, options, progress, cancel)?.mean(options.spp as u64))
}

/// The per-pixel fixed-point sums of samples `options.first_sample ..
/// options.first_sample + options.spp` with a concrete integrator type.
pub fn render_sums_with<I: Integrator>(
    scene: &Scene,
    integrator: &I,
    options: &RenderOptions,
    progress: ProgressFn,
    cancel: Option<&AtomicBool>,
) -> Result<SampleSums, RenderError> {
    let sums = map_pixels(scene, options, progress, cancel, |x, y| pixel_sum(scene, integrator, options, x, y))?;
    Ok(SampleSums { width: scene.camera.width, height: scene.camera.height, sums })
}

/// `pixel(x, y)` for every pixel of the scene's image, in 16x16 tiles on
/// `options.threads` threads (progress counted as `options.spp` samples
/// per pixel), assembled row by row from the top whatever the tile order.
pub(crate) fn map_pixels<P: Send>(
    scene: &Scene,
    options: &RenderOptions,
    progress: ProgressFn,
    cancel: Option<&AtomicBool>,
    pixel: impl Fn(u32, u32) -> P + Sync,
) -> Result<Vec<P>, RenderError> {
    match options.threads {
        Some(threads) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map_err(|e| RenderError::ThreadPool { threads, message: e.to_string() })?;
            pool.install(|| render_tiles(scene, options, progress, cancel, &pixel))
        }
        None => render_tiles(scene, options, progress, cancel, &pixel),
    }
}

fn render_tiles<P: Send>(
    scene: &Scene,
    options: &RenderOptions,
    progress: ProgressFn,
    cancel: Option<&AtomicBool>,
    pixel: &(impl Fn(u32, u32) -> P + Sync),
) -> Result<Vec<P>, RenderError> {
    use rayon::prelude::*;
    let (w, h) = (scene.camera.width, scene.camera.height);
    let tiles_x = w.div_ceil(TILE_SIZE);
    let tiles_y = h.div_ceil(TILE_SIZE);
    let total = w as u64 * h as u64 * options.spp as u64;
    let done = AtomicU64::new(0);
    let tiles: Vec<(u32, u32, Vec<P>)> = (0..tiles_x * tiles_y)
        .into_par_iter()
        .map(|tile| {
            let (x0, y0) = ((tile % tiles_x) * TILE_SIZE, (tile / tiles_x) * TILE_SIZE);
            let (x1, y1) = ((x0 + TILE_SIZE).min(w), (y0 + TILE_SIZE).min(h));
            let mut out = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
            if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                return (tile, 0, out);
            }
            for y in y0..y1 {
                for x in x0..x1 {
                    out.push(pixel(x, y));
                }
            }
            let n = (x1 - x0) as u64 * (y1 - y0) as u64 * options.spp as u64;
            progress(done.fetch_add(n, Ordering::Relaxed) + n, total);
            (tile, 1, out)
        })
        .collect();
    if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) || tiles.iter().any(|t| t.1 == 0) {
        return Err(RenderError::Cancelled);
    }
    // Tiles come in index order (rayon's collect keeps it) and hold their
    // pixels row by row: take each image row from the tiles it crosses.
    let mut tiles: Vec<std::vec::IntoIter<P>> = tiles.into_iter().map(|t| t.2.into_iter()).collect();
    let mut pixels = Vec::with_capacity(w as usize * h as usize);
    for y in 0..h {
        let row = (y / TILE_SIZE) * tiles_x;
        for tx in 0..tiles_x {
            let tw = ((tx + 1) * TILE_SIZE).min(w) - tx * TILE_SIZE;
            pixels.extend(tiles[(row + tx) as usize].by_ref().take(tw as usize));
        }
    }
    Ok(pixels)
}

/// Mean radiance of `options.spp` samples of pixel `(x, y)`:
/// [`mean_of_sum`] of [`pixel_sum`].
#[inline]
pub fn render_pixel<I: Integrator>(scene: &Scene, integrator: &I, options: &RenderOptions, x: u32, y: u32) -> Rgb {
    let sum = pixel_sum(scene, integrator, options, x, y);
    let n = options.spp as u64;
    Rgb::new(mean_of_sum(sum[0], n), mean_of_sum(sum[1], n), mean_of_sum(sum[2], n))
}

/// Fixed-point sum (`film::quantize_sample` per channel) of the samples
/// `options.first_sample .. options.first_sample + options.spp` of pixel
/// `(x, y)`. Samples with a non-finite value are dropped (counted as zero)
/// so that one numerical accident cannot poison a pixel; debug builds
/// assert instead.
#[inline]
pub fn pixel_sum<I: Integrator>(scene: &Scene, integrator: &I, options: &RenderOptions, x: u32, y: u32) -> [i128; 3] {
    let mut sum = [0i128; 3];
    for s in options.first_sample..options.first_sample + options.spp as u64 {
        let mut sampler = PixelSampler::for_pixel(options.sampler, options.seed, x, y, s);
        let ray = scene.camera.sample_ray(x, y, &mut sampler);
        let l = integrator.radiance(scene, ray, scene.camera_medium, &mut sampler);
        debug_assert!(l.is_finite(), "non-finite radiance {l:?} at pixel ({x}, {y}) sample {s}");
        if l.is_finite() {
            for c in 0..3 {
                sum[c] += quantize_sample(l[c]);
            }
        }
    }
    sum
}
