//! The scene description: plain data read from a scene file (JSON, version 1).
//!
//! These types mirror the file one to one, with defaults filled in and the
//! "one of two forms" choices (`sigma_a`/`sigma_s` or `sigma_t`/`albedo`, a
//! spot light's `target` or `direction`, ...) resolved into enums. They hold
//! names and numbers only; `Scene::build` turns them into runtime structures
//! with typed ids. Parse with [`parse_scene_str`](super::parse_scene_str) or
//! [`load_scene_file`](super::load_scene_file), which also run
//! [`SceneDesc::validate`].
//!
//! Units: lengths in scene units, coefficients per scene unit, angles in
//! degrees, colors linear Rec.709 RGB. Vectors are `[x, y, z]` arrays.
//! Numbers, vectors and colors are read here; the tagged types (`type`
//! fields) have hand-written `Deserialize` implementations in `parse.rs`.

use std::collections::BTreeMap;

use std::fmt;

use serde::de::{self, Deserializer, IgnoredAny, SeqAccess, Visitor};
use serde::Deserialize;

use crate::color::Rgb;

/// The scene file format version this build reads.
pub const SCENE_VERSION: u32 = 1;

/// A whole scene file.
///
/// Read it with [`parse_scene_str`](super::parse_scene_str) or
/// [`load_scene_file`](super::load_scene_file) rather than with
/// `serde_json` directly: they add the file name, full JSON paths, duplicate
/// key detection and validation to the errors.
///
/// ```
/// let desc = niebla::scene::parse_scene_str(
///     r#"{"version": 1,
///         "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 1, 0],
///                    "width": 64, "height": 48}}"#,
///     "example.json",
/// ).unwrap();
/// assert_eq!(desc.render.spp, 16);
/// assert!(desc.media.is_empty());
/// ```
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// File format version; must be [`SCENE_VERSION`] (1).
    pub version: u32,
    /// The camera (required).
    pub camera: CameraDesc,
    /// Integrator, samples per pixel, seed and exposure (all optional).
    #[serde(default)]
    pub render: RenderDesc,
    /// Participating media by name. Shapes and `ambient_medium` refer to them
    /// by name; ordered by name, so ids assigned in iteration order are stable.
    #[serde(default)]
    pub media: BTreeMap<String, MediumDesc>,
    /// Surfaces and medium boundaries, in file order.
    #[serde(default)]
    pub shapes: Vec<ShapeDesc>,
    /// Light sources, in file order.
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    /// Name of the medium filling space outside every shape (the medium the
    /// camera starts in unless it is inside a shape with an `interior`);
    /// `None` means vacuum.
    #[serde(default)]
    pub ambient_medium: Option<String>,
}

// ---------------------------------------------------------------------------
// Colors and vectors
// ---------------------------------------------------------------------------

/// A color or per-channel coefficient: a scalar (the same in every channel)
/// or `[r, g, b]` in linear Rec.709 RGB. Written in files as `0.5` or
/// `[0.08, 0.09, 0.1]`; anything else is an error "expected a number or an
/// array of 3 numbers".
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ColorDesc {
    /// The same value in all three channels.
    Gray(f32),
    /// Red, green, blue.
    Rgb([f32; 3]),
}

impl ColorDesc {
    /// The three channels (a gray value repeated).
    pub fn channels(&self) -> [f32; 3] {
        match *self {
            ColorDesc::Gray(v) => [v; 3],
            ColorDesc::Rgb(c) => c,
        }
    }

    /// As the renderer's RGB type.
    pub fn to_rgb(&self) -> Rgb {
        Rgb(self.channels())
    }
}

// ---------------------------------------------------------------------------
// Reading numbers, vectors and colors
// ---------------------------------------------------------------------------

/// A number or an array of exactly three numbers.
enum ScalarOrTriple {
    Scalar(f32),
    Triple([f32; 3]),
}

/// Reads [`ScalarOrTriple`]; `allow_scalar: false` demands the array.
struct TripleVisitor {
    allow_scalar: bool,
    expecting: &'static str,
}

impl TripleVisitor {
    fn scalar<E: de::Error>(self, v: f64, unexpected: de::Unexpected) -> Result<ScalarOrTriple, E> {
        if self.allow_scalar {
            Ok(ScalarOrTriple::Scalar(v as f32))
        } else {
            Err(E::invalid_type(unexpected, &self))
        }
    }
}

