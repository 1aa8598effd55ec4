//! Settings of the `hegeman` integrator (`"type": "hegeman"`): its fields
//! in a scene file, their defaults and checks, and their stable key.

use serde::Deserialize;

use super::HegemanSettings;
use crate::integrator::common_settings::{positive, within};
use crate::params::{rest, Located, Object};

/// The fields of a `hegeman` object; every one is optional.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HegemanFields {
    /// Include the multiple-scattering term (default true).
    #[serde(default)]
    multiple_scattering: Option<bool>,
    /// Lattice nodes along a grid medium's longest side (2 to 512; default 48).
    #[serde(default)]
    resolution: Option<u32>,
    /// View-ray march step in lattice cells (> 0; default 1).
    #[serde(default)]
    step_cells: Option<f32>,
}

/// `hegeman`'s settings from its object (the `type` taken out).
pub(crate) fn parse(object: Object) -> Result<HegemanSettings, Located> {
    let fields: HegemanFields = rest(object)?;
    let defaults = HegemanSettings::default();
    let settings = HegemanSettings {
        multiple_scattering: fields.multiple_scattering.unwrap_or(defaults.multiple_scattering),
        resolution: fields.resolution.unwrap_or(defaults.resolution),
        step_cells: fields.step_cells.unwrap_or(defaults.step_cells),
    };
    within("resolution", settings.resolution, 2, 512)?;
    positive("step_cells", settings.step_cells)?;
    Ok(settings)
}

/// The stable key of `hegeman`'s settings.
pub(crate) fn key(s: &HegemanSettings) -> String {
    format!(
        "hegeman(multiple_scattering={}, resolution={}, step_cells={:?})",
        s.multiple_scattering, s.resolution, s.step_cells
    )
}
