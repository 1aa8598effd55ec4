//! Descriptions of the microfacet and layered surfaces (Mitsuba 3's
//! `roughconductor`, `roughdielectric`, `thindielectric`, `plastic`,
//! `twosided`), with Mitsuba's parameter names and defaults.

use super::{BsdfDesc, ColorDesc, ConductorDesc, ReflectanceDesc, TextureDesc};
pub use crate::bsdf::MicrofacetKind;

/// Roughness of a microfacet surface: `alpha`, or `alpha_u` and `alpha_v`
/// (along the surface's local x and y axes), each in (0, 1] in practice;
/// Mitsuba's default is `alpha = 0.1`.
#[derive(Clone, Debug, PartialEq)]
pub enum AlphaDesc {
    /// The same roughness in every direction.
    Isotropic(f32),
    /// The same roughness in every direction, varying over the surface: a
    /// texture's value at the hit's uv (a gray texture's value, else the
    /// luminance of its color, as Mitsuba 3's `eval_1`). `roughconductor`
    /// and `roughdielectric` only.
    Textured(Box<TextureDesc>),
    /// Roughness along the tangent (`u`) and the bitangent (`v`).
    Anisotropic {
        /// `alpha_u`.
        u: f32,
        /// `alpha_v`.
        v: f32,
    },
    /// Roughness along the tangent and the bitangent, at least one of them
    /// a texture (each read as for [`AlphaDesc::Textured`]).
    /// `roughconductor` and `roughdielectric` only.
    TexturedAnisotropic(Box<AlphaPair>),
}

/// `alpha_u` and `alpha_v` of [`AlphaDesc::TexturedAnisotropic`] (boxed so
/// that a surface description stays small).
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaPair {
    /// `alpha_u`.
    pub u: AlphaValue,
    /// `alpha_v`.
    pub v: AlphaValue,
}

/// One roughness value of [`AlphaDesc::TexturedAnisotropic`]: a number or
/// a texture.
#[derive(Clone, Debug, PartialEq)]
pub enum AlphaValue {
    /// A constant, in (0, 1].
    Number(f32),
    /// A texture's scalar value at the hit's uv.
    Texture(Box<TextureDesc>),
}

impl AlphaDesc {
    /// True when some roughness of this description is a texture.
    pub fn is_textured(&self) -> bool {
        matches!(self, AlphaDesc::Textured(_) | AlphaDesc::TexturedAnisotropic(_))
    }
}

/// A microfacet distribution: `distribution` (`"beckmann"`, the default,
/// or `"ggx"`) and the roughness.
#[derive(Clone, Debug, PartialEq)]
pub struct MicrofacetDesc {
    /// Beckmann or GGX.
    pub distribution: MicrofacetKind,
    /// Roughness.
    pub alpha: AlphaDesc,
}

/// `"roughconductor"`: a rough metal.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughConductorDesc {
    /// Distribution and roughness.
    pub microfacet: MicrofacetDesc,
    /// The complex index, given as for `conductor`; Mitsuba's default
    /// (nothing given) is a perfect mirror, `eta = 0`, `k = 1`.
    pub conductor: ConductorDesc,
    /// Multiplier of the reflection, a color or texture (default 1).
    pub specular_reflectance: ReflectanceDesc,
}

/// `"roughdielectric"`: rough glass; a medium boundary.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughDielectricDesc {
    /// Distribution and roughness.
    pub microfacet: MicrofacetDesc,
    /// Index inside (default 1.5046, Mitsuba's BK7).
    pub int_ior: f32,
    /// Index outside (default 1.000277, air); must differ from `int_ior`.
    pub ext_ior: f32,
    /// Multiplier of the reflection (default 1).
    pub specular_reflectance: ColorDesc,
    /// Multiplier of the transmission (default 1).
    pub specular_transmittance: ColorDesc,
}

/// `"thindielectric"`: a thin glass sheet.
#[derive(Clone, Debug, PartialEq)]
pub struct ThinDielectricDesc {
    /// Index of the sheet (default 1.5046, BK7).
    pub int_ior: f32,
    /// Index around it (default 1.000277, air).
    pub ext_ior: f32,
    /// Multiplier of the reflection (default 1).
    pub specular_reflectance: ColorDesc,
    /// Multiplier of the transmission (default 1).
    pub specular_transmittance: ColorDesc,
}

/// `"plastic"`: a diffuse base under a smooth dielectric coating.
#[derive(Clone, Debug, PartialEq)]
pub struct PlasticDesc {
    /// Base color, a color or texture in [0, 1] (default 0.5).
    pub diffuse_reflectance: ReflectanceDesc,
    /// Multiplier of the coating's reflection (default 1).
    pub specular_reflectance: ColorDesc,
    /// Index of the coating (default 1.49, Mitsuba's polypropylene).
    pub int_ior: f32,
    /// Index outside (default 1.000277, air).
    pub ext_ior: f32,
    /// Mitsuba's `nonlinear` (default false): internal reflections tint the base.
    pub nonlinear: bool,
}

/// `"roughplastic"`: a diffuse base under a rough dielectric coating
/// (Mitsuba's; isotropic roughness only).
#[derive(Clone, Debug, PartialEq)]
pub struct RoughPlasticDesc {
    /// Normal distribution of the coating (`distribution`, `alpha`; default beckmann, 0.1).
    pub microfacet: MicrofacetDesc,
    /// The colors, indices and `nonlinear`, with `plastic`'s defaults.
    pub plastic: PlasticDesc,
}

/// `"twosided"`: reflecting models on both sides.
#[derive(Clone, Debug, PartialEq)]
pub struct TwoSidedDesc {
    /// Model on the front (the side the normal points to).
    pub front: Box<BsdfDesc>,
    /// Model on the back (the front one again for Mitsuba's one-child form).
    pub back: Box<BsdfDesc>,
}

/// Mitsuba's default `int_ior` of dielectrics (BK7 glass).
pub const BK7_IOR: f32 = 1.5046;
/// Mitsuba's default `ext_ior` (air).
pub const AIR_IOR: f32 = 1.000277;
/// Mitsuba's default `int_ior` of plastics (polypropylene).
pub const POLYPROPYLENE_IOR: f32 = 1.49;