impl<'de> Visitor<'de> for TripleVisitor {
    type Value = ScalarOrTriple;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(self.expecting)
    }

    fn visit_f64<E: de::Error>(self, v: f64) -> Result<ScalarOrTriple, E> {
        self.scalar(v, de::Unexpected::Float(v))
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<ScalarOrTriple, E> {
        self.scalar(v as f64, de::Unexpected::Signed(v))
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<ScalarOrTriple, E> {
        self.scalar(v as f64, de::Unexpected::Unsigned(v))
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<ScalarOrTriple, A::Error> {
        let mut out = [0.0f32; 3];
        for (i, slot) in out.iter_mut().enumerate() {
            match seq.next_element::<Number>()? {
                Some(Number(x)) => *slot = x,
                None => return Err(de::Error::invalid_length(i, &self)),
            }
        }
        let mut len = 3;
        while seq.next_element::<IgnoredAny>()?.is_some() {
            len += 1;
        }
        if len != 3 {
            return Err(de::Error::invalid_length(len, &self));
        }
        Ok(ScalarOrTriple::Triple(out))
    }
}

/// One number (integer or float) as `f32`. Values beyond the `f32` range
/// become infinite and are rejected by validation, with their path.
struct Number(f32);

impl<'de> Deserialize<'de> for Number {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Number, D::Error> {
        struct NumberVisitor;
        impl Visitor<'_> for NumberVisitor {
            type Value = Number;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Number, E> {
                Ok(Number(v as f32))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Number, E> {
                Ok(Number(v as f32))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Number, E> {
                Ok(Number(v as f32))
            }
        }
        deserializer.deserialize_any(NumberVisitor)
    }
}

const VEC3_EXPECTING: &str = "an array of 3 numbers [x, y, z]";

/// `deserialize_with` for a vector field: an array of exactly 3 numbers.
pub(super) fn vec3<'de, D: Deserializer<'de>>(deserializer: D) -> Result<[f32; 3], D::Error> {
    let visitor = TripleVisitor { allow_scalar: false, expecting: VEC3_EXPECTING };
    match deserializer.deserialize_any(visitor)? {
        ScalarOrTriple::Triple(v) => Ok(v),
        // Unreachable with `allow_scalar: false`; answered anyway, never a panic.
        ScalarOrTriple::Scalar(_) => Err(de::Error::custom(format!("expected {VEC3_EXPECTING}"))),
    }
}

/// `deserialize_with` for an optional vector field (with `#[serde(default)]`).
pub(super) fn optional_vec3<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<[f32; 3]>, D::Error> {
    vec3(deserializer).map(Some)
}

/// `deserialize_with` for an optional scale: a number (uniform) or 3 numbers.
pub(super) fn optional_scale<'de, D: Deserializer<'de>>(deserializer: D) -> Result<Option<[f32; 3]>, D::Error> {
    let visitor = TripleVisitor { allow_scalar: true, expecting: "a number or an array of 3 numbers [x, y, z]" };
    Ok(Some(match deserializer.deserialize_any(visitor)? {
        ScalarOrTriple::Scalar(s) => [s; 3],
        ScalarOrTriple::Triple(v) => v,
    }))
}

impl<'de> Deserialize<'de> for ColorDesc {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<ColorDesc, D::Error> {
        let visitor = TripleVisitor { allow_scalar: true, expecting: "a number or an array of 3 numbers [r, g, b]" };
        Ok(match deserializer.deserialize_any(visitor)? {
            ScalarOrTriple::Scalar(v) => ColorDesc::Gray(v),
            ScalarOrTriple::Triple(c) => ColorDesc::Rgb(c),
        })
    }
}

/// Reads a [`ResolutionDesc`]: a whole number or an array of exactly three.
struct ResolutionVisitor;

impl ResolutionVisitor {
    fn uniform<E: de::Error>(self, v: u64) -> Result<ResolutionDesc, E> {
        u32::try_from(v).map(ResolutionDesc::Uniform).map_err(|_| E::invalid_value(de::Unexpected::Unsigned(v), &self))
    }
}

impl<'de> Visitor<'de> for ResolutionVisitor {
    type Value = ResolutionDesc;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a whole number >= 1 or an array of 3 whole numbers [nx, ny, nz]")
    }

    fn visit_u64<E: de::Error>(self, v: u64) -> Result<ResolutionDesc, E> {
        self.uniform(v)
    }

    fn visit_i64<E: de::Error>(self, v: i64) -> Result<ResolutionDesc, E> {
        match u64::try_from(v) {
            Ok(v) => self.uniform(v),
            Err(_) => Err(E::invalid_value(de::Unexpected::Signed(v), &self)),
        }
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<ResolutionDesc, A::Error> {
        let mut out = [0u32; 3];
        for (i, slot) in out.iter_mut().enumerate() {
            match seq.next_element::<u32>()? {
                Some(n) => *slot = n,
                None => return Err(de::Error::invalid_length(i, &self)),
            }
        }
        let mut len = 3;
        while seq.next_element::<IgnoredAny>()?.is_some() {
            len += 1;
        }
        if len != 3 {
            return Err(de::Error::invalid_length(len, &self));
        }
        Ok(ResolutionDesc::PerAxis(out))
    }
}

impl<'de> Deserialize<'de> for ResolutionDesc {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<ResolutionDesc, D::Error> {
        deserializer.deserialize_any(ResolutionVisitor)
    }
}

// ---------------------------------------------------------------------------
// Camera
// ---------------------------------------------------------------------------

/// The camera, tagged by `type` in the file. Only `perspective` exists.
#[derive(Clone, Debug, PartialEq)]
pub enum CameraDesc {
    /// `"type": "perspective"`: a pinhole camera.
    Perspective(PerspectiveCameraDesc),
}

impl CameraDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["perspective"];
}

/// A pinhole camera looking from `position` toward `target`.
///
/// The image has `width` x `height` pixels (each at most 16384, together at
/// most 2^26); row 0 is the top of the image and columns increase toward the
/// camera's right.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PerspectiveCameraDesc {
    /// Eye point, in scene units.
    #[serde(deserialize_with = "vec3")]
    pub position: [f32; 3],
    /// A point the camera looks at; must differ from `position`.
    #[serde(deserialize_with = "vec3")]
    pub target: [f32; 3],
    /// Approximate up direction (default `[0, 1, 0]`); must not be parallel to
    /// the view direction. Need not be unit length or orthogonal.
    #[serde(default = "default_up", deserialize_with = "vec3")]
    pub up: [f32; 3],
    /// Full vertical field of view in degrees, in (0, 180); default 40.
    #[serde(default = "default_fov_y")]
    pub fov_y: f32,
    /// Image width in pixels, 1 to 16384.
    pub width: u32,
    /// Image height in pixels, 1 to 16384.
    pub height: u32,
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

fn default_fov_y() -> f32 {
    40.0
}

// ---------------------------------------------------------------------------
// Render settings
// ---------------------------------------------------------------------------

/// How to render: integrator, samples, seed and exposure. Every field has a
/// default, and so does the whole object.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    /// The light transport algorithm; default single scattering with defaults.
    #[serde(default)]
    pub integrator: IntegratorDesc,
    /// Samples per pixel, at least 1; default 16.
    #[serde(default = "default_spp")]
    pub spp: u32,
    /// Seed of the random numbers; sample `s` of pixel `(x, y)` depends only on
    /// `(seed, x, y, s)`. Default 0.
    #[serde(default)]
    pub seed: u64,
    /// Exposure in stops for PNG output: the image is scaled by `2^exposure`
    /// before the sRGB curve. Does not affect EXR. Default 0.
    #[serde(default)]
    pub exposure: f32,
}

fn default_spp() -> u32 {
    16
}

impl Default for RenderDesc {
    fn default() -> RenderDesc {
        RenderDesc { integrator: IntegratorDesc::default(), spp: default_spp(), seed: 0, exposure: 0.0 }
    }
}

/// The integrator, tagged by `type` in the file. New integrators add a
/// variant here, a name in `IntegratorDesc::TYPES` and an arm in `parse.rs`.
#[derive(Clone, Debug, PartialEq)]
pub enum IntegratorDesc {
    /// `"type": "single"`: single scattering by ray marching or analytic
    /// sampling along camera rays, plus medium emission.
    Single(SingleScatteringDesc),
    /// `"type": "emission"`: medium emission attenuated by transmittance only
    /// (no scattering).
    Emission(EmissionIntegratorDesc),
}

impl IntegratorDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["single", "emission"];
}

