//! Ray-march helpers shared by the integrators that march camera rays:
//! the default step, jittered steps through a grid medium, and where an
//! unbounded homogeneous segment stops mattering.

use crate::color::Rgb;
use crate::math::Ray;
use crate::sampling::PixelSampler;
use crate::tracking::MarchStep;

/// Ray-march step used when a scene gives none: a quarter of the mean free
/// path of the densest channel, but never coarser than 1/64 of the scene
/// diagonal and at most 4096 steps over the diagonal.
pub fn default_march_step(max_sigma_t: f32, scene_diagonal: f32) -> MarchStep {
    let diag = if scene_diagonal.is_finite() && scene_diagonal > 0.0 { scene_diagonal } else { 10.0 };
    let mfp_step = if max_sigma_t > 0.0 { 0.25 / max_sigma_t } else { f32::INFINITY };
    MarchStep::Length(mfp_step.min(diag / 64.0).max(diag / 4096.0))
}

/// How many times longer the view-ray march step of the interactive
/// integrators (`hegeman`, `zhou`) is in a live viewer's drag frames
/// ([`crate::render::PreparedIntegrator::set_drag_march`]) than in their
/// settings: the march is the largest cost of a drag frame, and it scales
/// with the number of steps. Finished frames march the settings' step.
pub const DRAG_STEP_FACTOR: f32 = 2.0;

/// Jittered steps along the part of a camera-ray segment `[0, t_end]` inside a
/// grid medium's bounds: `n` equal steps (about `step` long, 1 to 4096) with
/// one offset `u` in [0, 1) shared by all, sample `k` at `a + (k + u) dt`.
/// Used by the interactive integrators' view-ray marches.
#[derive(Clone, Copy, Debug)]
pub(crate) struct JitteredSteps {
    /// Start of the clipped segment (ray parameter).
    pub a: f32,
    /// Step length (ray parameter).
    pub dt: f32,
    /// Number of steps.
    pub n: usize,
    /// Offset of the samples within their steps.
    pub u: f32,
}

impl JitteredSteps {
    /// The steps of `ray` within `g`'s bounds up to `t_end`; `None` when the
    /// segment misses the medium.
    pub fn new(
        g: &crate::medium::GridMedium,
        ray: &Ray,
        t_end: f32,
        step: f32,
        sampler: &mut PixelSampler,
    ) -> Option<JitteredSteps> {
        let (a, b) = g.clip(ray, 0.0, t_end)?;
        let n = ((b - a) / step).ceil().clamp(1.0, 4096.0) as usize;
        Some(JitteredSteps { a, dt: (b - a) / n as f32, n, u: sampler.next_1d() })
    }

    /// Ray parameter of sample `k`.
    #[inline]
    pub fn t(&self, k: usize) -> f32 {
        self.a + (k as f32 + self.u) * self.dt
    }
}

/// Distance beyond which an unbounded homogeneous segment contributes less
/// than 1e-6 of its total (transmittance of the least attenuated channel that
/// matters drops below 1e-6); `None` when some channel does not attenuate.
#[inline]
pub(crate) fn negligible_distance(sigma_t: Rgb) -> Option<f32> {
    let min = sigma_t.min_channel();
    if min > 0.0 {
        Some(13.8155 / min)
    } else {
        None
    }
}
