//! Checks on a parsed [`SceneDesc`]: ranges, finiteness, geometric sanity and
//! references between objects (medium names). Each failure names the JSON path
//! of the offending value, down to the channel or component
//! (`media.fog.sigma_s[2]`).

use super::desc::*;
use super::error::SceneError;

/// Largest image side in pixels.
pub const MAX_IMAGE_SIDE: u32 = 16_384;
/// Largest image size in pixels (2^26, e.g. 8192 x 8192).
pub const MAX_IMAGE_PIXELS: u64 = 1 << 26;

impl SceneDesc {
    /// Checks the description and returns the first problem found, as an
    /// error in file `source` at the problem's JSON path.
    ///
    /// Checked: `version` is 1; every number is finite (values beyond the
    /// 32-bit float range read as infinite); coefficients, intensities and
    /// radiances are >= 0 and albedos and reflectances in [0, 1]; phase
    /// parameters `g`, `g1`, `g2`, `k` in (-1, 1) and `w` in [0, 1]; the
    /// camera has a valid resolution (each side 1 to 16384, at most 2^26
    /// pixels), a field of view in (0, 180) degrees, `position != target` and
    /// an `up` not parallel to the view direction; grid media have valid
    /// density and emission sources (inline grids with `nx * ny * nz` values,
    /// each finite and >= 0, at most 2^28; boxes with `max > min`; file and
    /// grid names non-empty; procedural parameters in range), an invertible
    /// `to_world`, emission scales >= 0 and a majorant resolution from 1 to
    /// 256 per axis (values inside files are checked when the scene is
    /// built); shapes are non-degenerate;
    /// every medium name used (`interior`, `exterior`, `ambient_medium`) is
    /// defined in `media`. [`parse_scene_str`](super::parse_scene_str) calls
    /// this; call it again after editing a description in code.
    pub fn validate(&self, source: &str) -> Result<(), SceneError> {
        validate_scene(self).map_err(|e| SceneError::new(source, e.path, e.message))
    }
}

/// A failed check: where and what.
struct Invalid {
    path: String,
    message: String,
}

type Check = Result<(), Invalid>;

fn fail(path: impl Into<String>, message: impl Into<String>) -> Check {
    Err(Invalid { path: path.into(), message: message.into() })
}