impl Default for IntegratorDesc {
    fn default() -> IntegratorDesc {
        IntegratorDesc::Single(SingleScatteringDesc::default())
    }
}

/// Settings of the single-scattering integrator (`"type": "single"`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SingleScatteringDesc {
    /// Ray-march step (`step` or `steps` in the file; default chosen by the
    /// renderer).
    pub march: MarchStepDesc,
    /// How scattering points along a ray are chosen (`sampling`; default
    /// `march`).
    pub sampling: ScatterSamplingDesc,
    /// How transmittance to the light is estimated (`transmittance`; default
    /// `analytic`).
    pub transmittance: TransmittanceDesc,
}

/// Settings of the emission-only integrator (`"type": "emission"`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EmissionIntegratorDesc {
    /// Ray-march step (`step` or `steps` in the file; default chosen by the
    /// renderer).
    pub march: MarchStepDesc,
    /// How transmittance is estimated (`transmittance`; default `analytic`).
    pub transmittance: TransmittanceDesc,
}

/// Ray-marching resolution. In the file, `step` (a length) and `steps` (a
/// count) are mutually exclusive; neither means [`MarchStepDesc::Auto`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum MarchStepDesc {
    /// The renderer chooses (from the media's extent and coefficients).
    #[default]
    Auto,
    /// `step`: step length in scene units, > 0.
    Length(f32),
    /// `steps`: number of steps per medium segment along a ray, >= 1.
    PerSegment(u32),
}

