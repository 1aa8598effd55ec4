//! Reading a scene file into a [`SceneDesc`], with errors that name the JSON
//! path of the offending value.
//!
//! Steps: the text is parsed into a `serde_json::Value` (syntax errors carry
//! line and column); the top level and `version` are checked; a small scanner
//! rejects duplicate keys (which `serde_json` would silently collapse); then
//! the value is deserialized with `serde_path_to_error`, and the result is
//! validated.
//!
//! Why the tagged types (`type` fields) have hand-written `Deserialize`
//! implementations: serde's internally tagged enums buffer their content, so
//! `serde_path_to_error` loses the path inside them (an error in
//! `lights[1].intensity[2]` would be reported at `lights[1]`), and
//! `deny_unknown_fields` does not work reliably on their variants. Instead each
//! tagged object is read into a `serde_json::Map`, the `type` is taken out, and
//! the rest is deserialized into a plain `deny_unknown_fields` struct with its
//! own `serde_path_to_error` tracking. The inner error's path travels out
//! inside the serde error message (see [`Located::into_serde`]) and is joined
//! to the outer path, so every error carries its full path.

use std::path::Path;

use serde::de::Deserializer;
use serde::Deserialize;
use serde_json::Value;

use super::desc::*;
use super::error::{byte_offset, find_duplicate_key, path_at, SceneError};
use crate::params::{describe, read_object, rest, take, take_tag, unknown_type, Located, Object};

/// Parses and validates a scene from JSON text.
///
/// `source` is the file name shown in error messages (for example the path
/// the text came from, or `<stdin>`). Relative paths inside the scene (such as
/// a tabulated phase function's `file`) are kept as written; they resolve
/// against the scene file's folder when the scene is built.
///
/// ```
/// use niebla::scene::parse_scene_str;
/// let err = parse_scene_str(r#"{"version": 1, "camera": {"type": "perspective",
///     "position": [0, 0, 5], "target": [0, 0, 0], "width": 64, "height": 64},
///     "media": {"fog": {"sigma_a": 0.1, "sigam_s": 1}}}"#, "fog.json").unwrap_err();
/// assert_eq!(err.path, "media.fog.sigam_s");
/// assert!(err.to_string().starts_with("fog.json: media.fog.sigam_s: unknown field `sigam_s`"));
/// ```
pub fn parse_scene_str(text: &str, source: &str) -> Result<SceneDesc, SceneError> {
    parse_scene_value(text, source, None, false).map(|(desc, _)| desc)
}

/// Parses and validates the scene of `frame` of a sequence from JSON text
/// (see [`super::frames`]): keyframed cameras and lights at that frame, the
/// frame patterns of `file` fields replaced. With `None`, the same as
/// [`parse_scene_str`]. Also returns the scene value the description was
/// read from (keyframes removed, frame patterns replaced).
///
/// ```
/// use niebla::scene::{parse_scene_frame, CameraDesc};
/// let text = r#"{"version": 1, "camera": {"type": "perspective", "position": [0, 0, 5],
///     "target": [0, 0, 0], "width": 8, "height": 8,
///     "keyframes": [{"frame": 1, "position": [0, 0, 5]}, {"frame": 5, "position": [4, 0, 5]}]}}"#;
/// let (desc, _) = parse_scene_frame(text, "turn.json", Some(2)).unwrap();
/// let CameraDesc::Perspective(camera) = &desc.camera;
/// assert_eq!(camera.position, [1.0, 0.0, 5.0]);
/// ```
pub fn parse_scene_frame(
    text: &str,
    source: &str,
    frame: Option<super::frames::FrameNumber>,
) -> Result<(SceneDesc, Value), SceneError> {
    parse_scene_value(text, source, frame, true)
}

/// The steps of [`parse_scene_frame`]; the value returned is `Null` unless
/// `keep_value`.
fn parse_scene_value(
    text: &str,
    source: &str,
    frame: Option<super::frames::FrameNumber>,
    keep_value: bool,
) -> Result<(SceneDesc, Value), SceneError> {
    let mut value: Value = serde_json::from_str(text).map_err(|e| json_syntax_error(text, source, &e))?;
    check_top_level(&value, source)?;
    if let Some((path, key)) = find_duplicate_key(text) {
        return Err(SceneError::new(
            source,
            path,
            format!("duplicate key `{key}`; each key may appear once per object"),
        ));
    }
    super::frames::resolve_frame(&mut value, source, frame, &|v| desc_from_value(v, source).map(|_| ()))?;
    if keep_value {
        Ok((desc_from_value(value.clone(), source)?, value))
    } else {
        Ok((desc_from_value(value, source)?, Value::Null))
    }
}

/// Deserializes and validates a scene value whose top level was checked.
fn desc_from_value(value: Value, source: &str) -> Result<SceneDesc, SceneError> {
    let desc: SceneDesc = serde_path_to_error::deserialize(value).map_err(|e| {
        let located = Located::from_path_error(e);
        SceneError::new(source, located.path, located.message)
    })?;
    desc.validate(source)?;
    Ok(desc)
}

