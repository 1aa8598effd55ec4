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
use crate::integrator::IntegratorSettings;
use crate::sampling::SamplerKind;

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
    /// Layers beside the beauty and the transparent background (optional).
    #[serde(default)]
    pub film: FilmDesc,
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
    /// When the shutter opens, in frames relative to the rendered frame's
    /// instant (e.g. -0.25 with `shutter_close` 0.25 is Blender's shutter
    /// 0.5 centred on the frame); finite, default 0.
    #[serde(default)]
    pub shutter_open: f32,
    /// When the shutter closes, in frames relative to the frame, at least
    /// `shutter_open`; default 0. With `shutter_open == shutter_close`
    /// nothing moves during the exposure (no motion blur, the scene renders
    /// as without these keys); otherwise each camera sample is taken at a
    /// time uniform in `[shutter_open, shutter_close]`.
    #[serde(default)]
    pub shutter_close: f32,
    /// Frames per second of the sequence, > 0; converts velocities given per
    /// second into frames (`"velocity_units"` of grid media). Default 24.
    #[serde(default = "default_fps")]
    pub fps: f32,
    /// The camera's pose one frame later (time 1): the pose at a sample's
    /// time is interpolated linearly between the camera's own fields (time
    /// 0) and these. Fields left out keep the camera's own value. Default:
    /// the camera does not move.
    #[serde(default)]
    pub motion: Option<CameraMotionDesc>,
}

/// `"motion"` of a camera: where it is one frame after the rendered frame.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraMotionDesc {
    /// Eye point at time 1 (default: the camera's `position`).
    #[serde(default, deserialize_with = "optional_vec3")]
    pub position: Option<[f32; 3]>,
    /// Target at time 1 (default: the camera's `target`).
    #[serde(default, deserialize_with = "optional_vec3")]
    pub target: Option<[f32; 3]>,
    /// Approximate up at time 1 (default: the camera's `up`).
    #[serde(default, deserialize_with = "optional_vec3")]
    pub up: Option<[f32; 3]>,
}

fn default_fps() -> f32 {
    24.0
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

/// How to render: integrator, samples, seed, sampler and exposure. Every field has a
/// default, and so does the whole object.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    /// The light transport algorithm; default single scattering with defaults.
    #[serde(default)]
    pub integrator: IntegratorSpec,
    /// Samples per pixel, at least 1; default 16.
    #[serde(default = "default_spp")]
    pub spp: u32,
    /// Seed of the random numbers; sample `s` of pixel `(x, y)` depends only on
    /// `(seed, x, y, s)`. Default 0.
    #[serde(default)]
    pub seed: u64,
    /// The numbers of the camera samples: `"independent"` or `"sobol"`
    /// (Owen-scrambled Sobol points, [`crate::sampling::sobol`]). Default
    /// [`SamplerKind::default`].
    #[serde(default)]
    pub sampler: SamplerKind,
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
        let sampler = SamplerKind::default();
        RenderDesc { integrator: IntegratorSpec::default(), spp: default_spp(), seed: 0, sampler, exposure: 0.0 }
    }
}

/// The `render.integrator` object as written (its `type` and that
/// integrator's fields) and the settings the integrator registry read from
/// it ([`crate::integrator::registry::parse`]). The object is kept so that
/// command-line overrides can change a field and read it again.
#[derive(Clone, Debug, PartialEq)]
pub struct IntegratorSpec {
    /// The object as written, `type` included.
    pub object: serde_json::Map<String, serde_json::Value>,
    /// The settings read from it, defaults filled in.
    pub settings: IntegratorSettings,
}

impl IntegratorSpec {
    /// The integrator's name (`type`).
    pub fn name(&self) -> &'static str {
        self.settings.name()
    }
}

impl Default for IntegratorSpec {
    fn default() -> IntegratorSpec {
        let mut object = serde_json::Map::new();
        object.insert("type".into(), serde_json::Value::String("single".into()));
        let settings = crate::integrator::registry::parse(&object).expect("the default integrator parses");
        IntegratorSpec { object, settings }
    }
}

mod film;
mod lights;
mod medium;
mod pyro;
mod shapes;
mod surfaces;

pub use film::*;
pub use lights::*;
pub use medium::*;
pub use pyro::*;
pub use shapes::*;
pub use surfaces::*;