/// How single scattering chooses points along a camera ray (`sampling`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScatterSamplingDesc {
    /// `"march"`: deterministic-offset ray marching with the integrator's step.
    #[default]
    March,
    /// `"equiangular"`: equiangular sampling toward each point or spot light
    /// (Kulla and Fajardo 2012).
    Equiangular,
    /// `"mis"`: distance (transmittance) sampling and equiangular sampling
    /// combined with multiple importance sampling.
    Mis,
}

/// How transmittance is estimated (`transmittance`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TransmittanceDesc {
    /// `"analytic"`: exact Beer-Lambert `exp(-sigma_t d)` in homogeneous media.
    #[default]
    Analytic,
    /// `"ray_march"`: numerical quadrature of the optical depth with the
    /// integrator's step.
    RayMarch,
    /// `"delta"`: delta tracking against the majorant grid (a binary, unbiased
    /// estimate; Woodcock et al. 1965).
    Delta,
    /// `"ratio"`: ratio tracking against the majorant grid (unbiased; Novak
    /// et al. 2014).
    Ratio,
    /// `"residual_ratio"`: residual ratio tracking with a per-cell control
    /// extinction (unbiased; Novak et al. 2014).
    ResidualRatio,
}

// ---------------------------------------------------------------------------
// Media
// ---------------------------------------------------------------------------

/// A participating medium, tagged by `type` in the file; `type` may be left
/// out and defaults to `grid` when the medium has a `density`, else to
/// `homogeneous`.
// A handful of descriptions per scene, read once: boxing the large variant
// would only make matching on it clumsier.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq)]
pub enum MediumDesc {
    /// `"type": "homogeneous"`: constant coefficients.
    Homogeneous(HomogeneousMediumDesc),
    /// `"type": "grid"`: coefficients per unit density times a voxel density.
    Grid(GridMediumDesc),
}

impl MediumDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["homogeneous", "grid"];

    /// The phase function, whatever the type.
    pub fn phase(&self) -> &PhaseDesc {
        match self {
            MediumDesc::Homogeneous(m) => &m.phase,
            MediumDesc::Grid(m) => &m.phase,
        }
    }
}

/// A medium with the same coefficients everywhere.
#[derive(Clone, Debug, PartialEq)]
pub struct HomogeneousMediumDesc {
    /// Absorption and scattering, in one of the two forms of the file.
    pub coefficients: CoefficientsDesc,
    /// Multiplies the coefficients (not the albedo); > 0, default 1.
    pub scale: f32,
    /// Phase function; default isotropic.
    pub phase: PhaseDesc,
    /// Emitted radiance, if the medium glows.
    pub emission: Option<EmissionDesc>,
}

impl HomogeneousMediumDesc {
    /// `(sigma_a, sigma_s)` per scene unit, with `scale` applied, whichever
    /// form the file used.
    pub fn sigma_a_sigma_s(&self) -> (Rgb, Rgb) {
        let (sigma_a, sigma_s) = self.coefficients.sigma_a_sigma_s();
        (sigma_a * self.scale, sigma_s * self.scale)
    }
}

/// The optical coefficients of a medium, per scene unit (before `scale`). A
/// file gives exactly one of the two forms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CoefficientsDesc {
    /// `sigma_a` and `sigma_s`: absorption and scattering coefficients, each
    /// finite and >= 0.
    AbsorptionScattering {
        /// Absorption coefficient sigma_a, >= 0.
        sigma_a: ColorDesc,
        /// Scattering coefficient sigma_s, >= 0.
        sigma_s: ColorDesc,
    },
    /// `sigma_t` and `albedo`: extinction coefficient (>= 0) and single
    /// scattering albedo `sigma_s / sigma_t` in [0, 1].
    ExtinctionAlbedo {
        /// Extinction coefficient sigma_t = sigma_a + sigma_s, >= 0.
        sigma_t: ColorDesc,
        /// Single-scattering albedo in [0, 1].
        albedo: ColorDesc,
    },
}

impl CoefficientsDesc {
    /// `(sigma_a, sigma_s)` per scene unit, converting from `sigma_t` and
    /// `albedo` if needed (`sigma_s = albedo sigma_t`, `sigma_a = sigma_t -
    /// sigma_s`).
    pub fn sigma_a_sigma_s(&self) -> (Rgb, Rgb) {
        match self {
            CoefficientsDesc::AbsorptionScattering { sigma_a, sigma_s } => (sigma_a.to_rgb(), sigma_s.to_rgb()),
            CoefficientsDesc::ExtinctionAlbedo { sigma_t, albedo } => {
                let sigma_t = sigma_t.to_rgb();
                let sigma_s = sigma_t * albedo.to_rgb();
                (sigma_t - sigma_s, sigma_s)
            }
        }
    }
}