fn validate_scene(desc: &SceneDesc) -> Check {
    if desc.version != SCENE_VERSION {
        return fail(
            "version",
            format!("unsupported scene version {}; this build of niebla reads version {SCENE_VERSION}", desc.version),
        );
    }
    validate_camera(&desc.camera)?;
    validate_render(&desc.render)?;
    for (name, medium) in &desc.media {
        if name.is_empty() {
            return fail("media", "medium names must not be empty");
        }
        validate_medium(&format!("media.{name}"), medium)?;
    }
    for (i, shape) in desc.shapes.iter().enumerate() {
        validate_shape(desc, &format!("shapes[{i}]"), shape)?;
    }
    for (i, light) in desc.lights.iter().enumerate() {
        validate_light(desc, &format!("lights[{i}]"), light)?;
    }
    if let Some(name) = &desc.ambient_medium {
        medium_exists(desc, "ambient_medium", name)?;
    }
    if let Err((i, message)) = desc.film.check() {
        return fail(format!("film.aovs[{i}]"), message);
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Numbers, vectors and colors
// ---------------------------------------------------------------------------

fn finite(path: &str, x: f32) -> Check {
    if x.is_finite() {
        Ok(())
    } else {
        fail(path, format!("expected a finite number, got {x} (magnitude must be below 3.4e38)"))
    }
}

fn non_negative(path: &str, x: f32) -> Check {
    finite(path, x)?;
    if x >= 0.0 {
        Ok(())
    } else {
        fail(path, format!("must be >= 0, got {x}"))
    }
}

fn positive(path: &str, x: f32) -> Check {
    finite(path, x)?;
    if x > 0.0 {
        Ok(())
    } else {
        fail(path, format!("must be > 0, got {x}"))
    }
}

fn below_one(path: &str, x: f32) -> Check {
    finite(path, x)?;
    if (0.0..1.0).contains(&x) {
        Ok(())
    } else {
        fail(path, format!("must be in [0, 1), got {x}"))
    }
}

fn in_unit_interval(path: &str, x: f32) -> Check {
    finite(path, x)?;
    if (0.0..=1.0).contains(&x) {
        Ok(())
    } else {
        fail(path, format!("must be in [0, 1], got {x}"))
    }
}

/// An asymmetry-like parameter in the open interval (-1, 1).
fn asymmetry(path: &str, x: f32) -> Check {
    finite(path, x)?;
    if x > -1.0 && x < 1.0 {
        Ok(())
    } else {
        fail(path, format!("must be in the open interval (-1, 1), got {x}"))
    }
}

/// Applies `check` to a color: to the value itself for a scalar, to each
/// channel (path `name[i]`) for an RGB triple.
/// A conductor's complex index `eta + i k` (niebla's `conductor` and
/// `roughconductor`): both non-negative, and not both 0 in any channel (the
/// Fresnel term divides by the index). `eta` 0 with `k` > 0 is a purely
/// imaginary index, a reflectance of 1 at every angle (Mitsuba's default
/// conductor, material "none").
fn conductor_index(path: &str, eta: &ColorDesc, k: &ColorDesc) -> Check {
    color(&format!("{path}.eta"), eta, non_negative)?;
    color(&format!("{path}.k"), k, non_negative)?;
    let (e, kk) = (eta.channels(), k.channels());
    if (0..3).any(|c| e[c] == 0.0 && kk[c] == 0.0) {
        return fail(format!("{path}.k"), "`eta` and `k` are both 0 in a channel: expected `eta` > 0 or `k` > 0");
    }
    Ok(())
}

fn color(path: &str, c: &ColorDesc, check: fn(&str, f32) -> Check) -> Check {
    match c {
        ColorDesc::Gray(v) => check(path, *v),
        ColorDesc::Rgb(rgb) => {
            for (i, v) in rgb.iter().enumerate() {
                check(&format!("{path}[{i}]"), *v)?;
            }
            Ok(())
        }
    }
}

fn vector(path: &str, v: &[f32; 3]) -> Check {
    for (i, x) in v.iter().enumerate() {
        finite(&format!("{path}[{i}]"), *x)?;
    }
    Ok(())
}

fn non_zero_vector(path: &str, v: &[f32; 3]) -> Check {
    vector(path, v)?;
    if v.iter().all(|x| *x == 0.0) {
        return fail(path, "must be a non-zero vector");
    }
    Ok(())
}

fn length(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn difference(a: &[f32; 3], b: &[f32; 3]) -> [f64; 3] {
    [f64::from(a[0]) - f64::from(b[0]), f64::from(a[1]) - f64::from(b[1]), f64::from(a[2]) - f64::from(b[2])]
}

// ---------------------------------------------------------------------------
// Camera and render settings
// ---------------------------------------------------------------------------

fn validate_camera(camera: &CameraDesc) -> Check {
    match camera {
        CameraDesc::Perspective(c) => {
            vector("camera.position", &c.position)?;
            vector("camera.target", &c.target)?;
            vector("camera.up", &c.up)?;
            finite("camera.fov_y", c.fov_y)?;
            if !(c.fov_y > 0.0 && c.fov_y < 180.0) {
                return fail(
                    "camera.fov_y",
                    format!("vertical field of view must be in the open interval (0, 180) degrees, got {}", c.fov_y),
                );
            }
            image_side("camera.width", c.width)?;
            image_side("camera.height", c.height)?;
            let pixels = u64::from(c.width) * u64::from(c.height);
            if pixels > MAX_IMAGE_PIXELS {
                return fail(
                    "camera",
                    format!(
                        "width x height = {} x {} = {pixels} pixels exceeds the limit of \
                         {MAX_IMAGE_PIXELS} (2^26) pixels",
                        c.width, c.height
                    ),
                );
            }
            let view = difference(&c.target, &c.position);
            if length(view) == 0.0 {
                return fail("camera.target", "must differ from `position`");
            }
            let up = c.up.map(f64::from);
            let cross = [
                view[1] * up[2] - view[2] * up[1],
                view[2] * up[0] - view[0] * up[2],
                view[0] * up[1] - view[1] * up[0],
            ];
            if length(up) == 0.0 {
                return fail("camera.up", "must be a non-zero vector");
            }
            if length(cross) <= 1e-6 * length(view) * length(up) {
                return fail("camera.up", "must not be parallel to the view direction (target - position)");
            }
            validate_shutter(c)
        }
    }
}

/// The shutter interval, the frame rate and the camera's motion: the pose
/// must be a view at both ends of the shutter.
fn validate_shutter(c: &PerspectiveCameraDesc) -> Check {
    finite("camera.shutter_open", c.shutter_open)?;
    finite("camera.shutter_close", c.shutter_close)?;
    if c.shutter_close < c.shutter_open {
        return fail(
            "camera.shutter_close",
            format!(
                "the shutter must close at or after it opens (frames relative to the frame), got shutter_open {} \
                 and shutter_close {}",
                c.shutter_open, c.shutter_close
            ),
        );
    }
    if !(c.fps.is_finite() && c.fps > 0.0) {
        return fail("camera.fps", format!("expected frames per second > 0, got {}", c.fps));
    }
    let Some(m) = &c.motion else { return Ok(()) };
    for (name, v) in [("position", &m.position), ("target", &m.target), ("up", &m.up)] {
        if let Some(v) = v {
            vector(&format!("camera.motion.{name}"), v)?;
        }
    }
    let lerp = |a: &[f32; 3], b: &Option<[f32; 3]>, t: f32| {
        let b = b.unwrap_or(*a);
        [0, 1, 2].map(|i| a[i] + (b[i] - a[i]) * t)
    };
    for t in [c.shutter_open, c.shutter_close] {
        let (p, target, up) = (lerp(&c.position, &m.position, t), lerp(&c.target, &m.target, t), lerp(&c.up, &m.up, t));
        let view = difference(&target, &p);
        let up = up.map(f64::from);
        let cross =
            [view[1] * up[2] - view[2] * up[1], view[2] * up[0] - view[0] * up[2], view[0] * up[1] - view[1] * up[0]];
        if length(view) == 0.0 || length(cross) <= 1e-6 * length(view) * length(up) {
            return fail(
                "camera.motion",
                format!(
                    "at time {t} (frames) the moving camera's position, target and up do not define a view \
                     (equal or parallel)"
                ),
            );
        }
    }
    Ok(())
}

fn image_side(path: &str, pixels: u32) -> Check {
    if pixels == 0 {
        fail(path, "must be at least 1 pixel, got 0")
    } else if pixels > MAX_IMAGE_SIDE {
        fail(path, format!("must be at most {MAX_IMAGE_SIDE} pixels, got {pixels}"))
    } else {
        Ok(())
    }
}

/// `spp` and `exposure`; the integrator object was checked by the
/// integrator registry when it was read.
fn validate_render(render: &RenderDesc) -> Check {
    if render.spp == 0 {
        return fail("render.spp", "samples per pixel must be at least 1, got 0");
    }
    finite("render.exposure", render.exposure)
}

// ---------------------------------------------------------------------------
// Media and phase functions
// ---------------------------------------------------------------------------

fn validate_medium(base: &str, medium: &MediumDesc) -> Check {
    match medium {
        MediumDesc::Homogeneous(m) => {
            validate_coefficients(base, &m.coefficients, m.scale)?;
            validate_phase(&format!("{base}.phase"), &m.phase)?;
            if let Some(emission) = &m.emission {
                color(&format!("{base}.emission.L_ve"), &emission.l_ve, non_negative)?;
            }
            Ok(())
        }
        MediumDesc::Grid(m) => {
            validate_coefficients(base, &m.coefficients, m.scale)?;
            validate_phase(&format!("{base}.phase"), &m.phase)?;
            validate_source(&format!("{base}.density"), &m.density)?;
            validate_transform(&format!("{base}.to_world"), &m.to_world)?;
            if let Some(emission) = &m.emission {
                validate_grid_emission(&format!("{base}.emission"), emission)?;
            }
            if let Some(r) = &m.majorant_resolution {
                resolution(&format!("{base}.majorant_resolution"), r, MAX_MAJORANT_RESOLUTION)?;
            }
            if let Some(source) = &m.albedo_grid {
                let at = format!("{base}.albedo_grid");
                if let DensitySourceDesc::Vdb { .. } = source {
                    return fail(
                        format!("{at}.type"),
                        "an albedo grid must be a dense source (constant, grid, npy, vol or procedural), not vdb",
                    );
                }
                validate_source(&at, source)?;
                // Values above 1 in files are refused when they are read.
                if let DensitySourceDesc::Constant { value, .. } = source {
                    in_unit_interval(&format!("{at}.value"), *value)?;
                }
                if let DensitySourceDesc::Grid(g) = source {
                    for (i, v) in g.data.iter().enumerate() {
                        in_unit_interval(&format!("{at}.data[{i}]"), *v)?;
                    }
                }
            }
            if let Some(t) = &m.albedo_to_world {
                validate_transform(&format!("{base}.albedo_to_world"), t)?;
            }
            Ok(())
        }
        MediumDesc::Pyro(m) => validate_pyro(base, m),
    }
}

/// The pyro medium's parameters (the grids are checked when they are read).
fn validate_pyro(base: &str, m: &PyroMediumDesc) -> Check {
    let at = |key: &str| format!("{base}.{key}");
    non_negative(&at("density"), m.density)?;
    color(&at("color"), &m.color, in_unit_interval)?;
    color(&at("absorption_color"), &m.absorption_color, in_unit_interval)?;
    validate_phase(&at("anisotropy"), &m.phase)?;
    non_negative(&at("emission_strength"), m.emission_strength)?;
    color(&at("emission_color"), &m.emission_color, non_negative)?;
    in_unit_interval(&at("blackbody_intensity"), m.blackbody_intensity)?;
    color(&at("blackbody_tint"), &m.blackbody_tint, non_negative)?;
    positive(&at("temperature"), m.temperature)?;
    finite(&at("temperature_offset"), m.temperature_offset)?;
    if m.temperature + m.temperature_offset.max(0.0) > PYRO_MAX_KELVIN {
        return fail(
            at("temperature"),
            format!(
                "temperature {} + temperature_offset {} exceeds {PYRO_MAX_KELVIN} K: \
                 is the remap of the raw temperatures right?",
                m.temperature, m.temperature_offset
            ),
        );
    }
    if let Some(ramp) = &m.flame_ramp {
        if ramp.is_empty() {
            return fail(at("flame_ramp"), "a color ramp needs at least one stop");
        }
        for (i, (position, c)) in ramp.iter().enumerate() {
            finite(&format!("{base}.flame_ramp[{i}][0]"), *position)?;
            color(&format!("{base}.flame_ramp[{i}][1]"), c, non_negative)?;
            if i > 0 && !(*position > ramp[i - 1].0) {
                return fail(
                    format!("{base}.flame_ramp[{i}][0]"),
                    format!("ramp positions must increase: {} follows {}", position, ramp[i - 1].0),
                );
            }
        }
    }
    validate_transform(&at("to_world"), &m.to_world)?;
    if let Some(r) = &m.majorant_resolution {
        resolution(&at("majorant_resolution"), r, MAX_MAJORANT_RESOLUTION)?;
    }
    Ok(())
}

fn validate_coefficients(base: &str, coefficients: &CoefficientsDesc, scale: f32) -> Check {
    match coefficients {
        CoefficientsDesc::AbsorptionScattering { sigma_a, sigma_s } => {
            color(&format!("{base}.sigma_a"), sigma_a, non_negative)?;
            color(&format!("{base}.sigma_s"), sigma_s, non_negative)?;
        }
        CoefficientsDesc::ExtinctionAlbedo { sigma_t, albedo } => {
            color(&format!("{base}.sigma_t"), sigma_t, non_negative)?;
            color(&format!("{base}.albedo"), albedo, in_unit_interval)?;
        }
    }
    positive(&format!("{base}.scale"), scale)
}

fn validate_grid_emission(base: &str, emission: &GridEmissionDesc) -> Check {
    match emission {
        GridEmissionDesc::ProportionalToDensity { l_ve } => color(&format!("{base}.L_ve"), l_ve, non_negative),
        GridEmissionDesc::Field { grid, color: c, emission_scale } => {
            validate_source(&format!("{base}.grid"), grid)?;
            color(&format!("{base}.color"), c, non_negative)?;
            non_negative(&format!("{base}.emission_scale"), *emission_scale)
        }
        GridEmissionDesc::Temperature { temperature, emission_scale } => {
            validate_source(&format!("{base}.temperature"), temperature)?;
            non_negative(&format!("{base}.emission_scale"), *emission_scale)
        }
    }
}

/// Checks a field source (density, emission grid or temperature): values
/// finite and >= 0, sizes within limits, boxes non-empty, names non-empty.
/// Values in files are checked when the scene is built.
fn validate_source(base: &str, source: &DensitySourceDesc) -> Check {
    match source {
        DensitySourceDesc::Constant { value, bounds } => {
            non_negative(&format!("{base}.value"), *value)?;
            validate_bounds(&format!("{base}.bounds"), bounds)
        }
        DensitySourceDesc::Grid(g) => {
            let voxels = resolution(&format!("{base}.dims"), &ResolutionDesc::PerAxis(g.dims), u32::MAX)?;
            if g.data.len() as u64 != voxels {
                let [nx, ny, nz] = g.dims;
                return fail(
                    format!("{base}.data"),
                    format!(
                        "expected nx * ny * nz = {nx} * {ny} * {nz} = {voxels} values for \
                         dims [{nx}, {ny}, {nz}], got {}",
                        g.data.len()
                    ),
                );
            }
            for (i, v) in g.data.iter().enumerate() {
                non_negative(&format!("{base}.data[{i}]"), *v)?;
            }
            validate_bounds(&format!("{base}.bounds"), &g.bounds)
        }
        DensitySourceDesc::Npy { file, bounds } => {
            file_name(&format!("{base}.file"), file)?;
            validate_bounds(&format!("{base}.bounds"), bounds)
        }
        DensitySourceDesc::Vol { file } => file_name(&format!("{base}.file"), file),
        DensitySourceDesc::Vdb { file, grid } => {
            file_name(&format!("{base}.file"), file)?;
            if grid.is_empty() {
                return fail(format!("{base}.grid"), "expected a grid name, got \"\"");
            }
            Ok(())
        }
        DensitySourceDesc::Procedural(p) => {
            resolution(&format!("{base}.resolution"), &p.resolution, MAX_PROCEDURAL_RESOLUTION)?;
            if !(1..=MAX_OCTAVES).contains(&p.octaves) {
                return fail(format!("{base}.octaves"), format!("must be from 1 to {MAX_OCTAVES}, got {}", p.octaves));
            }
            in_range(&format!("{base}.frequency"), p.frequency, 0.0, 1000.0, true)?;
            in_range(&format!("{base}.lacunarity"), p.lacunarity, 1.0, 8.0, false)?;
            in_unit_interval(&format!("{base}.gain"), p.gain)?;
            in_unit_interval(&format!("{base}.coverage"), p.coverage)?;
            in_range(&format!("{base}.sharpness"), p.sharpness, 0.0, 1000.0, true)
        }
    }
}

/// Most noise octaves of a procedural source (`niebla_volume`'s limit).
const MAX_OCTAVES: u32 = 12;
/// Most voxels per axis of a procedural source (`niebla_volume`'s limit).
const MAX_PROCEDURAL_RESOLUTION: u32 = 1024;

/// A number in `(lo, hi]` (with `open_low`) or `[lo, hi]`.
fn in_range(path: &str, x: f32, lo: f32, hi: f32, open_low: bool) -> Check {
    finite(path, x)?;
    let above = if open_low { x > lo } else { x >= lo };
    if above && x <= hi {
        return Ok(());
    }
    let open = if open_low { '(' } else { '[' };
    fail(path, format!("must be in {open}{lo}, {hi}], got {x}"))
}

fn file_name(path: &str, file: &str) -> Check {
    if file.is_empty() {
        return fail(path, "expected a file name, got \"\"");
    }
    Ok(())
}

/// Checks a resolution: each count from 1 to `max_per_axis`, at most
/// [`MAX_GRID_VOXELS`] in all. Returns the number of cells.
fn resolution(path: &str, r: &ResolutionDesc, max_per_axis: u32) -> Result<u64, Invalid> {
    let dims = r.dims();
    for (i, n) in dims.iter().enumerate() {
        let at = match r {
            ResolutionDesc::Uniform(_) => path.to_string(),
            ResolutionDesc::PerAxis(_) => format!("{path}[{i}]"),
        };
        if *n == 0 {
            return Err(Invalid { path: at, message: "must be at least 1, got 0".into() });
        }
        if *n > max_per_axis {
            return Err(Invalid { path: at, message: format!("must be at most {max_per_axis}, got {n}") });
        }
    }
    // In u128: three u32 counts overflow a u64 (found by fuzzing).
    let cells = dims.iter().map(|n| u128::from(*n)).product::<u128>();
    if cells > u128::from(MAX_GRID_VOXELS) {
        let [nx, ny, nz] = dims;
        return Err(Invalid {
            path: path.to_string(),
            message: format!("{nx} x {ny} x {nz} = {cells} cells exceeds the limit of {MAX_GRID_VOXELS} (2^28)"),
        });
    }
    Ok(cells as u64)
}

fn validate_bounds(base: &str, bounds: &BoundsDesc) -> Check {
    vector(&format!("{base}.min"), &bounds.min)?;
    vector(&format!("{base}.max"), &bounds.max)?;
    for axis in 0..3 {
        if bounds.min[axis] >= bounds.max[axis] {
            return fail(
                format!("{base}.max[{axis}]"),
                format!("must be greater than min[{axis}] = {}, got {}", bounds.min[axis], bounds.max[axis]),
            );
        }
    }
    Ok(())
}

fn validate_phase(base: &str, phase: &PhaseDesc) -> Check {
    match phase {
        PhaseDesc::Isotropic | PhaseDesc::Rayleigh | PhaseDesc::Fog | PhaseDesc::MieFog => Ok(()),
        PhaseDesc::HenyeyGreenstein { g } | PhaseDesc::CornetteShanks { g } => asymmetry(&format!("{base}.g"), *g),
        PhaseDesc::DoubleHenyeyGreenstein { w, g1, g2 } => {
            in_unit_interval(&format!("{base}.w"), *w)?;
            asymmetry(&format!("{base}.g1"), *g1)?;
            asymmetry(&format!("{base}.g2"), *g2)
        }
        PhaseDesc::Schlick(SchlickDesc::K(k)) => asymmetry(&format!("{base}.k"), *k),
        PhaseDesc::Schlick(SchlickDesc::G(g)) => asymmetry(&format!("{base}.g"), *g),
        PhaseDesc::Tabulated { file, column } => {
            if file.is_empty() {
                return fail(format!("{base}.file"), "expected a file name, got \"\"");
            }
            if column.is_empty() {
                return fail(format!("{base}.column"), "expected a column name, got \"\"");
            }
            Ok(())
        }
        PhaseDesc::TabulatedInline { mu, p } => match crate::phase::Tabulated::from_cosines(mu, p) {
            Ok(_) => Ok(()),
            Err(e) => fail(format!("{base}.mu"), e.to_string()),
        },
    }
}

// ---------------------------------------------------------------------------
// Shapes
// ---------------------------------------------------------------------------

fn medium_exists(desc: &SceneDesc, path: &str, name: &str) -> Check {
    if desc.media.contains_key(name) {
        return Ok(());
    }
    if desc.media.is_empty() {
        return fail(path, format!("unknown medium {name:?}; the scene defines no media (add it under `media`)"));
    }
    let known: Vec<&str> = desc.media.keys().map(String::as_str).collect();
    fail(path, format!("unknown medium {name:?}; known media: {}", known.join(", ")))
}

/// A shape's `motion`: only the fields of its own geometry, finite. Whether
/// the shape stays non-degenerate over the shutter is checked when it is
/// built (it needs the shutter and the transforms).
fn validate_shape_motion(base: &str, shape: &ShapeDesc, m: &ShapeMotionDesc) -> Check {
    let base = format!("{base}.motion");
    let (kind, allowed): (&str, &[&str]) = match &shape.geometry {
        GeometryDesc::Sphere(_) => ("a sphere", &["center", "radius"]),
        GeometryDesc::Box(_) => ("a box", &["min", "max"]),
        GeometryDesc::Rectangle(_) => ("a rectangle", &["to_world"]),
        GeometryDesc::Disk(_) => ("a disk", &["to_world"]),
        GeometryDesc::Mesh(_) => ("a mesh", &["to_world"]),
    };
    let given = [
        ("center", m.center.is_some()),
        ("radius", m.radius.is_some()),
        ("min", m.min.is_some()),
        ("max", m.max.is_some()),
        ("to_world", m.to_world.is_some()),
    ];
    for (key, present) in given {
        if present && !allowed.contains(&key) {
            return fail(
                format!("{base}.{key}"),
                format!(
                    "the motion of {kind} gives its pose one frame later by {}, not `{key}`",
                    allowed.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(" and ")
                ),
            );
        }
    }
    if !given.iter().any(|(_, present)| *present) {
        return fail(
            &base,
            format!(
                "an empty motion: give the pose of {kind} one frame later by {}",
                allowed.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(" and ")
            ),
        );
    }
    if let Some(c) = &m.center {
        vector(&format!("{base}.center"), c)?;
    }
    if let Some(r) = m.radius {
        positive(&format!("{base}.radius"), r)?;
    }
    if let Some(v) = &m.min {
        vector(&format!("{base}.min"), v)?;
    }
    if let Some(v) = &m.max {
        vector(&format!("{base}.max"), v)?;
    }
    if let GeometryDesc::Box(b) = &shape.geometry {
        let (lo, hi) = (m.min.unwrap_or(b.min), m.max.unwrap_or(b.max));
        for axis in 0..3 {
            if lo[axis] >= hi[axis] {
                return fail(
                    format!("{base}.max[{axis}]"),
                    format!("at time 1 max[{axis}] must be greater than min[{axis}] = {}, got {}", lo[axis], hi[axis]),
                );
            }
        }
    }
    if let Some(t) = &m.to_world {
        validate_transform(&format!("{base}.to_world"), t)?;
    }
    if shape.interior.is_some() || shape.exterior.is_some() {
        let side = if shape.interior.is_some() { "interior" } else { "exterior" };
        return fail(
            &base,
            format!(
                "a moving shape cannot bound a medium (it has an `{side}`): media stay where they are during the \
                 shutter; leave out `motion` or the shape's media"
            ),
        );
    }
    Ok(())
}

fn validate_shape(desc: &SceneDesc, base: &str, shape: &ShapeDesc) -> Check {
    match &shape.geometry {
        GeometryDesc::Sphere(s) => {
            vector(&format!("{base}.center"), &s.center)?;
            positive(&format!("{base}.radius"), s.radius)?;
            if let Some(r) = &s.rotation {
                validate_rotation(&format!("{base}.rotation"), r)?;
            }
        }
        GeometryDesc::Box(b) => {
            vector(&format!("{base}.min"), &b.min)?;
            vector(&format!("{base}.max"), &b.max)?;
            for axis in 0..3 {
                if b.min[axis] >= b.max[axis] {
                    return fail(
                        format!("{base}.max[{axis}]"),
                        format!("must be greater than min[{axis}] = {}, got {}", b.min[axis], b.max[axis]),
                    );
                }
            }
        }
        GeometryDesc::Rectangle(r) => validate_transform(&format!("{base}.to_world"), &r.to_world)?,
        GeometryDesc::Disk(d) => validate_transform(&format!("{base}.to_world"), &d.to_world)?,
        GeometryDesc::Mesh(m) => validate_mesh(base, m)?,
    }
    if let Some(m) = &shape.motion {
        validate_shape_motion(base, shape, m)?;
    }
    if let Some(name) = &shape.interior {
        medium_exists(desc, &format!("{base}.interior"), name)?;
    }
    if let Some(name) = &shape.exterior {
        medium_exists(desc, &format!("{base}.exterior"), name)?;
    }
    match &shape.bsdf {
        BsdfDesc::Null => Ok(()),
        BsdfDesc::Diffuse { reflectance } => validate_reflectance(&format!("{base}.bsdf.reflectance"), reflectance),
        BsdfDesc::Dielectric { int_ior, ext_ior } => {
            positive(&format!("{base}.bsdf.int_ior"), *int_ior)?;
            positive(&format!("{base}.bsdf.ext_ior"), *ext_ior)
        }
        BsdfDesc::Conductor(ConductorDesc::Material(_)) => Ok(()),
        BsdfDesc::Conductor(ConductorDesc::Index { eta, k }) => conductor_index(&format!("{base}.bsdf"), eta, k),
        BsdfDesc::Conductor(ConductorDesc::Reflectance(r)) => color(&format!("{base}.bsdf.reflectance"), r, below_one),
        other => validate_surface(&format!("{base}.bsdf"), other),
    }
}

/// Checks a microfacet or layered surface at JSON path `base` (`...bsdf`).
fn validate_surface(base: &str, bsdf: &BsdfDesc) -> Check {
    let alpha = |m: &MicrofacetDesc| -> Check {
        let check = |field: &str, a: f32| -> Check {
            if a.is_finite() && a > 0.0 && a <= 1.0 {
                Ok(())
            } else {
                fail(format!("{base}.{field}"), format!("expected a number in (0, 1] or a texture, got {a}"))
            }
        };
        match &m.alpha {
            AlphaDesc::Isotropic(a) => check("alpha", *a),
            AlphaDesc::Textured(t) => {
                validate_reflectance(&format!("{base}.alpha"), &ReflectanceDesc::Texture((**t).clone()))
            }
            AlphaDesc::Anisotropic { u, v } => {
                check("alpha_u", *u)?;
                check("alpha_v", *v)
            }
            AlphaDesc::TexturedAnisotropic(pair) => {
                for (field, value) in [("alpha_u", &pair.u), ("alpha_v", &pair.v)] {
                    match value {
                        AlphaValue::Number(a) => check(field, *a)?,
                        AlphaValue::Texture(t) => {
                            validate_reflectance(&format!("{base}.{field}"), &ReflectanceDesc::Texture((**t).clone()))?
                        }
                    }
                }
                Ok(())
            }
        }
    };
    let iors = |int_ior: f32, ext_ior: f32| -> Check {
        positive(&format!("{base}.int_ior"), int_ior)?;
        positive(&format!("{base}.ext_ior"), ext_ior)
    };
    match bsdf {
        BsdfDesc::RoughConductor(d) => {
            alpha(&d.microfacet)?;
            match &d.conductor {
                ConductorDesc::Material(_) => {}
                ConductorDesc::Index { eta, k } => conductor_index(base, eta, k)?,
                ConductorDesc::Reflectance(r) => color(&format!("{base}.reflectance"), r, below_one)?,
            }
            validate_reflectance(&format!("{base}.specular_reflectance"), &d.specular_reflectance)
        }
        BsdfDesc::RoughDielectric(d) => {
            alpha(&d.microfacet)?;
            iors(d.int_ior, d.ext_ior)?;
            if d.int_ior == d.ext_ior {
                return fail(
                    format!("{base}.int_ior"),
                    format!("must differ from ext_ior ({}): an index-matched rough interface is `null`", d.ext_ior),
                );
            }
            color(&format!("{base}.specular_reflectance"), &d.specular_reflectance, in_unit_interval)?;
            color(&format!("{base}.specular_transmittance"), &d.specular_transmittance, in_unit_interval)
        }
        BsdfDesc::ThinDielectric(d) => {
            iors(d.int_ior, d.ext_ior)?;
            color(&format!("{base}.specular_reflectance"), &d.specular_reflectance, in_unit_interval)?;
            color(&format!("{base}.specular_transmittance"), &d.specular_transmittance, in_unit_interval)
        }
        BsdfDesc::Plastic(d) => {
            iors(d.int_ior, d.ext_ior)?;
            validate_reflectance(&format!("{base}.diffuse_reflectance"), &d.diffuse_reflectance)?;
            color(&format!("{base}.specular_reflectance"), &d.specular_reflectance, in_unit_interval)
        }
        BsdfDesc::RoughPlastic(d) => {
            alpha(&d.microfacet)?;
            let p = &d.plastic;
            iors(p.int_ior, p.ext_ior)?;
            if p.int_ior == p.ext_ior {
                return fail(
                    format!("{base}.int_ior"),
                    format!("must differ from ext_ior ({}): the coating needs an interface (as in Mitsuba)", p.ext_ior),
                );
            }
            validate_reflectance(&format!("{base}.diffuse_reflectance"), &p.diffuse_reflectance)?;
            color(&format!("{base}.specular_reflectance"), &p.specular_reflectance, in_unit_interval)
        }
        BsdfDesc::TwoSided(d) => {
            let sides: Vec<(String, &BsdfDesc)> = if d.front == d.back {
                vec![(format!("{base}.bsdf"), &*d.front)]
            } else {
                vec![(format!("{base}.bsdf[0]"), &*d.front), (format!("{base}.bsdf[1]"), &*d.back)]
            };
            for (path, side) in sides {
                match side {
                    BsdfDesc::Diffuse { reflectance } => {
                        validate_reflectance(&format!("{path}.reflectance"), reflectance)?
                    }
                    BsdfDesc::Conductor(ConductorDesc::Material(_)) => {}
                    BsdfDesc::Conductor(ConductorDesc::Index { eta, k }) => conductor_index(&path, eta, k)?,
                    BsdfDesc::Conductor(ConductorDesc::Reflectance(r)) => {
                        color(&format!("{path}.reflectance"), r, below_one)?
                    }
                    BsdfDesc::RoughConductor(_) | BsdfDesc::Plastic(_) | BsdfDesc::RoughPlastic(_) => {
                        validate_surface(&path, side)?
                    }
                    _ => {
                        return fail(
                            format!("{path}.type"),
                            "twosided takes a reflecting bsdf: diffuse, conductor, roughconductor, plastic or \
                             roughplastic",
                        )
                    }
                }
            }
            Ok(())
        }
        BsdfDesc::Null | BsdfDesc::Diffuse { .. } | BsdfDesc::Dielectric { .. } | BsdfDesc::Conductor(_) => Ok(()),
    }
}

fn validate_reflectance(base: &str, r: &ReflectanceDesc) -> Check {
    let scale = |s: &[f32; 2]| -> Check {
        for (i, v) in s.iter().enumerate() {
            if !v.is_finite() || *v == 0.0 {
                return fail(format!("{base}.scale[{i}]"), format!("must be a finite non-zero number, got {v}"));
            }
        }
        Ok(())
    };
    let to_uv = |m: &Option<[[f32; 3]; 2]>| -> Check {
        for (i, row) in m.iter().flatten().enumerate() {
            for (j, v) in row.iter().enumerate() {
                if !v.is_finite() {
                    return fail(format!("{base}.to_uv[{i}][{j}]"), format!("must be a finite number, got {v}"));
                }
            }
        }
        Ok(())
    };
    match r {
        ReflectanceDesc::Color(c) => color(base, c, in_unit_interval),
        ReflectanceDesc::Texture(TextureDesc::Bitmap { scale: s, file, to_uv: m, .. }) => {
            if file.is_empty() {
                return fail(format!("{base}.file"), "must name an image file (.png, .jpg or .exr)");
            }
            scale(s)?;
            to_uv(m)
        }
        ReflectanceDesc::Texture(TextureDesc::Checkerboard { color0, color1, scale: s, to_uv: m }) => {
            color(&format!("{base}.color0"), color0, in_unit_interval)?;
            color(&format!("{base}.color1"), color1, in_unit_interval)?;
            scale(s)?;
            to_uv(m)
        }
    }
}

fn validate_mesh(base: &str, m: &MeshDesc) -> Check {
    validate_transform(&format!("{base}.to_world"), &m.to_world)?;
    match (&m.file, &m.positions, &m.indices) {
        (Some(_), None, None) => {
            for (field, given) in [("normals", m.normals.is_some()), ("uvs", m.uvs.is_some())] {
                if given {
                    return fail(
                        format!("{base}.{field}"),
                        "inline arrays go with `positions` and `indices`, not `file`",
                    );
                }
            }
            Ok(())
        }
        (Some(_), _, _) => {
            fail(format!("{base}.file"), "give either `file` or inline `positions` and `indices`, not both")
        }
        (None, Some(_), None) => fail(format!("{base}.indices"), "inline `positions` need `indices` (triangles)"),
        (None, None, Some(_)) => fail(format!("{base}.positions"), "inline `indices` need `positions`"),
        (None, None, None) => {
            fail(base.to_string(), "a mesh needs `file` (an .obj or .ply) or inline `positions` and `indices`")
        }
        (None, Some(_), Some(_)) => {
            if m.object.is_some() {
                return fail(format!("{base}.object"), "selects an object of an OBJ `file`; this mesh has none");
            }
            Ok(())
        }
    }
}

/// A sphere's `rotation`: finite angles, or a finite 3x3 matrix that is
/// orthonormal with determinant +1 to 1e-4 (a rotation, no scale, shear or
/// mirror: the sphere's size is its `radius`).
fn validate_rotation(base: &str, rotation: &RotationDesc) -> Check {
    match rotation {
        RotationDesc::Angles(a) => {
            for (axis, x) in ["x", "y", "z"].iter().zip(a) {
                finite(&format!("{base}.rotate_{axis}"), *x)?;
            }
            Ok(())
        }
        RotationDesc::Matrix(m) => {
            for (r, row) in m.iter().enumerate() {
                for (c, x) in row.iter().enumerate() {
                    finite(&format!("{base}.matrix[{r}][{c}]"), *x)?;
                }
            }
            let a = |r: usize, c: usize| f64::from(m[r][c]);
            let mut worst = 0.0f64;
            for i in 0..3 {
                for j in 0..3 {
                    let dot = (0..3).map(|k| a(i, k) * a(j, k)).sum::<f64>();
                    worst = worst.max((dot - if i == j { 1.0 } else { 0.0 }).abs());
                }
            }
            let det = a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1))
                - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0))
                + a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0));
            if worst > 1e-4 || det <= 0.0 {
                return fail(
                    format!("{base}.matrix"),
                    format!(
                        "must be a rotation (rows orthonormal to 1e-4, determinant +1; got rows off by {worst:.2e}, \
                         determinant {det:.4}): a sphere's size is its `radius`, and it cannot be mirrored"
                    ),
                );
            }
            Ok(())
        }
    }
}