/// Reads, parses and validates a scene file. Errors name the file as
/// `path.display()` shows it, including errors reading it.
pub fn load_scene_file(path: &Path) -> Result<SceneDesc, SceneError> {
    let source = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::new(&source, "", format!("cannot read scene file: {e}")))?;
    parse_scene_str(&text, &source)
}

/// The error for text that is not valid JSON. A number too large for a
/// 64-bit float also lands here; for it the scanner finds the JSON path.
fn json_syntax_error(text: &str, source: &str, e: &serde_json::Error) -> SceneError {
    let message = e.to_string();
    if message.starts_with("number out of range") {
        let offset = byte_offset(text, e.line(), e.column());
        return SceneError::new(
            source,
            path_at(text, offset),
            format!("number out of range, expected a finite number (at line {} column {})", e.line(), e.column()),
        );
    }
    SceneError::new(source, "", format!("invalid JSON: {message}"))
}

/// Checks that the top level is an object and, before anything else, that
/// `version` is 1 (a file for a later version would otherwise fail on its
/// new keys with a less helpful message).
fn check_top_level(value: &Value, source: &str) -> Result<(), SceneError> {
    let Value::Object(object) = value else {
        return Err(SceneError::new(
            source,
            "",
            format!("expected a JSON object at the top level, got {}", describe(value)),
        ));
    };
    if let Some(Value::Number(n)) = object.get("version") {
        if n.as_u64() != Some(u64::from(SCENE_VERSION)) {
            return Err(SceneError::new(
                source,
                "version",
                format!("unsupported scene version {n}; this build of niebla reads version {SCENE_VERSION}"),
            ));
        }
    }
    Ok(())
}

/// An object that must have no fields besides `type`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NoFields {}

/// Implements `Deserialize` for a type through a `fn(Object) -> Result<T,
/// Located>`.
macro_rules! deserialize_object {
    ($ty:ty, $expecting:literal, $parse:ident) => {
        impl<'de> Deserialize<'de> for $ty {
            fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<$ty, D::Error> {
                let object = read_object(deserializer, $expecting)?;
                $parse(object).map_err(Located::into_serde)
            }
        }
    };
}

// ---------------------------------------------------------------------------
// Camera and render settings
// ---------------------------------------------------------------------------

deserialize_object!(CameraDesc, "a camera object with a \"type\" field", parse_camera);

fn parse_camera(mut object: Object) -> Result<CameraDesc, Located> {
    let tag = take_tag(&mut object, "camera", CameraDesc::TYPES, None)?;
    match tag.as_str() {
        "perspective" => Ok(CameraDesc::Perspective(rest(object)?)),
        _ => Err(unknown_type("camera", &tag, CameraDesc::TYPES)),
    }
}

deserialize_object!(IntegratorSpec, "an integrator object with a \"type\" field", parse_integrator);

/// The `render.integrator` object, read by the integrator registry.
fn parse_integrator(object: Object) -> Result<IntegratorSpec, Located> {
    let settings = crate::integrator::registry::parse(&object)?;
    Ok(IntegratorSpec { object, settings })
}

// ---------------------------------------------------------------------------
// Media and phase functions
// ---------------------------------------------------------------------------

deserialize_object!(MediumDesc, "a medium object", parse_medium);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHomogeneous {
    #[serde(default)]
    sigma_a: Option<ColorDesc>,
    #[serde(default)]
    sigma_s: Option<ColorDesc>,
    #[serde(default)]
    sigma_t: Option<ColorDesc>,
    #[serde(default)]
    albedo: Option<ColorDesc>,
    #[serde(default = "one")]
    scale: f32,
    #[serde(default)]
    phase: PhaseDesc,
    #[serde(default)]
    emission: Option<EmissionDesc>,
}

fn one() -> f32 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGrid {
    #[serde(default)]
    sigma_a: Option<ColorDesc>,
    #[serde(default)]
    sigma_s: Option<ColorDesc>,
    #[serde(default)]
    sigma_t: Option<ColorDesc>,
    #[serde(default)]
    albedo: Option<ColorDesc>,
    #[serde(default = "one")]
    scale: f32,
    #[serde(default)]
    phase: PhaseDesc,
    #[serde(default)]
    to_world: TransformDesc,
    #[serde(default)]
    emission: Option<GridEmissionDesc>,
    #[serde(default)]
    majorant_resolution: Option<ResolutionDesc>,
    #[serde(default)]
    storage: GridStorageDesc,
    #[serde(default)]
    velocity: Option<String>,
    #[serde(default)]
    velocity_units: VelocityUnitsDesc,
}

/// Fields only a grid medium accepts; a homogeneous medium with one of them
/// gets an error that says so (rather than a bare "unknown field").
const GRID_ONLY_FIELDS: &[&str] = &[
    "density",
    "to_world",
    "majorant_resolution",
    "storage",
    "velocity",
    "velocity_units",
    "albedo_grid",
    "albedo_to_world",
];