/// Light emitted by a medium.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmissionDesc {
    /// `L_ve`: emitted radiance per unit length, W/(sr m^2) per scene unit;
    /// finite and >= 0. Not multiplied by `scale` or by sigma_a.
    #[serde(rename = "L_ve")]
    pub l_ve: ColorDesc,
}

/// A heterogeneous medium: `sigma_x(p) = density(p) * scale * sigma_x`.
///
/// In a file:
/// ```json
/// {"type": "grid", "density": {"type": "vdb", "file": "plume.vdb"},
///  "sigma_t": 30, "albedo": 0.8, "phase": {"type": "hg", "g": 0.3},
///  "to_world": {"scale": 2}, "majorant_resolution": 16,
///  "emission": {"temperature": {"type": "vdb", "file": "plume.vdb", "grid": "temperature"}}}
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct GridMediumDesc {
    /// Absorption and scattering per unit density, in one of the two forms.
    pub coefficients: CoefficientsDesc,
    /// Multiplies the coefficients (not the albedo); > 0, default 1.
    pub scale: f32,
    /// Phase function; default isotropic.
    pub phase: PhaseDesc,
    /// The density (dimensionless multiplier of the coefficients; finite and
    /// >= 0 everywhere).
    pub density: DensitySourceDesc,
    /// Places the density source's space in the world: a dense source's box,
    /// or a VDB grid's own world space (after its index-to-world map).
    /// Default identity.
    pub to_world: TransformDesc,
    /// Emitted radiance, if the medium glows.
    pub emission: Option<GridEmissionDesc>,
    /// Resolution of the majorant grid; `None` is the default (16^3 cells,
    /// at most one per voxel, for dense sources; one cell per VDB leaf within
    /// [`MajorantGrid::DEFAULT_MAX_CELLS`](niebla_volume::MajorantGrid::DEFAULT_MAX_CELLS)
    /// cells for VDB grids).
    pub majorant_resolution: Option<ResolutionDesc>,
}

impl GridMediumDesc {
    /// `(sigma_a, sigma_s)` per scene unit per unit density, with `scale`
    /// applied, whichever form the file used.
    pub fn sigma_a_sigma_s(&self) -> (Rgb, Rgb) {
        let (sigma_a, sigma_s) = self.coefficients.sigma_a_sigma_s();
        (sigma_a * self.scale, sigma_s * self.scale)
    }
}

/// Largest majorant grid resolution per axis a file may ask for.
pub const MAX_MAJORANT_RESOLUTION: u32 = 256;
/// Largest number of voxels of an inline or procedural grid (2^28).
pub const MAX_GRID_VOXELS: u64 = 1 << 28;

/// A resolution: one number for all three axes, or `[nx, ny, nz]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResolutionDesc {
    /// The same count on every axis.
    Uniform(u32),
    /// Per axis, `[nx, ny, nz]`.
    PerAxis([u32; 3]),
}

impl ResolutionDesc {
    /// `[nx, ny, nz]`.
    pub fn dims(&self) -> [u32; 3] {
        match *self {
            ResolutionDesc::Uniform(n) => [n; 3],
            ResolutionDesc::PerAxis(d) => d,
        }
    }
}

/// An axis-aligned box `{"min": [x, y, z], "max": [x, y, z]}`; `max` exceeds
/// `min` on every axis. The default is the unit box `[0, 1]^3`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundsDesc {
    /// Lowest corner.
    #[serde(deserialize_with = "vec3")]
    pub min: [f32; 3],
    /// Highest corner.
    #[serde(deserialize_with = "vec3")]
    pub max: [f32; 3],
}

impl BoundsDesc {
    /// The unit box `[0, 1]^3`.
    pub const UNIT: BoundsDesc = BoundsDesc { min: [0.0; 3], max: [1.0; 3] };
}

impl Default for BoundsDesc {
    fn default() -> BoundsDesc {
        BoundsDesc::UNIT
    }
}

/// Where a scalar field (a density, an emission grid, a temperature) comes
/// from, tagged by `type` in the file. Dense sources (`constant`, `grid`,
/// `npy`, `vol`, `procedural`) fill a box with `nx * ny * nz` values at cell
/// centers, indexed `[z][y][x]` with x fastest; `vdb` keeps the file's
/// sparse grid and its index-to-world map. File names are relative to the
/// scene file's folder.
#[derive(Clone, Debug, PartialEq)]
pub enum DensitySourceDesc {
    /// `"constant"`: one value filling `bounds`.
    Constant {
        /// The value, finite and >= 0; default 1.
        value: f32,
        /// The box it fills; default the unit box.
        bounds: BoundsDesc,
    },
    /// `"grid"`: a small grid written in the scene file.
    Grid(InlineGridDesc),
    /// `"npy"`: a NumPy `.npy` array of shape `(nz, ny, nx)`, float32 or
    /// float64, filling `bounds`.
    Npy {
        /// The file.
        file: String,
        /// The box it fills; default the unit box.
        bounds: BoundsDesc,
    },
    /// `"vol"`: a Mitsuba 3 binary `.vol` grid; its box is stored in the file.
    Vol {
        /// The file.
        file: String,
    },
    /// `"vdb"`: one float grid of an OpenVDB file.
    Vdb {
        /// The file.
        file: String,
        /// The grid's name; default `"density"`.
        grid: String,
    },
    /// `"procedural"`: seeded fractal noise over the unit box `[0, 1]^3`.
    Procedural(ProceduralDesc),
}

