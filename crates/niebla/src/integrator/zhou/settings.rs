//! Settings of the `zhou` integrator (`"type": "zhou"`): its fields in a
//! scene file, their defaults and checks, and their stable key.

use serde::Deserialize;

use super::{Compensation, LocalLights, ZhouSettings};
use crate::integrator::common_settings::{positive, within};
use crate::params::{rest, Located, Object};

/// `compensation`: how the residual enters the view-ray march.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
enum CompensationField {
    /// The full density for source and attenuation.
    Full,
    /// The full density for the source, the RBF density for attenuation.
    Source,
    /// The RBF density everywhere.
    Off,
}

/// `transmittance`: transmittance toward the environment at the RBF centres.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
enum TransmittanceField {
    /// Rotated zonal optical-depth table.
    Sh,
    /// Closed form per quadrature direction.
    Exact,
}

/// `local_lights`: how point and spot lights light the model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
enum LocalLightsField {
    /// Transmittance from the RBF density at the centres, diffusion.
    Rbf,
    /// The calibrated `hegeman` light model.
    Hegeman,
}

/// The fields of a `zhou` object; every one is optional.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ZhouFields {
    /// RBFs per grid medium (1 to 20000; default 600).
    #[serde(default)]
    rbf_count: Option<u32>,
    /// L-BFGS iterations of the fit (0 to 10000; default 60).
    #[serde(default)]
    fit_iterations: Option<u32>,
    /// Lattice nodes along a grid medium's longest side (4 to 128; default
    /// 48). Memory grows as its cube: about 0.5 KiB per node at `sh_order` 4
    /// during the precomputation.
    #[serde(default)]
    resolution: Option<u32>,
    /// SH order of lighting and source radiance (1 to 6; default 4).
    #[serde(default)]
    sh_order: Option<u32>,
    /// Include the diffusion term (default true).
    #[serde(default)]
    multiple_scattering: Option<bool>,
    /// `"full"` (default), `"source"` or `"off"`.
    #[serde(default)]
    compensation: Option<CompensationField>,
    /// `"sh"` (default) or `"exact"`.
    #[serde(default)]
    transmittance: Option<TransmittanceField>,
    /// View-ray march step in lattice cells (> 0; default 1).
    #[serde(default)]
    step_cells: Option<f32>,
    /// Read and write RBF fits in the cache folder (default true).
    #[serde(default)]
    cache: Option<bool>,
    /// `"hegeman"` (default) or `"rbf"`: point and spot lights.
    #[serde(default)]
    local_lights: Option<LocalLightsField>,
    /// Shadows of the medium on surfaces: "lattice_environment" (default:
    /// line integrals toward each light and the environment's octant
    /// directions), "lattice" (the lights only) or "march".
    #[serde(default)]
    surface_shadows: Option<String>,
}

/// `zhou`'s settings from its object (the `type` taken out).
pub(crate) fn parse(object: Object) -> Result<ZhouSettings, Located> {
    let f: ZhouFields = rest(object)?;
    let d = ZhouSettings::default();
    let settings = ZhouSettings {
        rbf_count: f.rbf_count.unwrap_or(d.rbf_count),
        fit_iterations: f.fit_iterations.unwrap_or(d.fit_iterations),
        resolution: f.resolution.unwrap_or(d.resolution),
        sh_order: f.sh_order.unwrap_or(d.sh_order),
        multiple_scattering: f.multiple_scattering.unwrap_or(d.multiple_scattering),
        compensation: match f.compensation {
            None => d.compensation,
            Some(CompensationField::Full) => Compensation::Full,
            Some(CompensationField::Source) => Compensation::SourceOnly,
            Some(CompensationField::Off) => Compensation::Off,
        },
        exact_transmittance: f.transmittance.map_or(d.exact_transmittance, |t| t == TransmittanceField::Exact),
        step_cells: f.step_cells.unwrap_or(d.step_cells),
        cache: f.cache.unwrap_or(d.cache),
        local_lights: match f.local_lights {
            None => d.local_lights,
            Some(LocalLightsField::Rbf) => LocalLights::Rbf,
            Some(LocalLightsField::Hegeman) => LocalLights::Hegeman,
        },
        surface_shadows: crate::integrator::hegeman::settings::parse_surface_shadows(
            f.surface_shadows.as_deref(),
            d.surface_shadows,
        )?,
    };
    within("rbf_count", settings.rbf_count, 1, 20_000)?;
    within("fit_iterations", settings.fit_iterations, 0, 10_000)?;
    within("resolution", settings.resolution, 4, 128)?;
    within("sh_order", settings.sh_order, 1, 6)?;
    positive("step_cells", settings.step_cells)?;
    Ok(settings)
}

/// The stable key of `zhou`'s settings.
pub(crate) fn key(s: &ZhouSettings) -> String {
    format!(
        "zhou(rbf_count={}, fit_iterations={}, resolution={}, sh_order={}, multiple_scattering={}, \
         compensation={}, transmittance={}, step_cells={:?}, cache={}, local_lights={}, surface_shadows={})",
        s.rbf_count,
        s.fit_iterations,
        s.resolution,
        s.sh_order,
        s.multiple_scattering,
        s.compensation.name(),
        if s.exact_transmittance { "exact" } else { "sh" },
        s.step_cells,
        s.cache,
        s.local_lights.name(),
        s.surface_shadows.name()
    )
}
