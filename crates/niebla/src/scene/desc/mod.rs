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
    /// `"type": "volpath"`: unbiased volumetric path tracing (all orders of
    /// scattering).
    VolPath(VolPathDesc),
    /// `"type": "analytic"`: closed-form single scattering (Sun et al. 2005)
    /// in homogeneous media from point and spot lights; no parameters.
    Analytic,
    /// `"type": "hegeman"`: single scattering plus the blurred
    /// multiple-scattering approximation of Hegeman et al. 2005
    /// (reconstructed), interactive.
    Hegeman(HegemanDesc),
    /// `"type": "zhou"`: compensated ray marching (Zhou et al. 2008,
    /// reconstructed): RBF density fit, SH environment lighting, diffusion.
    Zhou(ZhouDesc),
    /// `"type": "photon"`: volumetric photon mapping (Jensen and Christensen
    /// 1998) with one photon map per render.
    Photon(PhotonDesc),
    /// `"type": "ppm"`: progressive photon mapping (Knaus and Zwicker 2011):
    /// a photon map and a smaller radius per pass; converges to `volpath`.
    Ppm(PhotonDesc),
}

/// Settings of the `photon` and `ppm` integrators. Every field is optional.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PhotonDesc {
    /// Photons emitted (`photons`, >= 1; per pass for `ppm`).
    pub photons: Option<u32>,
    /// Neighbours of a k-nearest estimate (`k`, >= 1; `photon` only). With
    /// `radius` and no `k`, `photon` gathers within the fixed radius.
    pub k: Option<u32>,
    /// Volume gather radius in scene units (`radius`, > 0): fixed radius, cap
    /// of the k-nearest search, or `ppm`'s initial radius.
    pub radius: Option<f32>,
    /// Surface gather radius in scene units (`surface_radius`, > 0).
    pub surface_radius: Option<f32>,
    /// Ray-march step of point queries (`step` or `steps`).
    pub march: MarchStepDesc,
    /// `query`: `"march"` (point queries, default) or `"beam"` (beam
    /// radiance estimate).
    pub beam: bool,
    /// Single-scattering sampling along camera rays (`sampling`, default `mis`).
    pub sampling: Option<ScatterSamplingDesc>,
    /// Largest number of scattering events on a photon path (`max_depth`, >= 1).
    pub max_depth: Option<u32>,
    /// `ppm`'s radius reduction in (0, 1) (`alpha`, default 2/3).
    pub alpha: Option<f32>,
}

/// Settings of the `hegeman` integrator (`"type": "hegeman"`).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HegemanDesc {
    /// Include the multiple-scattering term (`multiple_scattering`, default true).
    #[serde(default = "default_true")]
    pub multiple_scattering: bool,
    /// Lattice nodes of the per-light volumes along a grid medium's longest
    /// side (`resolution`, 2 to 512; default 48).
    #[serde(default = "default_hegeman_resolution")]
    pub resolution: u32,
    /// View-ray march step in lattice cells (`step_cells`, > 0; default 1).
    #[serde(default = "default_one")]
    pub step_cells: f32,
}

/// Settings of the `zhou` integrator (`"type": "zhou"`). Every field is optional.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ZhouDesc {
    /// RBFs per grid medium (`rbf_count`, 1 to 20000; default 600).
    #[serde(default = "default_rbf_count")]
    pub rbf_count: u32,
    /// L-BFGS iterations of the fit (`fit_iterations`, 0 to 10000; default 60).
    #[serde(default = "default_fit_iterations")]
    pub fit_iterations: u32,
    /// Lattice nodes along a grid medium's longest side (`resolution`, 4 to
    /// 128; default 48). Memory grows as its cube: about 0.5 KiB per node at
    /// `sh_order` 4 during the precomputation (measured: 529 MB peak at 96 on
    /// the smoke scene; 128: about 1.1 GB).
    #[serde(default = "default_hegeman_resolution")]
    pub resolution: u32,
    /// SH order of lighting and source radiance (`sh_order`, 1 to 6; default 4).
    #[serde(default = "default_sh_order")]
    pub sh_order: u32,
    /// Include the diffusion term (`multiple_scattering`, default true).
    #[serde(default = "default_true")]
    pub multiple_scattering: bool,
    /// How the residual enters the view-ray march (`compensation`: `"full"`,
    /// `"source"` or `"off"`; default `"full"`).
    #[serde(default)]
    pub compensation: CompensationDesc,
    /// Transmittance toward the environment at the RBF centres
    /// (`transmittance`: `"sh"` (rotated zonal table, default) or `"exact"`).
    #[serde(default)]
    pub transmittance: ZhouTransmittanceDesc,
    /// View-ray march step in lattice cells (`step_cells`, > 0; default 1).
    #[serde(default = "default_one")]
    pub step_cells: f32,
    /// Read and write RBF fits in the cache folder (`cache`, default true).
    #[serde(default = "default_true")]
    pub cache: bool,
}

/// `compensation` of the `zhou` integrator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CompensationDesc {
    /// The full density for source and attenuation.
    #[default]
    Full,
    /// The full density for the source, the RBF density for attenuation.
    Source,
    /// The RBF density everywhere.
    Off,
}

/// `transmittance` of the `zhou` integrator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ZhouTransmittanceDesc {
    /// Rotated zonal optical-depth table.
    #[default]
    Sh,
    /// Closed form per quadrature direction.
    Exact,
}

fn default_rbf_count() -> u32 {
    600
}

fn default_fit_iterations() -> u32 {
    60
}

fn default_sh_order() -> u32 {
    4
}

fn default_true() -> bool {
    true
}

fn default_hegeman_resolution() -> u32 {
    48
}

fn default_one() -> f32 {
    1.0
}

impl IntegratorDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] =
        &["single", "emission", "volpath", "analytic", "hegeman", "zhou", "photon", "ppm"];
}

/// Settings of the volumetric path tracer (`"type": "volpath"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VolPathDesc {
    /// Largest number of scattering events on a path (`max_depth`, >= 1;
    /// default 1024).
    pub max_depth: u32,
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

mod medium;
mod shapes;

pub use medium::*;
pub use shapes::*;
