//! Lights of the scene description.

use super::*;

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
    /// `"type": "area"`: an emitting rectangle, disk or sphere.
    Area(AreaLightDesc),
    /// `"type": "envmap"`: a lat-long environment map from an EXR file.
    Envmap(EnvmapLightDesc),
}

impl LightDesc {
    /// The `type` names, in the order of the variants.
    pub const TYPES: &'static [&'static str] = &["point", "spot", "directional", "constant", "area", "envmap"];
}

/// An area light: a `rectangle`, `disk`, `sphere` or `mesh` (the shape
/// syntax of `shapes`, without media or bsdf) emitting uniform `radiance`
/// (W/(sr m^2)) from its front (a rectangle's or disk's local +z side, a
/// sphere's outside, a mesh's shading-normal side as in Mitsuba 3), or from
/// both sides of a rectangle or disk with `two_sided`. Its surface is black:
/// it absorbs what hits it. A sphere's `rotation` has no effect here (a
/// warning says so).
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLightDesc {
    /// The emitting shape.
    pub shape: ShapeDesc,
    /// Emitted radiance, finite and >= 0.
    pub radiance: ColorDesc,
    /// Emit from both sides of a rectangle or disk (default false).
    pub two_sided: bool,
}

/// A lat-long environment map (Mitsuba 3's `envmap` mapping: image top is
/// +y, image center is +z, u grows toward +x): `file` (an EXR of linear RGB
/// radiance, relative to the scene file), `scale` (>= 0, default 1) and
/// `to_world` (a rotation; default identity).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvmapLightDesc {
    /// EXR file.
    pub file: String,
    /// Radiance multiplier.
    pub scale: f32,
    /// Orientation of the map in the world (rotation only).
    pub to_world: TransformDesc,
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