fn parse_medium(mut object: Object) -> Result<MediumDesc, Located> {
    // Without a `type`, a medium with a `density` is a grid medium, any
    // other homogeneous.
    let default = if object.contains_key("density") { "grid" } else { "homogeneous" };
    let tag = take_tag(&mut object, "medium", MediumDesc::TYPES, Some(default))?;
    match tag.as_str() {
        "homogeneous" => {
            check_homogeneous_has_no_grid_fields(&object)?;
            let raw: RawHomogeneous = rest(object)?;
            let coefficients = coefficients(raw.sigma_a, raw.sigma_s, raw.sigma_t, raw.albedo)?;
            Ok(MediumDesc::Homogeneous(HomogeneousMediumDesc {
                coefficients,
                scale: raw.scale,
                phase: raw.phase,
                emission: raw.emission,
            }))
        }
        "grid" => {
            let density = take::<DensitySourceDesc>(&mut object, "density")?.ok_or_else(|| {
                Located::new(
                    "density",
                    format!(
                        "missing required field `density`: a grid medium needs a density \
                         source, an object with \"type\" one of: {}",
                        DensitySourceDesc::TYPES.join(", ")
                    ),
                )
            })?;
            let albedo_grid = take::<DensitySourceDesc>(&mut object, "albedo_grid")?;
            let albedo_to_world = take::<TransformDesc>(&mut object, "albedo_to_world")?;
            let raw: RawGrid = rest(object)?;
            let albedo = match &albedo_grid {
                None => {
                    if albedo_to_world.is_some() {
                        return Err(Located::new(
                            "albedo_to_world",
                            "`albedo_to_world` places an `albedo_grid`, which this medium does not have",
                        ));
                    }
                    raw.albedo
                }
                Some(_) => {
                    if let Some(key) = [("sigma_a", raw.sigma_a.is_some()), ("sigma_s", raw.sigma_s.is_some())]
                        .iter()
                        .find_map(|&(k, given)| given.then_some(k))
                    {
                        return Err(Located::new(
                            key,
                            format!(
                                "`{key}` cannot be combined with `albedo_grid`: a medium with an albedo grid \
                                 gives `sigma_t` (and optionally `albedo`, which multiplies the grid)"
                            ),
                        ));
                    }
                    if raw.sigma_t.is_none() {
                        return Err(Located::new(
                            "sigma_t",
                            "missing required field `sigma_t`, which goes with `albedo_grid`",
                        ));
                    }
                    Some(raw.albedo.unwrap_or(ColorDesc::Gray(1.0)))
                }
            };
            let coefficients = coefficients(raw.sigma_a, raw.sigma_s, raw.sigma_t, albedo)?;
            Ok(MediumDesc::Grid(GridMediumDesc {
                coefficients,
                scale: raw.scale,
                phase: raw.phase,
                density,
                to_world: raw.to_world,
                emission: raw.emission,
                majorant_resolution: raw.majorant_resolution,
                storage: raw.storage,
                velocity: raw.velocity,
                velocity_units: raw.velocity_units,
                albedo_grid,
                albedo_to_world,
            }))
        }
        "pyro" => {
            let mut pyro: PyroMediumDesc = rest(object)?;
            pyro.phase = if pyro.anisotropy == 0.0 {
                PhaseDesc::Isotropic
            } else {
                PhaseDesc::HenyeyGreenstein { g: pyro.anisotropy }
            };
            Ok(MediumDesc::Pyro(pyro))
        }
        _ => Err(unknown_type("medium", &tag, MediumDesc::TYPES)),
    }
}

/// A homogeneous medium (the default type) given a grid medium's field: most
/// likely `"type": "grid"` was forgotten, so say that.
fn check_homogeneous_has_no_grid_fields(object: &Object) -> Result<(), Located> {
    if let Some(key) = GRID_ONLY_FIELDS.iter().find(|k| object.contains_key(**k)) {
        return Err(Located::new(
            *key,
            format!(
                "`{key}` is only valid in a heterogeneous medium: add \"type\": \"grid\" \
                 (a homogeneous medium, the default type, has the same coefficients everywhere)"
            ),
        ));
    }
    if let Some(Value::Object(emission)) = object.get("emission") {
        if let Some(key) = ["grid", "temperature"].iter().find(|k| emission.contains_key(**k)) {
            return Err(Located::new(
                format!("emission.{key}"),
                format!(
                    "emission from a `{key}` source needs a heterogeneous medium: add \
                     \"type\": \"grid\" (a homogeneous medium's emission is `L_ve` only)"
                ),
            ));
        }
    }
    Ok(())
}

deserialize_object!(
    GridEmissionDesc,
    "an emission object with one of `L_ve`, `grid`, `temperature`",
    parse_grid_emission
);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGridEmission {
    #[serde(default, rename = "L_ve")]
    l_ve: Option<ColorDesc>,
    #[serde(default)]
    grid: Option<DensitySourceDesc>,
    #[serde(default)]
    color: Option<ColorDesc>,
    #[serde(default)]
    temperature: Option<DensitySourceDesc>,
    #[serde(default)]
    emission_scale: Option<f32>,
}

