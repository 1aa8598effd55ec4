//! Integrators: each computes the radiance arriving at the camera along one
//! camera ray ([`Integrator`]). Which ones exist, their settings and the one
//! `match` over their kinds are in [`registry`]; the render loop is
//! monomorphized over the chosen type, so the per-sample path has no virtual
//! call.

mod analytic;
mod camera_layout;
mod camera_ray;
mod common_settings;
mod direct;
mod emission_absorption;
mod equiangular;
pub mod hegeman;
mod march;
pub mod photon;
mod precompute_memory;
pub mod registry;
mod single;
pub mod surface_shadows;
mod volpath;
mod volume_lights;
pub mod zhou;

pub use analytic::airlight::{airlight_integral, airlight_table, AirlightTable};
pub use analytic::AnalyticIntegrator;
pub use camera_ray::SegmentRadiance;
pub(crate) use camera_ray::{trace_laid_out_camera_ray, walk_camera_ray, CameraRayVisitor};
pub use common_settings::DEFAULT_TRANSMITTANCE_STEPS;
pub use direct::{direct_surface_radiance, in_scattered_radiance, light_in_scattered_radiance};
pub use emission_absorption::EmissionIntegrator;
pub use hegeman::{HegemanIntegrator, HegemanSettings};
pub use march::default_march_step;
pub use march::DRAG_STEP_FACTOR;
pub(crate) use march::{negligible_distance, JitteredSteps};
pub use precompute_memory::{precompute_memory, PrecomputeMemory};
pub use registry::{IntegratorSettings, PreparedIntegrator};
pub use single::{SingleIntegrator, SingleSampling};
pub use surface_shadows::SurfaceShadows;
pub use volpath::{
    VolPathIntegrator, DEFAULT_DISTANCE_MIXTURE, DEFAULT_EMITTER_GUIDE_FRACTION, DEFAULT_GUIDE_FRACTION,
    DEFAULT_POINT_GUIDE_FRACTION,
};
pub use volume_lights::{majorant_at, VolumeLightSample, VolumeLights};
pub use zhou::{ZhouIntegrator, ZhouSettings};

use crate::color::Rgb;
use crate::math::Ray;
use crate::medium::MediumId;
use crate::sampling::PixelSampler;
use crate::world::Scene;

/// Radiance along a camera ray.
pub trait Integrator: Sync {
    /// Radiance (W/(sr m^2)) arriving at `ray.o` from direction `-ray.d`, for a
    /// ray that starts inside `medium`.
    fn radiance(&self, scene: &Scene, ray: Ray, medium: Option<MediumId>, sampler: &mut PixelSampler) -> Rgb;

    /// [`Integrator::radiance`] split by path class for the layers of
    /// `crate::aov` (its `total` is the same sample, bit for bit);
    /// integrators that do not classify their paths give the total alone.
    fn radiance_split(
        &self,
        scene: &Scene,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut PixelSampler,
    ) -> crate::aov::LayerSplit {
        crate::aov::LayerSplit::unsplit(self.radiance(scene, ray, medium, sampler))
    }
}
