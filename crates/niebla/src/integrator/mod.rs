//! Integrators: each computes the radiance arriving at the camera along one
//! camera ray. They are selected once per render (a `match` on
//! [`IntegratorSettings`]) and the render loop is monomorphized over the chosen
//! type, so the per-sample path has no virtual call.

mod analytic;
mod camera_ray;
mod direct;
mod emission_absorption;
mod equiangular;
pub mod hegeman;
pub mod photon;
mod precompute_memory;
mod single;
mod volpath;
pub mod zhou;

pub use analytic::airlight::{airlight_integral, airlight_table, AirlightTable};
pub use analytic::AnalyticIntegrator;
pub use camera_ray::SegmentRadiance;
pub(crate) use camera_ray::{trace_camera_ray, walk_camera_ray, CameraRayVisitor};
pub use direct::{direct_surface_radiance, in_scattered_radiance, light_in_scattered_radiance};
pub use emission_absorption::EmissionIntegrator;
pub use hegeman::{HegemanIntegrator, HegemanSettings};
pub use precompute_memory::{precompute_memory, PrecomputeMemory};
pub use single::{SingleIntegrator, SingleSampling};
pub use volpath::{VolPathIntegrator, DEFAULT_GUIDE_FRACTION};
pub use zhou::{ZhouIntegrator, ZhouSettings};

use crate::color::Rgb;
use crate::math::Ray;
use crate::medium::MediumId;
use crate::sampling::PixelSampler;
use crate::scene::Scene;
use crate::tracking::{MarchStep, TransmittanceMethod};

/// Radiance along a camera ray.
pub trait Integrator: Sync {
    /// Radiance (W/(sr m^2)) arriving at `ray.o` from direction `-ray.d`, for a
    /// ray that starts inside `medium`.
    fn radiance(&self, scene: &Scene, ray: Ray, medium: Option<MediumId>, sampler: &mut PixelSampler) -> Rgb;
}

/// Which integrator to run and its parameters (built from the scene file and
/// command-line overrides).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IntegratorSettings {
    /// Emission and absorption only (no in-scattering); surfaces lit directly.
    Emission {
        /// Ray-march step for the emission integral; `None` picks a default per medium.
        step: Option<MarchStep>,
        /// Transmittance estimator.
        transmittance: TransmittanceMethod,
    },
    /// Single scattering with shadow rays to every light; surfaces lit directly.
    Single {
        /// Ray-march step along the camera ray; `None` picks a default per medium.
        step: Option<MarchStep>,
        /// How scattering points along the camera ray are chosen.
        sampling: SingleSampling,
        /// Transmittance estimator.
        transmittance: TransmittanceMethod,
    },
    /// Unbiased volumetric path tracing (multiple scattering).
    VolPath {
        /// Largest number of scattering events on a path.
        max_depth: u32,
    },
    /// Closed-form single scattering (Sun et al. 2005) in homogeneous media
    /// from point and spot lights; surfaces lit directly.
    Analytic,
    /// Single scattering plus the blurred multiple-scattering approximation
    /// of Hegeman et al. 2005 (reconstructed), with per-light precomputed
    /// volumes; interactive.
    Hegeman(hegeman::HegemanSettings),
    /// Compensated ray marching (Zhou et al. 2008, reconstructed): RBF
    /// density fit, SH environment lighting, diffusion, residual compensated
    /// along view rays; interactive.
    Zhou(zhou::ZhouSettings),
    /// Volumetric photon mapping (Jensen and Christensen 1998): one photon
    /// map per render, single scattering by shadow rays.
    Photon(photon::PhotonSettings),
    /// Progressive photon mapping (Knaus and Zwicker 2011): one photon map
    /// and a smaller radius per sample index; converges to `volpath`.
    Ppm(photon::PpmSettings),
}

impl IntegratorSettings {
    /// The name used on the command line and in scene files.
    pub fn name(&self) -> &'static str {
        match self {
            IntegratorSettings::Emission { .. } => "emission",
            IntegratorSettings::Single { .. } => "single",
            IntegratorSettings::VolPath { .. } => "volpath",
            IntegratorSettings::Analytic => "analytic",
            IntegratorSettings::Hegeman(_) => "hegeman",
            IntegratorSettings::Zhou(_) => "zhou",
            IntegratorSettings::Photon(_) => "photon",
            IntegratorSettings::Ppm(_) => "ppm",
        }
    }

    /// Names of all integrators that can be selected.
    pub const NAMES: &'static [&'static str] =
        &["emission", "single", "volpath", "analytic", "photon", "ppm", "hegeman", "zhou"];

    /// Default path depth of `volpath`: deep enough for dense albedo-0.99 media.
    pub const DEFAULT_MAX_DEPTH: u32 = 1024;
}

/// Ray-march step used when a scene gives none: a quarter of the mean free
/// path of the densest channel, but never coarser than 1/64 of the scene
/// diagonal and at most 4096 steps over the diagonal.
pub fn default_march_step(max_sigma_t: f32, scene_diagonal: f32) -> MarchStep {
    let diag = if scene_diagonal.is_finite() && scene_diagonal > 0.0 { scene_diagonal } else { 10.0 };
    let mfp_step = if max_sigma_t > 0.0 { 0.25 / max_sigma_t } else { f32::INFINITY };
    MarchStep::Length(mfp_step.min(diag / 64.0).max(diag / 4096.0))
}

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