fn parse_grid_emission(object: Object) -> Result<GridEmissionDesc, Located> {
    const FORMS: &str = "give exactly one of `L_ve` (emission proportional to the density), \
                         `grid` (an emission grid) and `temperature` (a temperature grid in Kelvin)";
    let raw: RawGridEmission = rest(object)?;
    let given: Vec<&str> =
        [("L_ve", raw.l_ve.is_some()), ("grid", raw.grid.is_some()), ("temperature", raw.temperature.is_some())]
            .iter()
            .filter(|(_, given)| *given)
            .map(|(name, _)| *name)
            .collect();
    match given.as_slice() {
        [] => return Err(Located::new("", format!("missing emission: {FORMS}"))),
        [_] => {}
        [first, second, ..] => {
            return Err(Located::new(*second, format!("`{second}` cannot be combined with `{first}`: {FORMS}")))
        }
    }
    if raw.color.is_some() && raw.grid.is_none() {
        return Err(Located::new("color", "`color` goes with `grid` only (it colors a one-channel emission grid)"));
    }
    if let (Some(l_ve), scale) = (raw.l_ve, raw.emission_scale) {
        if scale.is_some() {
            return Err(Located::new(
                "emission_scale",
                "`emission_scale` goes with `grid` or `temperature`; with `L_ve`, scale \
                 `L_ve` itself",
            ));
        }
        return Ok(GridEmissionDesc::ProportionalToDensity { l_ve });
    }
    let emission_scale = raw.emission_scale.unwrap_or(1.0);
    if let Some(grid) = raw.grid {
        return Ok(GridEmissionDesc::Field { grid, color: raw.color.unwrap_or(ColorDesc::Gray(1.0)), emission_scale });
    }
    match raw.temperature {
        Some(temperature) => Ok(GridEmissionDesc::Temperature { temperature, emission_scale }),
        // Unreachable: exactly one form was given. Answered anyway, never a panic.
        None => Err(Located::new("", format!("missing emission: {FORMS}"))),
    }
}

