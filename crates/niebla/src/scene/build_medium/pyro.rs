//! Building a pyro medium (`"type": "pyro"`): its grids found in one VDB
//! file by the names given or the exporters' usual names, the Principled
//! Volume parameters turned into the grid medium's coefficients, and the
//! pyro emission.
//!
//! Grids on different transforms (a temperature grid at half the density's
//! resolution, say) are each looked up through their own index-to-world map,
//! i.e. resampled trilinearly at every point; nothing is refused for that.
//! A grid of the wrong type (a Vec3 grid named as the temperature) is an
//! error naming the file, the grid and the field.

use std::path::Path;
use std::sync::Arc;

use niebla_volume::VdbValueKind;

use super::{build_grid_medium, FieldKind, Loader};
use crate::color::{BlackbodyTable, Rgb};
use crate::medium::{ColorRamp, GridEmission, GridField, GridMedium, PyroEmission, PyroTemperature};
use crate::phase::PhaseFunction;
use crate::scene::desc::*;
use crate::scene::SceneError;

/// The grid medium of a pyro description.
pub(super) fn build_pyro_medium(
    desc: &PyroMediumDesc,
    path: &str,
    loader: &mut Loader,
    phase: PhaseFunction,
) -> Result<GridMedium, SceneError> {
    let file = loader.base_dir.join(&desc.file);
    let names = loader.vdb_grid_kinds(&format!("{path}.file"), &file)?;

    let density_at = format!("{path}.density_attribute");
    let density_name = pick(loader, &density_at, &file, &names, desc.density_attribute.as_deref(), PYRO_DENSITY_NAMES)?
        .ok_or_else(|| loader.error(&density_at, format!("{}: a pyro medium needs a density grid", file.display())))?;

    // Principled Volume's coefficients per unit of the density grid.
    let c = desc.color.to_rgb();
    let a = desc.absorption_color.to_rgb();
    let sigma_s = c * desc.density;
    let sigma_a = c.map(|v| (1.0 - v).max(0.0)) * a.map(|v| (1.0 - v.max(0.0).sqrt()).max(0.0)) * desc.density;
    let grid_desc = GridMediumDesc {
        coefficients: CoefficientsDesc::AbsorptionScattering {
            sigma_a: ColorDesc::Rgb(sigma_a.0),
            sigma_s: ColorDesc::Rgb(sigma_s.0),
        },
        scale: 1.0,
        phase: desc.phase.clone(),
        density: vdb_source(desc, &density_name),
        to_world: desc.to_world,
        emission: None,
        majorant_resolution: desc.majorant_resolution,
        storage: GridStorageDesc::F32,
        velocity: desc.velocity.clone(),
        velocity_units: desc.velocity_units,
        albedo_grid: None,
        albedo_to_world: None,
    };
    // The density is read under `density_attribute`, so errors point there.
    let mut medium = build_grid_medium(&grid_desc, path, loader, phase).map_err(|mut e| {
        if e.path == format!("{path}.density.grid") || e.path == format!("{path}.density.file") {
            e.path = density_at.clone();
        }
        e
    })?;
    let to_world = super::build_transform(&desc.to_world).expect("checked by build_grid_medium").to_world;

    let emission =
        if desc.emission_strength > 0.0 { desc.emission_color.to_rgb() * desc.emission_strength } else { Rgb::ZERO };
    let flame = if emission.is_black() {
        None
    } else {
        let at = format!("{path}.flame_attribute");
        match pick(loader, &at, &file, &names, desc.flame_attribute.as_deref(), PYRO_FLAME_NAMES)? {
            None => None,
            Some(name) => {
                let field = loader.field(&at, &vdb_source(desc, &name), FieldKind::Emission, &to_world)?;
                let ramp = desc
                    .flame_ramp
                    .as_ref()
                    .map(|stops| ColorRamp { stops: stops.iter().map(|(x, c)| (*x, c.to_rgb())).collect() });
                Some((field, ramp))
            }
        }
    };

    let mut temperature = PyroTemperature { field: None, scale: desc.temperature, offset: desc.temperature_offset };
    if desc.blackbody_intensity > 0.0 {
        let at = format!("{path}.temperature_attribute");
        if let Some(name) =
            pick(loader, &at, &file, &names, desc.temperature_attribute.as_deref(), PYRO_TEMPERATURE_NAMES)?
        {
            let field = loader.field(&at, &vdb_source(desc, &name), FieldKind::Temperature, &to_world)?;
            check_remap(loader, &at, &file, &name, &field, &temperature)?;
            temperature.field = Some(field);
        }
    }

    let pyro = PyroEmission {
        emission,
        flame,
        blackbody_intensity: desc.blackbody_intensity,
        blackbody_tint: desc.blackbody_tint.to_rgb(),
        temperature,
        table: Arc::new(BlackbodyTable::new()),
    };
    if !pyro.is_black() {
        medium.emission = GridEmission::Pyro(Box::new(pyro));
    }
    Ok(medium)
}