fn validate_transform(base: &str, transform: &TransformDesc) -> Check {
    match transform {
        TransformDesc::Components { scale, rotate_x, rotate_y, rotate_z, translate } => {
            // A uniform scale may have been written as one number: point at
            // the field rather than at a component.
            let uniform = scale[0] == scale[1] && scale[1] == scale[2];
            for (i, s) in scale.iter().enumerate() {
                let path = if uniform { format!("{base}.scale") } else { format!("{base}.scale[{i}]") };
                finite(&path, *s)?;
                if *s == 0.0 {
                    return fail(path, "scale factors must be non-zero");
                }
            }
            finite(&format!("{base}.rotate_x"), *rotate_x)?;
            finite(&format!("{base}.rotate_y"), *rotate_y)?;
            finite(&format!("{base}.rotate_z"), *rotate_z)?;
            vector(&format!("{base}.translate"), translate)
        }
        TransformDesc::Matrix(m) => {
            for (r, row) in m.iter().enumerate() {
                for (c, x) in row.iter().enumerate() {
                    finite(&format!("{base}.matrix[{r}][{c}]"), *x)?;
                }
            }
            if m[3] != [0.0, 0.0, 0.0, 1.0] {
                return fail(
                    format!("{base}.matrix[3]"),
                    "the last row must be [0, 0, 0, 1] (only affine transforms are supported)",
                );
            }
            let a = |r: usize, c: usize| f64::from(m[r][c]);
            let det = a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1))
                - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0))
                + a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0));
            let size = (0..3).flat_map(|r| (0..3).map(move |c| (r, c))).map(|(r, c)| a(r, c).abs()).fold(0.0, f64::max);
            if det.abs() <= 1e-12 * size * size * size {
                return fail(
                    format!("{base}.matrix"),
                    "the upper 3x3 block is singular; the transform must be invertible",
                );
            }
            Ok(())
        }
    }
}