deserialize_object!(DensitySourceDesc, "a density source object with a \"type\" field", parse_density_source);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConstant {
    #[serde(default = "one")]
    value: f32,
    #[serde(default)]
    bounds: BoundsDesc,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawNpy {
    file: String,
    #[serde(default)]
    bounds: BoundsDesc,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawVol {
    file: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawVdb {
    file: String,
    #[serde(default = "default_vdb_grid")]
    grid: String,
}

fn default_vdb_grid() -> String {
    "density".to_string()
}

fn parse_density_source(mut object: Object) -> Result<DensitySourceDesc, Located> {
    let tag = take_tag(&mut object, "density source", DensitySourceDesc::TYPES, None)?;
    Ok(match tag.as_str() {
        "constant" => {
            let raw: RawConstant = rest(object)?;
            DensitySourceDesc::Constant { value: raw.value, bounds: raw.bounds }
        }
        "grid" => DensitySourceDesc::Grid(rest(object)?),
        "npy" => {
            let raw: RawNpy = rest(object)?;
            DensitySourceDesc::Npy { file: raw.file, bounds: raw.bounds }
        }
        "vol" => DensitySourceDesc::Vol { file: rest::<RawVol>(object)?.file },
        "vdb" => {
            let raw: RawVdb = rest(object)?;
            DensitySourceDesc::Vdb { file: raw.file, grid: raw.grid }
        }
        "procedural" => DensitySourceDesc::Procedural(rest(object)?),
        _ => return Err(unknown_type("density source", &tag, DensitySourceDesc::TYPES)),
    })
}

/// Exactly one of the forms `sigma_a` + `sigma_s` and `sigma_t` + `albedo`.
fn coefficients(
    sigma_a: Option<ColorDesc>,
    sigma_s: Option<ColorDesc>,
    sigma_t: Option<ColorDesc>,
    albedo: Option<ColorDesc>,
) -> Result<CoefficientsDesc, Located> {
    const FORMS: &str = "give either `sigma_a` and `sigma_s`, or `sigma_t` and `albedo`";
    match (sigma_a, sigma_s, sigma_t, albedo) {
        (Some(sigma_a), Some(sigma_s), None, None) => Ok(CoefficientsDesc::AbsorptionScattering { sigma_a, sigma_s }),
        (None, None, Some(sigma_t), Some(albedo)) => Ok(CoefficientsDesc::ExtinctionAlbedo { sigma_t, albedo }),
        (None, None, None, None) => Err(Located::new("", format!("missing coefficients: {FORMS}"))),
        (a, s, t, al) => {
            let first_form = a.map(|_| "sigma_a").or(s.map(|_| "sigma_s"));
            let second_form = t.map(|_| "sigma_t").or(al.map(|_| "albedo"));
            if let (Some(first), Some(second)) = (first_form, second_form) {
                return Err(Located::new(second, format!("`{second}` cannot be combined with `{first}`: {FORMS}")));
            }
            let (given, missing) = match (a, s, t) {
                (Some(_), _, _) => ("sigma_a", "sigma_s"),
                (_, Some(_), _) => ("sigma_s", "sigma_a"),
                (_, _, Some(_)) => ("sigma_t", "albedo"),
                _ => ("albedo", "sigma_t"),
            };
            Err(Located::new(
                missing,
                format!("missing required field `{missing}`, which goes with `{given}`: {FORMS}"),
            ))
        }
    }
}

deserialize_object!(PhaseDesc, "a phase function object with a \"type\" field", parse_phase);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawG {
    g: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDoubleHg {
    w: f32,
    g1: f32,
    g2: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSchlick {
    #[serde(default)]
    k: Option<f32>,
    #[serde(default)]
    g: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTabulated {
    #[serde(default)]
    file: Option<String>,
    #[serde(default)]
    column: Option<String>,
    #[serde(default)]
    mu: Option<Vec<f64>>,
    #[serde(default)]
    p: Option<Vec<f64>>,
}

/// A `"tabulated"` phase function: a table file (`file`, optional
/// `column`) or the table inline (`mu` and `p`), not both.
fn tabulated_phase(raw: RawTabulated) -> Result<PhaseDesc, Located> {
    match (raw.file, raw.mu, raw.p) {
        (Some(file), None, None) => {
            Ok(PhaseDesc::Tabulated { file, column: raw.column.unwrap_or_else(|| "p_mie_poly".to_string()) })
        }
        (None, Some(mu), Some(p)) => {
            if raw.column.is_some() {
                return Err(Located::new(
                    "column",
                    "`column` names a column of a table file: it needs `file`, not `mu`/`p`",
                ));
            }
            Ok(PhaseDesc::TabulatedInline { mu, p })
        }
        (Some(_), _, _) => Err(Located::new(
            "file",
            "`file` and `mu`/`p` are mutually exclusive: give a table file or the table inline",
        )),
        (None, Some(_), None) => Err(Located::new("p", "missing field `p` (the phase values at the cosines `mu`)")),
        (None, None, Some(_)) => Err(Located::new("mu", "missing field `mu` (the cosines of the values `p`)")),
        (None, None, None) => {
            Err(Located::new("file", "missing field `file` (a table file; or give the table inline as `mu` and `p`)"))
        }
    }
}

fn parse_phase(mut object: Object) -> Result<PhaseDesc, Located> {
    let tag = take_tag(&mut object, "phase function", PhaseDesc::TYPES, None)?;
    let no_fields = |object| rest::<NoFields>(object).map(|_| ());
    Ok(match tag.as_str() {
        "isotropic" => {
            no_fields(object)?;
            PhaseDesc::Isotropic
        }
        "hg" => PhaseDesc::HenyeyGreenstein { g: rest::<RawG>(object)?.g },
        "double_hg" => {
            let raw: RawDoubleHg = rest(object)?;
            PhaseDesc::DoubleHenyeyGreenstein { w: raw.w, g1: raw.g1, g2: raw.g2 }
        }
        "schlick" => {
            let raw: RawSchlick = rest(object)?;
            PhaseDesc::Schlick(match (raw.k, raw.g) {
                (Some(k), None) => SchlickDesc::K(k),
                (None, Some(g)) => SchlickDesc::G(g),
                (Some(_), Some(_)) => {
                    return Err(Located::new(
                        "g",
                        "`k` and `g` are mutually exclusive: give Schlick's `k` or the HG asymmetry `g`",
                    ))
                }
                (None, None) => {
                    return Err(Located::new("k", "missing required field `k` (or give the HG asymmetry `g` instead)"))
                }
            })
        }
        "rayleigh" => {
            no_fields(object)?;
            PhaseDesc::Rayleigh
        }
        "cornette_shanks" => PhaseDesc::CornetteShanks { g: rest::<RawG>(object)?.g },
        "tabulated" => {
            let raw: RawTabulated = rest(object)?;
            tabulated_phase(raw)?
        }
        "fog" => {
            no_fields(object)?;
            PhaseDesc::Fog
        }
        "mie_fog" => {
            no_fields(object)?;
            PhaseDesc::MieFog
        }
        _ => return Err(unknown_type("phase function", &tag, PhaseDesc::TYPES)),
    })
}

// ---------------------------------------------------------------------------
// Shapes, surfaces and transforms
// ---------------------------------------------------------------------------

deserialize_object!(ShapeDesc, "a shape object with a \"type\" field", parse_shape);

/// Fields every shape accepts besides its geometry's.
const SHAPE_COMMON_FIELDS: &str = "`type`, `interior`, `exterior`, `bsdf`, `motion`, `tangent_frame`";

fn parse_shape(mut object: Object) -> Result<ShapeDesc, Located> {
    let tag = take_tag(&mut object, "shape", GeometryDesc::TYPES, None)?;
    if !GeometryDesc::TYPES.contains(&tag.as_str()) {
        return Err(unknown_type("shape", &tag, GeometryDesc::TYPES));
    }
    let interior = take::<String>(&mut object, "interior")?;
    let exterior = take::<String>(&mut object, "exterior")?;
    let bsdf = take::<BsdfDesc>(&mut object, "bsdf")?.unwrap_or_default();
    let motion = take::<ShapeMotionDesc>(&mut object, "motion")?.map(Box::new);
    let tangent_frame = take::<TangentFrameDesc>(&mut object, "tangent_frame")?.unwrap_or_default();
    let geometry = match tag.as_str() {
        "sphere" => rest(object).map(GeometryDesc::Sphere),
        "box" => rest(object).map(GeometryDesc::Box),
        "rectangle" => rest(object).map(GeometryDesc::Rectangle),
        "disk" => rest(object).map(GeometryDesc::Disk),
        "mesh" => rest(object).map(GeometryDesc::Mesh),
        _ => Err(unknown_type("shape", &tag, GeometryDesc::TYPES)),
    };
    let geometry = geometry.map_err(|mut e| {
        let direct_child = !e.path.contains(['.', '[']);
        if direct_child && e.message.starts_with("unknown field") {
            e.message = format!("{}; every shape also accepts {SHAPE_COMMON_FIELDS}", e.message);
        }
        e
    })?;
    Ok(ShapeDesc { geometry, interior, exterior, bsdf, motion, tangent_frame })
}

deserialize_object!(BsdfDesc, "a bsdf object with a \"type\" field", parse_bsdf);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDiffuse {
    #[serde(default = "half_gray")]
    reflectance: ReflectanceDesc,
}

fn half_gray() -> ReflectanceDesc {
    ReflectanceDesc::Color(ColorDesc::Gray(0.5))
}

impl<'de> Deserialize<'de> for ReflectanceDesc {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<ReflectanceDesc, D::Error> {
        match serde_json::Value::deserialize(deserializer)? {
            serde_json::Value::Object(object) => {
                parse_texture(object).map(ReflectanceDesc::Texture).map_err(Located::into_serde)
            }
            other => ColorDesc::deserialize(other).map(ReflectanceDesc::Color).map_err(|e| {
                serde::de::Error::custom(format!("expected a color (a number or [r, g, b]) or a texture object: {e}"))
            }),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBitmap {
    file: String,
    #[serde(default)]
    wrap: Option<String>,
    #[serde(default)]
    raw: bool,
    #[serde(default = "unit_uv_scale")]
    scale: [f32; 2],
    #[serde(default)]
    filter: Option<String>,
    #[serde(default)]
    to_uv: Option<[[f32; 3]; 2]>,
}

fn unit_uv_scale() -> [f32; 2] {
    [1.0, 1.0]
}

fn checker_uv_scale() -> [f32; 2] {
    [2.0, 2.0]
}

fn checker_color0() -> ColorDesc {
    ColorDesc::Gray(0.4)
}

fn checker_color1() -> ColorDesc {
    ColorDesc::Gray(0.2)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCheckerboard {
    #[serde(default = "checker_color0")]
    color0: ColorDesc,
    #[serde(default = "checker_color1")]
    color1: ColorDesc,
    #[serde(default = "checker_uv_scale")]
    scale: [f32; 2],
    #[serde(default)]
    to_uv: Option<[[f32; 3]; 2]>,
}

pub(super) fn parse_texture(mut object: Object) -> Result<TextureDesc, Located> {
    let tag = take_tag(&mut object, "texture", TextureDesc::TYPES, None)?;
    match tag.as_str() {
        "bitmap" => {
            let raw: RawBitmap = rest(object)?;
            let wrap = match raw.wrap.as_deref() {
                None | Some("repeat") => crate::texture::WrapMode::Repeat,
                Some("mirror") => crate::texture::WrapMode::Mirror,
                Some("clamp") => crate::texture::WrapMode::Clamp,
                Some(other) => {
                    return Err(Located::new(
                        "wrap",
                        format!("unknown wrap mode \"{other}\"; expected \"repeat\", \"mirror\" or \"clamp\""),
                    ))
                }
            };
            let filter = match raw.filter.as_deref() {
                None | Some("bilinear") => crate::texture::FilterMode::Bilinear,
                Some("nearest") => crate::texture::FilterMode::Nearest,
                Some(other) => {
                    return Err(Located::new(
                        "filter",
                        format!("unknown filter \"{other}\"; expected \"bilinear\" or \"nearest\""),
                    ))
                }
            };
            Ok(TextureDesc::Bitmap { file: raw.file, wrap, raw: raw.raw, scale: raw.scale, filter, to_uv: raw.to_uv })
        }
        "checkerboard" => {
            let raw: RawCheckerboard = rest(object)?;
            Ok(TextureDesc::Checkerboard { color0: raw.color0, color1: raw.color1, scale: raw.scale, to_uv: raw.to_uv })
        }
        _ => Err(unknown_type("texture", &tag, TextureDesc::TYPES)),
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDielectric {
    #[serde(default = "glass_ior")]
    int_ior: f32,
    #[serde(default = "one")]
    ext_ior: f32,
}

fn glass_ior() -> f32 {
    1.5
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConductor {
    #[serde(default)]
    material: Option<String>,
    #[serde(default)]
    eta: Option<ColorDesc>,
    #[serde(default)]
    k: Option<ColorDesc>,
    #[serde(default)]
    reflectance: Option<ColorDesc>,
}

fn parse_bsdf(mut object: Object) -> Result<BsdfDesc, Located> {
    let tag = take_tag(&mut object, "bsdf", BsdfDesc::TYPES, None)?;
    match tag.as_str() {
        "null" => rest::<NoFields>(object).map(|_| BsdfDesc::Null),
        "diffuse" => {
            let raw: RawDiffuse = rest(object)?;
            Ok(BsdfDesc::Diffuse { reflectance: raw.reflectance })
        }
        "dielectric" => {
            let raw: RawDielectric = rest(object)?;
            Ok(BsdfDesc::Dielectric { int_ior: raw.int_ior, ext_ior: raw.ext_ior })
        }
        "conductor" => {
            let raw: RawConductor = rest(object)?;
            let given = [raw.material.is_some(), raw.eta.is_some() || raw.k.is_some(), raw.reflectance.is_some()];
            if given.iter().filter(|g| **g).count() != 1 {
                return Err(Located::new(
                    "",
                    "give exactly one of `material` (gold, silver, aluminium, copper), `eta` with `k`, or \
                     `reflectance`",
                ));
            }
            if let Some(name) = raw.material {
                let preset = crate::bsdf::conductor_preset(&name).ok_or_else(|| {
                    Located::new(
                        "material",
                        format!(
                            "unknown conductor material \"{name}\"; expected one of: {}",
                            crate::bsdf::CONDUCTOR_PRESETS.iter().map(|p| p.name).collect::<Vec<_>>().join(", ")
                        ),
                    )
                })?;
                return Ok(BsdfDesc::Conductor(ConductorDesc::Material(preset.name)));
            }
            if let Some(r) = raw.reflectance {
                return Ok(BsdfDesc::Conductor(ConductorDesc::Reflectance(r)));
            }
            match (raw.eta, raw.k) {
                (Some(eta), Some(k)) => Ok(BsdfDesc::Conductor(ConductorDesc::Index { eta, k })),
                (None, _) => Err(Located::new("eta", "missing `eta`: give it together with `k`")),
                (_, None) => Err(Located::new("k", "missing `k`: give it together with `eta`")),
            }
        }
        other => super::parse_surfaces::parse_surface(other, object)
            .unwrap_or_else(|| Err(unknown_type("bsdf", &tag, BsdfDesc::TYPES))),
    }
}

deserialize_object!(
    TransformDesc,
    "a transform object (translate, scale, rotate_x, rotate_y, rotate_z, or matrix)",
    parse_transform
);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTransform {
    #[serde(default, deserialize_with = "optional_vec3")]
    translate: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "optional_scale")]
    scale: Option<[f32; 3]>,
    #[serde(default)]
    rotate_x: Option<f32>,
    #[serde(default)]
    rotate_y: Option<f32>,
    #[serde(default)]
    rotate_z: Option<f32>,
    #[serde(default)]
    matrix: Option<[[f32; 4]; 4]>,
}

fn parse_transform(object: Object) -> Result<TransformDesc, Located> {
    let raw: RawTransform = rest(object)?;
    if let Some(matrix) = raw.matrix {
        let others = [
            ("translate", raw.translate.is_some()),
            ("scale", raw.scale.is_some()),
            ("rotate_x", raw.rotate_x.is_some()),
            ("rotate_y", raw.rotate_y.is_some()),
            ("rotate_z", raw.rotate_z.is_some()),
        ];
        only_matrix(&others, "a full matrix, or translate/scale/rotate_x/rotate_y/rotate_z")?;
        return Ok(TransformDesc::Matrix(matrix));
    }
    Ok(TransformDesc::Components {
        scale: raw.scale.unwrap_or([1.0; 3]),
        rotate_x: raw.rotate_x.unwrap_or(0.0),
        rotate_y: raw.rotate_y.unwrap_or(0.0),
        rotate_z: raw.rotate_z.unwrap_or(0.0),
        translate: raw.translate.unwrap_or([0.0; 3]),
    })
}

deserialize_object!(RotationDesc, "a rotation object (rotate_x, rotate_y, rotate_z, or matrix)", parse_rotation);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRotation {
    #[serde(default)]
    rotate_x: Option<f32>,
    #[serde(default)]
    rotate_y: Option<f32>,
    #[serde(default)]
    rotate_z: Option<f32>,
    #[serde(default)]
    matrix: Option<[[f32; 3]; 3]>,
}

fn parse_rotation(object: Object) -> Result<RotationDesc, Located> {
    let raw: RawRotation = rest(object)?;
    let angles = [raw.rotate_x, raw.rotate_y, raw.rotate_z];
    match raw.matrix {
        Some(matrix) => {
            let others = [
                ("rotate_x", raw.rotate_x.is_some()),
                ("rotate_y", raw.rotate_y.is_some()),
                ("rotate_z", raw.rotate_z.is_some()),
            ];
            only_matrix(&others, "a 3x3 matrix, or rotate_x/rotate_y/rotate_z")?;
            Ok(RotationDesc::Matrix(matrix))
        }
        None => Ok(RotationDesc::Angles(angles.map(|a| a.unwrap_or(0.0)))),
    }
}

/// Refuses the first key given beside `matrix` (`others`: each key's name
/// and whether the object has it), with an error at that key saying that
/// the object takes `alternatives` instead.
fn only_matrix(others: &[(&'static str, bool)], alternatives: &str) -> Result<(), Located> {
    match others.iter().find(|(_, given)| *given) {
        Some((name, _)) => {
            Err(Located::new(*name, format!("`{name}` cannot be combined with `matrix`: give {alternatives}")))
        }
        None => Ok(()),
    }
}

// ---------------------------------------------------------------------------
// Lights
// ---------------------------------------------------------------------------

deserialize_object!(LightDesc, "a light object with a \"type\" field", parse_light);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSpot {
    #[serde(deserialize_with = "vec3")]
    position: [f32; 3],
    #[serde(default, deserialize_with = "optional_vec3")]
    target: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "optional_vec3")]
    direction: Option<[f32; 3]>,
    intensity: ColorDesc,
    #[serde(default = "default_cutoff_angle")]
    cutoff_angle: f32,
    #[serde(default)]
    beam_width: Option<f32>,
}

fn default_cutoff_angle() -> f32 {
    20.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawArea {
    radiance: ColorDesc,
    #[serde(default)]
    two_sided: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawEnvmap {
    file: String,
    #[serde(default = "one")]
    scale: f32,
    #[serde(default)]
    to_world: TransformDesc,
}

fn parse_light(mut object: Object) -> Result<LightDesc, Located> {
    let tag = take_tag(&mut object, "light", LightDesc::TYPES, None)?;
    match tag.as_str() {
        "point" => rest(object).map(LightDesc::Point),
        "spot" => {
            let raw: RawSpot = rest(object)?;
            let aim = match (raw.target, raw.direction) {
                (Some(target), None) => SpotAimDesc::Target(target),
                (None, Some(direction)) => SpotAimDesc::Direction(direction),
                (Some(_), Some(_)) => {
                    return Err(Located::new(
                        "direction",
                        "`target` and `direction` are mutually exclusive: give the point the \
                         spot light looks at, or the direction of its axis",
                    ))
                }
                (None, None) => {
                    return Err(Located::new("target", "missing required field `target` (or give `direction` instead)"))
                }
            };
            Ok(LightDesc::Spot(SpotLightDesc {
                position: raw.position,
                aim,
                intensity: raw.intensity,
                cutoff_angle: raw.cutoff_angle,
                beam_width: raw.beam_width.unwrap_or(0.75 * raw.cutoff_angle),
            }))
        }
        "directional" => rest(object).map(LightDesc::Directional),
        "constant" => rest(object).map(LightDesc::Constant),
        "area" => {
            let shape = take::<ShapeDesc>(&mut object, "shape")?.ok_or_else(|| {
                Located::new("shape", "missing required field `shape`: a rectangle, disk or sphere object")
            })?;
            let raw: RawArea = rest(object)?;
            Ok(LightDesc::Area(AreaLightDesc { shape, radiance: raw.radiance, two_sided: raw.two_sided }))
        }
        "envmap" => {
            let raw: RawEnvmap = rest(object)?;
            Ok(LightDesc::Envmap(EnvmapLightDesc { file: raw.file, scale: raw.scale, to_world: raw.to_world }))
        }
        _ => Err(unknown_type("light", &tag, LightDesc::TYPES)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_numbers_are_reported_at_their_path() {
        let text = "{\"version\": 1,\n \"media\": {\"fog\": {\"sigma_s\": [1, 1e400]}}}";
        let err = parse_scene_str(text, "t.json").unwrap_err();
        assert_eq!(err.path, "media.fog.sigma_s[1]", "{err}");
        assert!(err.message.contains("line 2"), "{err}");
    }

    /// Every name in a `TYPES` list is accepted by its parser (the lists
    /// feed error messages and must match the `match` arms).
    #[test]
    fn every_listed_type_is_parsed() {
        fn accepted(parse: fn(Object) -> Result<(), Located>, types: &[&str]) {
            for tag in types {
                let mut object = Object::new();
                object.insert("type".into(), Value::String(tag.to_string()));
                if let Err(e) = parse(object) {
                    assert!(!e.message.starts_with("unknown"), "{tag}: {e:?}");
                }
            }
        }
        accepted(|o| parse_camera(o).map(drop), CameraDesc::TYPES);
        accepted(|o| parse_integrator(o).map(drop), &crate::integrator::registry::NAMES);
        accepted(|o| parse_medium(o).map(drop), MediumDesc::TYPES);
        accepted(|o| parse_density_source(o).map(drop), DensitySourceDesc::TYPES);
        accepted(|o| parse_phase(o).map(drop), PhaseDesc::TYPES);
        accepted(|o| parse_shape(o).map(drop), GeometryDesc::TYPES);
        accepted(|o| parse_bsdf(o).map(drop), BsdfDesc::TYPES);
        accepted(|o| parse_light(o).map(drop), LightDesc::TYPES);
    }
}
