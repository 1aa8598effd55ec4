//! The pyro medium (`"type": "pyro"`): fire and smoke from the grids of one
//! OpenVDB file, with the parameters of Blender's Principled Volume shader.
//!
//! Mapping (Cycles' `node_principled_volume`, Blender 2.8 and later), with
//! `d(x) = density * density_grid(x)`, `c = color`:
//! - scattering `sigma_s = d(x) c`, phase Henyey-Greenstein with
//!   `g = anisotropy`;
//! - absorption `sigma_a = d(x) max(1 - c, 0) max(1 - sqrt(absorption_color), 0)`;
//! - emission, radiance per unit length (not multiplied by the density),
//!   wherever `d(x) > 0`:
//!   `L_ve(x) = emission_strength emission_color ramp(flame(x))`
//!   `+ blackbody_tint (5.670373e-14 / pi) lerp(1, T(x)^4, blackbody_intensity) B(T(x))`,
//!   where `B(T)` is the unit-luminance Rec.709 blackbody color, `T(x) =
//!   temperature * temperature_grid(x) + temperature_offset` Kelvin, the
//!   blackbody term is present only for `blackbody_intensity > 0`, and
//!   `ramp(flame)` is 1 without a flame grid (then the emission is constant
//!   inside the smoke, as in Cycles), the flame value itself (gray) without a
//!   `flame_ramp`, else the ramp's piecewise linear color.

use serde::Deserialize;

use super::{ColorDesc, PhaseDesc, ResolutionDesc, TransformDesc, VelocityUnitsDesc};

/// Grid names read by default for the density, in order of preference:
/// Houdini, Blender (Mantaflow) and EmberGen all write `density`; some
/// exporters write `smoke`.
pub const PYRO_DENSITY_NAMES: &[&str] = &["density", "smoke"];
/// Grid names read by default for the temperature: `temperature` (Houdini,
/// Blender, EmberGen), `heat` (Mantaflow's raw heat grid).
pub const PYRO_TEMPERATURE_NAMES: &[&str] = &["temperature", "heat"];
/// Grid names read by default for the flame: `flame` (Houdini, Blender),
/// `flames` and `fire` (EmberGen and older exporters).
pub const PYRO_FLAME_NAMES: &[&str] = &["flame", "flames", "fire"];

/// Largest temperature (Kelvin) a remapped temperature grid may reach: far
/// above any flame; more means the remap is wrong.
pub const PYRO_MAX_KELVIN: f32 = 100_000.0;

/// A pyro medium (see the module docs for the mapping of each parameter).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PyroMediumDesc {
    /// The OpenVDB file holding the grids, relative to the scene file.
    pub file: String,
    /// Density multiplier (Blender's Density), finite and >= 0; default 1.
    #[serde(default = "one")]
    pub density: f32,
    /// Density grid name; default the first of [`PYRO_DENSITY_NAMES`] in the file.
    #[serde(default)]
    pub density_attribute: Option<String>,
    /// Scattering color, each channel in [0, 1]; default 0.5.
    #[serde(default = "half_gray")]
    pub color: ColorDesc,
    /// Absorption color, each channel in [0, 1]; default 0 (black).
    #[serde(default = "black")]
    pub absorption_color: ColorDesc,
    /// Henyey-Greenstein asymmetry in (-1, 1); default 0.
    #[serde(default)]
    pub anisotropy: f32,
    /// Emission strength, finite and >= 0; default 0.
    #[serde(default)]
    pub emission_strength: f32,
    /// Emission color, finite and >= 0; default 1.
    #[serde(default = "white")]
    pub emission_color: ColorDesc,
    /// Flame grid that modulates the emission; default the first of
    /// [`PYRO_FLAME_NAMES`] in the file when `emission_strength > 0`; `""`
    /// for none.
    #[serde(default)]
    pub flame_attribute: Option<String>,
    /// Color ramp of the flame value: `[[position, color], ...]` with
    /// increasing positions; clamped outside. Default: the flame value as gray.
    #[serde(default)]
    pub flame_ramp: Option<Vec<(f32, ColorDesc)>>,
    /// Blackbody intensity in [0, 1] (1 = physically based intensity); default 0.
    #[serde(default)]
    pub blackbody_intensity: f32,
    /// Blackbody tint, finite and >= 0; default 1.
    #[serde(default = "white")]
    pub blackbody_tint: ColorDesc,
    /// Temperature in Kelvin, or the multiplier of the temperature grid
    /// (Blender's Temperature); finite and > 0; default 1000.
    #[serde(default = "default_temperature")]
    pub temperature: f32,
    /// Kelvin added after the multiplication (a linear remap of raw
    /// simulation temperatures, `T = temperature * grid + offset`); default 0.
    #[serde(default)]
    pub temperature_offset: f32,
    /// Temperature grid name; default the first of
    /// [`PYRO_TEMPERATURE_NAMES`] in the file when `blackbody_intensity > 0`;
    /// `""` for a constant temperature.
    #[serde(default)]
    pub temperature_attribute: Option<String>,
    /// Places the grids' world space in the scene; default identity.
    #[serde(default)]
    pub to_world: TransformDesc,
    /// Majorant cell budget, as for a grid medium.
    #[serde(default)]
    pub majorant_resolution: Option<ResolutionDesc>,
    /// Name of a Vec3 velocity grid in the file, for Eulerian motion blur
    /// (as a grid medium's `velocity`; Mantaflow and Houdini call it
    /// `vel`); default none: the medium does not move.
    #[serde(default)]
    pub velocity: Option<String>,
    /// Units of the velocity grid, as a grid medium's; default
    /// `world_per_second`.
    #[serde(default)]
    pub velocity_units: VelocityUnitsDesc,
    /// The phase function implied by `anisotropy` (filled in by the parser).
    #[serde(skip)]
    pub phase: PhaseDesc,
}

fn one() -> f32 {
    1.0
}
fn half_gray() -> ColorDesc {
    ColorDesc::Gray(0.5)
}
fn black() -> ColorDesc {
    ColorDesc::Gray(0.0)
}
fn white() -> ColorDesc {
    ColorDesc::Gray(1.0)
}
fn default_temperature() -> f32 {
    1000.0
}