// ---------------------------------------------------------------------------
// Lights
// ---------------------------------------------------------------------------

fn validate_light(desc: &SceneDesc, base: &str, light: &LightDesc) -> Check {
    match light {
        LightDesc::Point(p) => {
            vector(&format!("{base}.position"), &p.position)?;
            color(&format!("{base}.intensity"), &p.intensity, non_negative)
        }
        LightDesc::Spot(s) => {
            vector(&format!("{base}.position"), &s.position)?;
            match &s.aim {
                SpotAimDesc::Target(target) => {
                    let path = format!("{base}.target");
                    vector(&path, target)?;
                    if length(difference(target, &s.position)) == 0.0 {
                        return fail(path, "must differ from `position`");
                    }
                }
                SpotAimDesc::Direction(direction) => {
                    non_zero_vector(&format!("{base}.direction"), direction)?;
                }
            }
            color(&format!("{base}.intensity"), &s.intensity, non_negative)?;
            let cutoff_path = format!("{base}.cutoff_angle");
            finite(&cutoff_path, s.cutoff_angle)?;
            if !(s.cutoff_angle > 0.0 && s.cutoff_angle <= 90.0) {
                return fail(cutoff_path, format!("must be in (0, 90] degrees, got {}", s.cutoff_angle));
            }
            let beam_path = format!("{base}.beam_width");
            finite(&beam_path, s.beam_width)?;
            if !(s.beam_width > 0.0 && s.beam_width <= s.cutoff_angle) {
                return fail(
                    beam_path,
                    format!("must be in (0, cutoff_angle = {}] degrees, got {}", s.cutoff_angle, s.beam_width),
                );
            }
            Ok(())
        }
        LightDesc::Directional(d) => {
            non_zero_vector(&format!("{base}.direction"), &d.direction)?;
            color(&format!("{base}.irradiance"), &d.irradiance, non_negative)
        }
        LightDesc::Constant(c) => color(&format!("{base}.radiance"), &c.radiance, non_negative),
        LightDesc::Area(a) => {
            let shape = format!("{base}.shape");
            if matches!(a.shape.geometry, GeometryDesc::Box(_)) {
                return fail(
                    format!("{shape}.type"),
                    "an area light is a rectangle, a disk, a sphere or a mesh, got box (write it as a mesh)",
                );
            }
            if matches!(a.shape.geometry, GeometryDesc::Mesh(_)) && a.shape.motion.is_some() {
                return fail(format!("{shape}.motion"), "an emitting mesh cannot move (motion is not supported there)");
            }
            if a.shape.interior.is_some() || a.shape.exterior.is_some() || a.shape.bsdf != BsdfDesc::Null {
                return fail(shape, "an area light's shape takes no `interior`, `exterior` or `bsdf` (it is black)");
            }
            validate_shape(desc, &shape, &a.shape)?;
            color(&format!("{base}.radiance"), &a.radiance, non_negative)
        }
        LightDesc::Envmap(e) => {
            if e.file.is_empty() {
                return fail(format!("{base}.file"), "expected the path of an EXR file");
            }
            finite(&format!("{base}.scale"), e.scale)?;
            if e.scale < 0.0 {
                return fail(format!("{base}.scale"), format!("must be >= 0, got {}", e.scale));
            }
            validate_transform(&format!("{base}.to_world"), &e.to_world)
        }
    }
}