impl DensitySourceDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["constant", "grid", "npy", "vol", "vdb", "procedural"];

    /// The file the source reads, if any (relative to the scene's folder).
    pub fn file(&self) -> Option<&str> {
        match self {
            DensitySourceDesc::Npy { file, .. }
            | DensitySourceDesc::Vol { file }
            | DensitySourceDesc::Vdb { file, .. } => Some(file),
            _ => None,
        }
    }
}

/// A grid written inline: `{"type": "grid", "data": [...], "dims": [nx, ny,
/// nz], "bounds": {...}}`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InlineGridDesc {
    /// `nx * ny * nz` values, `[z][y][x]` with x fastest, each finite and
    /// >= 0.
    pub data: Vec<f32>,
    /// `[nx, ny, nz]`, each >= 1, product at most 2^28.
    pub dims: [u32; 3],
    /// The box the grid fills; default the unit box.
    #[serde(default)]
    pub bounds: BoundsDesc,
}

/// Seeded fractal noise (`"type": "procedural"`) over the unit box `[0,
/// 1]^3`, y up, baked by [`niebla_volume::procedural_density`]; values in
/// [0, 1].
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProceduralDesc {
    /// `"cloud"` (default) or `"plume"`.
    #[serde(default)]
    pub shape: ProceduralShapeDesc,
    /// Seed of the noise; default 0.
    #[serde(default)]
    pub seed: u64,
    /// Voxels per axis, a number or `[nx, ny, nz]`, each from 1 to 1024, at
    /// most 2^28 in all; default 64. The voxels next to each face are zero.
    #[serde(default = "default_procedural_resolution")]
    pub resolution: ResolutionDesc,
    /// Noise octaves, 1 to 12; default 5.
    #[serde(default = "default_octaves")]
    pub octaves: u32,
    /// Base frequency in cycles per unit box, in (0, 1000]; default 3.
    #[serde(default = "default_frequency")]
    pub frequency: f32,
    /// Frequency ratio between octaves, in [1, 8]; default 2.
    #[serde(default = "default_lacunarity")]
    pub lacunarity: f32,
    /// Amplitude ratio between octaves, in [0, 1] (higher is rougher);
    /// default 0.5.
    #[serde(default = "default_gain")]
    pub gain: f32,
    /// Fraction of the box the medium covers, in [0, 1]; default 0.5.
    #[serde(default = "default_coverage")]
    pub coverage: f32,
    /// Edge sharpness, in (0, 1000]: the density rises from 0 to 1 over a
    /// band `1 / sharpness` wide (1 soft, 50 nearly hard); default 4.
    #[serde(default = "default_sharpness")]
    pub sharpness: f32,
}

fn default_procedural_resolution() -> ResolutionDesc {
    ResolutionDesc::Uniform(64)
}
fn default_octaves() -> u32 {
    5
}
fn default_frequency() -> f32 {
    3.0
}
fn default_lacunarity() -> f32 {
    2.0
}
fn default_gain() -> f32 {
    0.5
}
fn default_coverage() -> f32 {
    0.5
}
fn default_sharpness() -> f32 {
    4.0
}

/// The kind of procedural field.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProceduralShapeDesc {
    /// `"cloud"`: a puffy blob.
    #[default]
    Cloud,
    /// `"plume"`: a rising column that spreads with height.
    Plume,
}

/// Light emitted by a grid medium: the file gives exactly one of `L_ve`,
/// `grid` and `temperature`.
#[derive(Clone, Debug, PartialEq)]
pub enum GridEmissionDesc {
    /// `{"L_ve": color}`: `L_ve(x) = L_ve * density(x)`.
    ProportionalToDensity {
        /// Emitted radiance per unit length at unit density, finite and >= 0.
        l_ve: ColorDesc,
    },
    /// `{"grid": source, "color": c, "emission_scale": s}`:
    /// `L_ve(x) = s * c * value(x)`.
    Field {
        /// The emission field (one channel, finite and >= 0), placed by the
        /// medium's `to_world` like the density.
        grid: DensitySourceDesc,
        /// Color, finite and >= 0; default 1.
        color: ColorDesc,
        /// Scale, finite and >= 0; default 1.
        emission_scale: f32,
    },
    /// `{"temperature": source, "emission_scale": s}`: `L_ve(x) = s *
    /// blackbody(T(x))`, the blackbody color of unit luminance at `T(x)`
    /// Kelvin (black below 400 K).
    Temperature {
        /// Temperature in Kelvin (finite and >= 0), placed by the medium's
        /// `to_world` like the density.
        temperature: DensitySourceDesc,
        /// Scale, finite and >= 0; default 1.
        emission_scale: f32,
    },
}

