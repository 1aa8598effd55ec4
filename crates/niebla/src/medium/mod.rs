//! Participating media: optical coefficients (per unit length) x density,
//! a phase function and emission.
//!
//! Emission follows the lecture's (and pbrt-v2's) convention: `L_ve` is
//! radiance emitted per unit length, not multiplied by `sigma_a`, so the source term is
//! `S = L_ve + sigma_s * integral p L_i`, and a deep purely absorbing emitting
//! medium looks like `L_ve / sigma_a`.

mod grid;
mod homogeneous;
mod pyro;

pub use grid::{
    AlbedoField, AlbedoGrid, DensityGrid, DensityReader, GridEmission, GridField, GridMedium, GridMotion, LazyMinorant,
    MinorantRecipe,
};
pub use homogeneous::HomogeneousMedium;
pub use pyro::{ColorRamp, PyroEmission, PyroTemperature, PYRO_STEFAN_BOLTZMANN};

use crate::color::Rgb;
use crate::math::{Ray, Vec3};
use crate::phase::PhaseFunction;

/// Index of a medium in the scene's medium table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MediumId(pub u32);

/// Optical coefficients at one point (all per unit length).
#[derive(Clone, Copy, Debug, Default)]
pub struct MediumPoint {
    /// Absorption coefficient sigma_a.
    pub sigma_a: Rgb,
    /// Scattering coefficient sigma_s.
    pub sigma_s: Rgb,
    /// Emitted radiance per unit length L_ve.
    pub l_ve: Rgb,
}

impl MediumPoint {
    /// Extinction sigma_t = sigma_a + sigma_s.
    #[inline]
    pub fn sigma_t(&self) -> Rgb {
        self.sigma_a + self.sigma_s
    }
}

/// A closed set of media, dispatched by `match` (no virtual call per sample).
/// A scene holds a handful of media
/// in a table, so the size difference between variants costs nothing.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
pub enum Medium {
    /// Constant coefficients everywhere (unbounded; shapes bound it).
    Homogeneous(HomogeneousMedium),
    /// Coefficients times a voxel density, zero outside the grid's box.
    Grid(GridMedium),
}

impl Medium {
    /// Coefficients at world point `p` (a moving medium at time 0).
    #[inline]
    pub fn at(&self, p: Vec3) -> MediumPoint {
        match self {
            Medium::Homogeneous(m) => m.point(),
            Medium::Grid(m) => m.point(p),
        }
    }

    /// Coefficients at world point `p` at `time` (frames relative to the
    /// rendered frame, a camera sample's
    /// [`crate::sampling::PixelSampler::time`]).
    #[inline]
    pub fn at_time(&self, p: Vec3, time: f32) -> MediumPoint {
        match self {
            Medium::Homogeneous(m) => m.point(),
            Medium::Grid(m) => m.point_at_time(p, time),
        }
    }

    /// The phase function (the same everywhere in the medium).
    #[inline]
    pub fn phase(&self) -> &PhaseFunction {
        match self {
            Medium::Homogeneous(m) => &m.phase,
            Medium::Grid(m) => &m.phase,
        }
    }

    /// Extinction per unit density (the homogeneous medium's own sigma_t).
    #[inline]
    pub fn sigma_t_per_density(&self) -> Rgb {
        match self {
            Medium::Homogeneous(m) => m.sigma_t(),
            Medium::Grid(m) => m.sigma_t(),
        }
    }

    /// Optical depth along `ray` over `[t0, t1]` in closed form, when the medium has one.
    #[inline]
    pub fn exact_optical_depth(&self, _ray: &Ray, t0: f32, t1: f32) -> Option<Rgb> {
        match self {
            Medium::Homogeneous(m) => {
                let length = (t1 - t0).max(0.0);
                // 0 * inf would be NaN: a channel without extinction has zero depth.
                Some(m.sigma_t().map(|s| if s == 0.0 { 0.0 } else { s * length }))
            }
            Medium::Grid(_) => None,
        }
    }

    /// Homogeneous coefficients, if the medium is homogeneous.
    #[inline]
    pub fn as_homogeneous(&self) -> Option<&HomogeneousMedium> {
        match self {
            Medium::Homogeneous(m) => Some(m),
            Medium::Grid(_) => None,
        }
    }

    /// Upper bound of sigma_t over the whole medium (max over channels).
    pub fn max_sigma_t(&self) -> f32 {
        match self {
            Medium::Homogeneous(m) => m.sigma_t().max_channel(),
            Medium::Grid(m) => m.max_sigma_t(),
        }
    }

    /// True if the medium emits anywhere.
    pub fn is_emissive(&self) -> bool {
        match self {
            Medium::Homogeneous(m) => !m.l_ve.is_black(),
            Medium::Grid(m) => !matches!(m.emission, GridEmission::None),
        }
    }
}
