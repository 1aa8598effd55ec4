//! Volumetric photon mapping (Jensen and Christensen 1998), its progressive
//! and consistent form (Knaus and Zwicker 2011) and the beam radiance
//! estimate (Jarosz, Zwicker and Jensen 2008).
//!
//! - [`trace_photons`]: photons from every light through media and surfaces
//!   with `volpath`'s free-flight code; stored at real scattering events in
//!   media (volume map) and at diffuse surfaces (surface map), direct
//!   photons excluded (see `trace.rs` for the storage rule).
//! - [`PhotonTree`]: a balanced kd-tree answering radius, k-nearest and
//!   ray-segment (beam) queries.
//! - [`PhotonIntegrator`]: camera rays through media and specular surfaces.
//!   Each medium segment gets emission and single scattering from
//!   [`SingleIntegrator`](crate::integrator::single::SingleIntegrator) (shadow rays, equiangular/distance MIS), plus
//!   multiple scattering from the volume map: ray marched point queries
//!   `sum p(wo, wi_k) Phi_k / (4/3 pi r^3)` at stratified points times the
//!   transmittance, or one beam query `sum T(t_k) p Phi_k / (pi r_k^2)`. At
//!   the first diffuse surface: direct light by shadow rays plus the surface
//!   map's `sum f Phi_k / (pi r^2)` (indirect light and caustics).
//! - `photon`: one photon map for the whole render ([`render_photon`]);
//!   `ppm`: one photon map per pass (sample index) with a radius that
//!   shrinks as `r_{i+1}^d = r_i^d (i + alpha) / (i + 1)`, `d = 3` for
//!   point queries and `d = 2` for beam and surface queries; the image is
//!   the mean over passes ([`render_ppm`]). Bias and variance both vanish as
//!   passes grow, so `ppm` converges to the `volpath` image.
//!
//! Determinism: photon `i` of pass `s` draws from a stream keyed by
//! `(seed, s, i)` and maps are concatenated in a fixed order, so both
//! integrators give the same image for any thread count.
//!
//! `ppb` (progressive photon beams, Jarosz et al. 2011) stores the free
//! flights of the same photons as beams and queries them with the beam x
//! beam 1D estimate along camera rays ([`render_ppb`]; `beams.rs`, `ppb.rs`).
//!
//! Light emitted by media (`L_ve`) is seen along camera rays by the
//! single-scattering code and scattered by photons emitted from the media
//! ([`Emitters`]).

mod beams;
mod emitters;
mod estimate;
mod kdtree;
mod maps;
mod passes;
mod ppb;
pub(crate) mod settings;
mod stored;
mod trace;

pub use beams::{beams_supported, Beam, BeamMap, Crossing};
pub use ppb::{beam_estimate, ppb_radius_factor, render_ppb, BeamIntegrator, PpbSettings};

pub use emitters::Emitters;
pub use estimate::{Kernel, PhotonIntegrator};
pub use kdtree::{Neighbor, PhotonTree};
pub use maps::{auto_radius, PhotonMaps};
pub use passes::{ppm_radius_factor, render_photon, render_ppm};
pub use stored::{pack_normal, unpack_normal, Photon};
pub use trace::{
    photon_stream, trace_beams_with, trace_photons, trace_photons_with, TraceSettings, TraceStats, TracedPhotons,
};

use super::SingleSampling;
use crate::tracking::MarchStep;

/// How many photons a density estimate uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotonGather {
    /// The `k` nearest photons (within the radius cap); the estimate divides
    /// by the volume (area) of the sphere (disk) through the k-th.
    Nearest(u32),
    /// Every photon within a fixed radius.
    Radius,
}

/// How camera rays query the volume photon map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeQuery {
    /// Point queries at ray-marched points (3D kernel `1 / (4/3 pi r^3)`).
    March,
    /// One beam query per medium segment (2D kernel `1 / (pi r^2)`).
    Beam,
}

/// Parameters of the `photon` integrator (and of each `ppm` pass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonSettings {
    /// Photons emitted (per pass for `ppm`), >= 1.
    pub photons: u32,
    /// Nearest-neighbour or fixed-radius gathering (`ppm` always uses the radius).
    pub gather: PhotonGather,
    /// Volume gather radius in scene units (> 0): the fixed radius, the cap
    /// of k-nearest searches, or `ppm`'s initial radius. `None`: the median
    /// distance from a stored photon to its 50th nearest neighbour (capped
    /// at 1/16 of the scene diagonal for k-nearest searches).
    pub radius: Option<f32>,
    /// Surface gather radius, same rules as `radius`.
    pub surface_radius: Option<f32>,
    /// Ray-march step of point queries; `None` picks the default of `single`.
    pub step: Option<MarchStep>,
    /// Point queries or beam queries.
    pub query: VolumeQuery,
    /// Sampling of single scattering along camera rays.
    pub sampling: SingleSampling,
    /// Largest number of scattering events on a photon path (>= 1).
    pub max_depth: u32,
    /// Store direct photons too (double counts direct light; for tests).
    pub store_direct: bool,
}

impl PhotonSettings {
    /// Photons per render of the `photon` integrator by default.
    pub const DEFAULT_PHOTONS: u32 = 200_000;
    /// Photons per pass of `ppm` by default.
    pub const DEFAULT_PPM_PHOTONS: u32 = 20_000;
    /// Neighbours of a k-nearest estimate by default.
    pub const DEFAULT_K: u32 = 50;

    /// Defaults of the `photon` integrator.
    ///
    /// ```
    /// use niebla::integrator::photon::{PhotonGather, PhotonSettings};
    /// assert_eq!(PhotonSettings::photon().gather, PhotonGather::Nearest(50));
    /// ```
    pub fn photon() -> PhotonSettings {
        PhotonSettings {
            photons: Self::DEFAULT_PHOTONS,
            gather: PhotonGather::Nearest(Self::DEFAULT_K),
            radius: None,
            surface_radius: None,
            step: None,
            query: VolumeQuery::March,
            sampling: SingleSampling::Mis,
            max_depth: super::IntegratorSettings::DEFAULT_MAX_DEPTH,
            store_direct: false,
        }
    }

    /// Defaults of one `ppm` pass.
    pub fn ppm() -> PhotonSettings {
        PhotonSettings { photons: Self::DEFAULT_PPM_PHOTONS, gather: PhotonGather::Radius, ..Self::photon() }
    }
}

/// Parameters of the `ppm` integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PpmSettings {
    /// Settings of each pass (`radius` is the initial radius).
    pub photon: PhotonSettings,
    /// Radius reduction `alpha` in (0, 1) (Knaus and Zwicker's; 2/3 by default).
    pub alpha: f32,
}

impl PpmSettings {
    /// Default `alpha`.
    pub const DEFAULT_ALPHA: f32 = 2.0 / 3.0;
}

impl Default for PpmSettings {
    fn default() -> PpmSettings {
        PpmSettings { photon: PhotonSettings::ppm(), alpha: Self::DEFAULT_ALPHA }
    }
}