/// A phase function, tagged by `type` in the file; default isotropic.
///
/// Convention: `p(wo, wi)` with both directions pointing away from the
/// scattering point, normalized over the sphere; `g > 0` scatters forward.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum PhaseDesc {
    /// `"isotropic"`: `1 / (4 pi)`.
    #[default]
    Isotropic,
    /// `"hg"`: Henyey-Greenstein (1941); pbrt-v4 section 11.3.1.
    HenyeyGreenstein {
        /// Asymmetry g in (-1, 1); g > 0 scatters forward.
        g: f32,
    },
    /// `"double_hg"`: `w HG(g1) + (1 - w) HG(g2)`.
    DoubleHenyeyGreenstein {
        /// Weight of the first lobe, in [0, 1].
        w: f32,
        /// Asymmetry of the first lobe, in (-1, 1).
        g1: f32,
        /// Asymmetry of the second lobe, in (-1, 1).
        g2: f32,
    },
    /// `"schlick"`: Blasi, Le Saec and Schlick (1993) approximation of HG.
    Schlick(SchlickDesc),
    /// `"rayleigh"`: `3 / (16 pi) (1 + cos^2 theta)`.
    Rayleigh,
    /// `"cornette_shanks"`: Cornette and Shanks (1992), HG with a Rayleigh-like
    /// `(1 + cos^2 theta)` factor.
    CornetteShanks {
        /// Asymmetry parameter g in (-1, 1).
        g: f32,
    },
    /// `"tabulated"`: a phase function read from a table file.
    Tabulated {
        /// Table file, relative to the scene file's folder.
        file: String,
        /// Name of the column holding the phase values; default
        /// `"p_mie_poly"`.
        column: String,
    },
    /// `"fog"`: two-lobe HG fit of the Mie phase function of fog droplets.
    Fog,
    /// `"mie_fog"`: the built-in Mie table of fog droplets.
    MieFog,
}

impl PhaseDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] =
        &["isotropic", "hg", "double_hg", "schlick", "rayleigh", "cornette_shanks", "tabulated", "fog", "mie_fog"];
}

/// The parameter of a Schlick phase function: the file gives exactly one of
/// `k` and `g`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SchlickDesc {
    /// `k`: Schlick's own parameter, in (-1, 1).
    K(f32),
    /// `g`: the asymmetry of the HG lobe to approximate, in (-1, 1); the
    /// renderer converts it to `k` (`k = 1.55 g - 0.55 g^3`).
    G(f32),
}

// ---------------------------------------------------------------------------
// Shapes
// ---------------------------------------------------------------------------

/// A shape: its geometry (tagged by `type` in the file), the media on either
/// side and its surface.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeDesc {
    /// Geometry; `type` names it.
    pub geometry: GeometryDesc,
    /// Name of the medium inside (behind the surface normal), a key of
    /// `media`; `None` means vacuum, or for open shapes nothing.
    pub interior: Option<String>,
    /// Name of the medium outside (on the normal's side), a key of `media`;
    /// `None` means the surrounding medium.
    pub exterior: Option<String>,
    /// Surface scattering; default `null` (an index-matched medium boundary).
    pub bsdf: BsdfDesc,
}

/// The geometry of a shape.
#[derive(Clone, Debug, PartialEq)]
pub enum GeometryDesc {
    /// `"type": "sphere"`.
    Sphere(SphereDesc),
    /// `"type": "box"`: an axis-aligned box.
    Box(BoxDesc),
    /// `"type": "rectangle"`.
    Rectangle(RectangleDesc),
}

impl GeometryDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["sphere", "box", "rectangle"];
}

/// A sphere; its normal points outward.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereDesc {
    /// Center, in scene units.
    #[serde(deserialize_with = "vec3")]
    pub center: [f32; 3],
    /// Radius in scene units, > 0.
    pub radius: f32,
}

/// An axis-aligned box; its normals point outward.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxDesc {
    /// Minimum corner, in scene units.
    #[serde(deserialize_with = "vec3")]
    pub min: [f32; 3],
    /// Maximum corner; greater than `min` on every axis.
    #[serde(deserialize_with = "vec3")]
    pub max: [f32; 3],
}