/// A `vdb` source for grid `name` of the pyro file.
fn vdb_source(desc: &PyroMediumDesc, name: &str) -> DensitySourceDesc {
    DensitySourceDesc::Vdb { file: desc.file.clone(), grid: name.to_string() }
}

/// The grid to read for one attribute: the name given (`""`: none), else
/// the first of `defaults` that the file holds as a scalar grid.
fn pick(
    loader: &Loader,
    at: &str,
    file: &Path,
    names: &[(String, VdbValueKind)],
    given: Option<&str>,
    defaults: &[&str],
) -> Result<Option<String>, SceneError> {
    match given {
        Some("") => Ok(None),
        Some(name) => {
            // Named grids must exist and be scalar; say which of the file's
            // grids could be meant.
            match names.iter().find(|(n, _)| n == name) {
                None => Err(loader
                    .error(at, format!("{}: no grid named {name:?}; the file has {}", file.display(), list(names)))),
                Some((_, kind)) if !kind.is_scalar() => Err(loader.error(
                    at,
                    format!(
                        "{}: grid {name:?} is a {} grid, expected a scalar float grid for this field",
                        file.display(),
                        kind_name(*kind)
                    ),
                )),
                Some(_) => Ok(Some(name.to_string())),
            }
        }
        None => {
            Ok(defaults.iter().find(|d| names.iter().any(|(n, k)| n == *d && k.is_scalar())).map(|d| d.to_string()))
        }
    }
}

fn kind_name(kind: VdbValueKind) -> &'static str {
    match kind {
        VdbValueKind::Float => "float",
        VdbValueKind::Double => "double",
        VdbValueKind::Vec3Float => "Vec3 (vec3s)",
        VdbValueKind::Vec3Double => "Vec3 (vec3d)",
        VdbValueKind::Other => "non-float",
    }
}

fn list(names: &[(String, VdbValueKind)]) -> String {
    let v: Vec<String> = names.iter().map(|(n, k)| format!("{n:?} ({})", kind_name(*k))).collect();
    v.join(", ")
}

/// Refuses a temperature remap that sends the grid's values below 0 K or
/// above [`PYRO_MAX_KELVIN`].
fn check_remap(
    loader: &Loader,
    at: &str,
    file: &Path,
    grid: &str,
    field: &GridField,
    t: &PyroTemperature,
) -> Result<(), SceneError> {
    let max = field.grid.max_value();
    let hottest = t.scale * max + t.offset;
    let coldest = t.offset; // grids hold values >= 0 (checked when read)
    if !(hottest <= PYRO_MAX_KELVIN) || coldest < 0.0 {
        return Err(loader.error(
            at,
            format!(
                "{}: grid {grid:?}: temperature = {} x value + {} reaches {hottest} K (largest value {max}) \
                 and {coldest} K: expected 0 to {PYRO_MAX_KELVIN} K; check `temperature` and `temperature_offset`",
                file.display(),
                t.scale,
                t.offset
            ),
        ));
    }
    Ok(())
}
