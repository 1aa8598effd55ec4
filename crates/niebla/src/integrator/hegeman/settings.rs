//! Settings of the `hegeman` integrator (`"type": "hegeman"`): its fields
//! in a scene file, their defaults and checks, and their stable key.

use serde::Deserialize;
use serde_json::Value;

use super::{Calibration, HegemanSettings, SurfaceScattering};
use crate::integrator::common_settings::{positive, within};
use crate::integrator::surface_shadows::SurfaceShadows;
use crate::params::{describe, rest, Located, Object};

/// The fields of a `hegeman` object; every one is optional.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HegemanFields {
    /// Calibration of the multiple-scattering term: "none" (default), "mc_tables" or "mc_fluence".
    #[serde(default)]
    calibration: Option<String>,
    /// Photons per Monte Carlo calibration table (1000 to 2^24; default 2^18).
    #[serde(default)]
    calibration_photons: Option<u32>,
    /// Include the multiple-scattering term (default true).
    #[serde(default)]
    multiple_scattering: Option<bool>,
    /// Lattice nodes along a grid medium's longest side (2 to 512; default 48).
    #[serde(default)]
    resolution: Option<u32>,
    /// View-ray march step in lattice cells (> 0; default 1).
    #[serde(default)]
    step_cells: Option<f32>,
    /// How surfaces inside grid media get the model's scattered light:
    /// "cone" (default), "line" or "off"; the booleans keep their meaning
    /// from before the cone model: `true` is "line", `false` "off".
    #[serde(default)]
    surface_scattering: Option<Value>,
    /// Shadows of the medium on surfaces: "lattice_environment" (default:
    /// the model's line integrals toward the lights and the environment's
    /// octant directions), "lattice" (the lights only) or "march".
    #[serde(default)]
    surface_shadows: Option<String>,
}

/// `hegeman`'s settings from its object (the `type` taken out).
pub(crate) fn parse(object: Object) -> Result<HegemanSettings, Located> {
    let fields: HegemanFields = rest(object)?;
    let defaults = HegemanSettings::default();
    let calibration = match fields.calibration.as_deref() {
        None => defaults.calibration,
        Some("mc_tables") => Calibration::McTables,
        Some("mc_fluence") => Calibration::McFluence,
        Some("none") => Calibration::None,
        Some(other) => {
            return Err(Located::new(
                "calibration",
                format!("expected \"mc_tables\", \"mc_fluence\" or \"none\", found \"{other}\""),
            ))
        }
    };
    let surface_scattering = match fields.surface_scattering {
        None => defaults.surface_scattering,
        Some(Value::Bool(true)) => SurfaceScattering::Line,
        Some(Value::Bool(false)) => SurfaceScattering::Off,
        Some(Value::String(name)) if name == "cone" => SurfaceScattering::Cone,
        Some(Value::String(name)) if name == "line" => SurfaceScattering::Line,
        Some(Value::String(name)) if name == "off" => SurfaceScattering::Off,
        Some(other) => {
            let found = match &other {
                Value::String(name) => format!("\"{name}\""),
                v => describe(v).to_string(),
            };
            return Err(Located::new(
                "surface_scattering",
                format!("expected \"cone\", \"line\", \"off\" or a boolean, found {found}"),
            ));
        }
    };
    let surface_shadows = parse_surface_shadows(fields.surface_shadows.as_deref(), defaults.surface_shadows)?;
    let settings = HegemanSettings {
        calibration,
        calibration_photons: fields.calibration_photons.unwrap_or(defaults.calibration_photons),
        multiple_scattering: fields.multiple_scattering.unwrap_or(defaults.multiple_scattering),
        resolution: fields.resolution.unwrap_or(defaults.resolution),
        step_cells: fields.step_cells.unwrap_or(defaults.step_cells),
        surface_scattering,
        surface_shadows,
    };
    within("resolution", settings.resolution, 2, 512)?;
    within("calibration_photons", settings.calibration_photons, 1000, 1 << 24)?;
    positive("step_cells", settings.step_cells)?;
    Ok(settings)
}

/// The `surface_shadows` field of a `hegeman` or `zhou` object (`default` when absent).
pub(crate) fn parse_surface_shadows(name: Option<&str>, default: SurfaceShadows) -> Result<SurfaceShadows, Located> {
    match name {
        None => Ok(default),
        Some(name) => SurfaceShadows::from_name(name).ok_or_else(|| {
            Located::new(
                "surface_shadows",
                format!("expected \"lattice_environment\", \"lattice\" or \"march\", found \"{name}\""),
            )
        }),
    }
}

/// The stable key of `hegeman`'s settings.
pub(crate) fn key(s: &HegemanSettings) -> String {
    format!(
        "hegeman(multiple_scattering={}, resolution={}, step_cells={:?}, calibration={}, calibration_photons={}, \
         surface_scattering={}, surface_shadows={})",
        s.multiple_scattering,
        s.resolution,
        s.step_cells,
        s.calibration.name(),
        s.calibration_photons,
        s.surface_scattering.name(),
        s.surface_shadows.name()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn surface(value: Value) -> SurfaceScattering {
        let mut object = Object::new();
        object.insert("surface_scattering".into(), value);
        parse(object).expect("valid settings").surface_scattering
    }

    /// The booleans written before the cone model keep their meaning
    /// (`true`: the line factor, `false`: direct light only); the default is
    /// the cone.
    #[test]
    fn booleans_keep_their_old_meaning() {
        assert_eq!(surface(Value::Bool(true)), SurfaceScattering::Line);
        assert_eq!(surface(Value::Bool(false)), SurfaceScattering::Off);
        assert_eq!(surface(Value::String("cone".into())), SurfaceScattering::Cone);
        assert_eq!(parse(Object::new()).expect("defaults").surface_scattering, SurfaceScattering::Cone);
    }
}