/// A rectangle: the square [-1, 1]^2 in the xy plane with normal +z
/// (Mitsuba's convention), mapped by `to_world`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RectangleDesc {
    /// Object-to-world transform; default identity.
    #[serde(default)]
    pub to_world: TransformDesc,
}

/// Surface scattering, tagged by `type` in the file; default `null`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum BsdfDesc {
    /// `"null"`: no surface; light passes unchanged (an index-matched
    /// boundary between media).
    #[default]
    Null,
    /// `"diffuse"`: Lambertian reflection.
    Diffuse {
        /// Reflectance (albedo), each channel in [0, 1]; default 0.5.
        reflectance: ColorDesc,
    },
}

impl BsdfDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["null", "diffuse"];
}

/// An object-to-world transform.
///
/// In a file: an object with any of `scale` (a number or `[x, y, z]`, each
/// non-zero), `rotate_x`, `rotate_y`, `rotate_z` (degrees, right-handed about
/// the world axes) and `translate` (`[x, y, z]`), applied in that order: scale,
/// then rotate about x, then y, then z, then translate. Or just `matrix`: a
/// row-major 4x4 array of 4 rows of 4 numbers, acting on column vectors
/// `[x, y, z, 1]` (last row `[0, 0, 0, 1]`, upper 3x3 invertible).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TransformDesc {
    /// Scale, rotations and translation.
    Components {
        /// Per-axis scale factors, each non-zero (a scalar `s` in the file
        /// gives `[s, s, s]`).
        scale: [f32; 3],
        /// Rotation about the x axis, in degrees.
        rotate_x: f32,
        /// Rotation about the y axis, in degrees.
        rotate_y: f32,
        /// Rotation about the z axis, in degrees.
        rotate_z: f32,
        /// Translation, in scene units.
        translate: [f32; 3],
    },
    /// A row-major 4x4 affine matrix.
    Matrix([[f32; 4]; 4]),
}

impl TransformDesc {
    /// The identity transform.
    pub const IDENTITY: TransformDesc =
        TransformDesc::Components { scale: [1.0; 3], rotate_x: 0.0, rotate_y: 0.0, rotate_z: 0.0, translate: [0.0; 3] };
}

impl Default for TransformDesc {
    fn default() -> TransformDesc {
        TransformDesc::IDENTITY
    }
}

// ---------------------------------------------------------------------------
// Lights
// ---------------------------------------------------------------------------

/// A light source, tagged by `type` in the file. Radiometry follows Mitsuba 3.
#[derive(Clone, Debug, PartialEq)]
pub enum LightDesc {
    /// `"type": "point"`.
    Point(PointLightDesc),
    /// `"type": "spot"`.
    Spot(SpotLightDesc),
    /// `"type": "directional"`.
    Directional(DirectionalLightDesc),
    /// `"type": "constant"`: uniform environment.
    Constant(ConstantLightDesc),
}

impl LightDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["point", "spot", "directional", "constant"];
}

/// An isotropic point light.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointLightDesc {
    /// Position, in scene units.
    #[serde(deserialize_with = "vec3")]
    pub position: [f32; 3],
    /// Radiant intensity in W/sr, finite and >= 0.
    pub intensity: ColorDesc,
}

/// A spot light: a point light limited to a cone, with a smooth falloff
/// between `beam_width` and `cutoff_angle` (Mitsuba 3's `spot`).
#[derive(Clone, Debug, PartialEq)]
pub struct SpotLightDesc {
    /// Position (apex of the cone), in scene units.
    pub position: [f32; 3],
    /// Where the axis of the cone points.
    pub aim: SpotAimDesc,
    /// Radiant intensity on the axis in W/sr, finite and >= 0.
    pub intensity: ColorDesc,
    /// Half-angle of the cone in degrees, in (0, 90]; no light outside it.
    /// Default 20.
    pub cutoff_angle: f32,
    /// Half-angle in degrees within which the intensity is full, in
    /// (0, `cutoff_angle`]; default 3/4 of `cutoff_angle`.
    pub beam_width: f32,
}

/// The axis of a spot light: the file gives exactly one of `target` and
/// `direction`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpotAimDesc {
    /// `target`: a point on the axis, different from the position.
    Target([f32; 3]),
    /// `direction`: the direction of the axis (need not be unit length;
    /// non-zero).
    Direction([f32; 3]),
}

/// A directional light (infinitely far away).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DirectionalLightDesc {
    /// Direction in which the light travels (need not be unit length;
    /// non-zero).
    #[serde(deserialize_with = "vec3")]
    pub direction: [f32; 3],
    /// Irradiance in W/m^2 on a surface perpendicular to `direction`, finite
    /// and >= 0.
    pub irradiance: ColorDesc,
}

/// A uniform environment light.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstantLightDesc {
    /// Radiance in W/(sr m^2) arriving from every direction, finite and >= 0.
    pub radiance: ColorDesc,
}
