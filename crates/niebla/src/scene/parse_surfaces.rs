//! Reading the microfacet and layered surfaces (`roughconductor`,
//! `roughdielectric`, `thindielectric`, `plastic`, `roughplastic`, `twosided`) from a
//! shape's `bsdf` object, with Mitsuba 3's parameter names and defaults.

use serde::Deserialize;
use serde_json::Value;

use super::desc::*;
use crate::params::{describe, rest, Located, Object};

/// The surface called `tag`, read from the rest of its object; `None` when
/// `tag` is none of this module's types.
pub(super) fn parse_surface(tag: &str, object: Object) -> Option<Result<BsdfDesc, Located>> {
    Some(match tag {
        "roughconductor" => parse_rough_conductor(object),
        "roughdielectric" => parse_rough_dielectric(object),
        "thindielectric" => parse_thin_dielectric(object),
        "plastic" => parse_plastic(object),
        "roughplastic" => parse_rough_plastic(object),
        "twosided" => parse_two_sided(object),
        _ => return None,
    })
}

fn bk7() -> f32 {
    BK7_IOR
}

fn air() -> f32 {
    AIR_IOR
}

fn polypropylene() -> f32 {
    POLYPROPYLENE_IOR
}

fn white() -> ColorDesc {
    ColorDesc::Gray(1.0)
}

fn white_reflectance() -> ReflectanceDesc {
    ReflectanceDesc::Color(ColorDesc::Gray(1.0))
}

fn half_gray() -> ReflectanceDesc {
    ReflectanceDesc::Color(ColorDesc::Gray(0.5))
}

/// The microfacet fields every rough surface shares.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMicrofacet {
    #[serde(default)]
    distribution: Option<String>,
    #[serde(default)]
    alpha: Option<Value>,
    #[serde(default)]
    alpha_u: Option<Value>,
    #[serde(default)]
    alpha_v: Option<Value>,
}

/// A roughness value: a number (checked later to lie in (0, 1]) or a
/// texture object.
fn alpha_value(field: &str, value: &Value) -> Result<AlphaValue, Located> {
    match value {
        Value::Number(n) => Ok(AlphaValue::Number(n.as_f64().unwrap_or(f64::NAN) as f32)),
        Value::Object(o) => {
            super::parse::parse_texture(o.clone()).map(|t| AlphaValue::Texture(Box::new(t))).map_err(|e| e.under(field))
        }
        other => Err(Located::new(field, format!("expected a number in (0, 1] or a texture, got {}", describe(other)))),
    }
}

/// The isotropic roughness `alpha`: a number or a texture object.
fn isotropic(value: &Value) -> Result<AlphaDesc, Located> {
    Ok(match alpha_value("alpha", value)? {
        AlphaValue::Number(a) => AlphaDesc::Isotropic(a),
        AlphaValue::Texture(t) => AlphaDesc::Textured(t),
    })
}

/// `alpha_u` and `alpha_v`, each a number or a texture object.
fn anisotropic(u: &Value, v: &Value) -> Result<AlphaDesc, Located> {
    Ok(match (alpha_value("alpha_u", u)?, alpha_value("alpha_v", v)?) {
        (AlphaValue::Number(u), AlphaValue::Number(v)) => AlphaDesc::Anisotropic { u, v },
        (u, v) => AlphaDesc::TexturedAnisotropic(Box::new(AlphaPair { u, v })),
    })
}

fn microfacet(raw: &RawMicrofacet) -> Result<MicrofacetDesc, Located> {
    let distribution = match raw.distribution.as_deref().map(str::to_ascii_lowercase).as_deref() {
        None | Some("beckmann") => MicrofacetKind::Beckmann,
        Some("ggx") => MicrofacetKind::Ggx,
        Some(other) => {
            return Err(Located::new(
                "distribution",
                format!("unknown distribution \"{other}\"; expected \"beckmann\" or \"ggx\""),
            ))
        }
    };
    let alpha = match (&raw.alpha, &raw.alpha_u, &raw.alpha_v) {
        (None, None, None) => AlphaDesc::Isotropic(0.1),
        (Some(a), None, None) => isotropic(a)?,
        (None, Some(u), Some(v)) => anisotropic(u, v)?,
        (Some(_), _, _) => {
            return Err(Located::new("alpha", "give either `alpha` or `alpha_u` with `alpha_v`, not both"))
        }
        (None, None, Some(_)) => {
            return Err(Located::new("alpha_u", "missing `alpha_u`: give it together with `alpha_v`"))
        }
        (None, Some(_), None) => {
            return Err(Located::new("alpha_v", "missing `alpha_v`: give it together with `alpha_u`"))
        }
    };
    Ok(MicrofacetDesc { distribution, alpha })
}

/// Splits the microfacet fields off an object and reads them.
fn take_microfacet(object: &mut Object) -> Result<MicrofacetDesc, Located> {
    let mut fields = Object::new();
    for key in ["distribution", "alpha", "alpha_u", "alpha_v"] {
        if let Some(v) = object.remove(key) {
            fields.insert(key.to_string(), v);
        }
    }
    let raw: RawMicrofacet = rest(fields)?;
    microfacet(&raw)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRoughConductor {
    #[serde(default)]
    material: Option<String>,
    #[serde(default)]
    eta: Option<ColorDesc>,
    #[serde(default)]
    k: Option<ColorDesc>,
    #[serde(default)]
    reflectance: Option<ColorDesc>,
    #[serde(default = "white_reflectance")]
    specular_reflectance: ReflectanceDesc,
}

fn parse_rough_conductor(mut object: Object) -> Result<BsdfDesc, Located> {
    let microfacet = take_microfacet(&mut object)?;
    let raw: RawRoughConductor = rest(object)?;
    let given = [raw.material.is_some(), raw.eta.is_some() || raw.k.is_some(), raw.reflectance.is_some()];
    if given.iter().filter(|g| **g).count() > 1 {
        return Err(Located::new(
            "",
            "give at most one of `material`, `eta` with `k`, or `reflectance` (none: a perfect mirror)",
        ));
    }
    let conductor = if let Some(name) = raw.material {
        if name == "none" {
            ConductorDesc::Index { eta: ColorDesc::Gray(0.0), k: ColorDesc::Gray(1.0) }
        } else {
            let mitsuba = crate::bsdf::MITSUBA_CONDUCTORS.iter().find(|p| p.name == name);
            let preset = mitsuba.copied().or_else(|| crate::bsdf::conductor_preset(&name)).ok_or_else(|| {
                Located::new(
                    "material",
                    format!(
                        "unknown conductor material \"{name}\"; expected one of: {}, or one of Mitsuba's: {}",
                        crate::bsdf::CONDUCTOR_PRESETS.iter().map(|p| p.name).collect::<Vec<_>>().join(", "),
                        crate::bsdf::MITSUBA_CONDUCTORS.iter().map(|p| p.name).collect::<Vec<_>>().join(", ")
                    ),
                )
            })?;
            ConductorDesc::Material(preset.name)
        }
    } else if let Some(r) = raw.reflectance {
        ConductorDesc::Reflectance(r)
    } else {
        match (raw.eta, raw.k) {
            (Some(eta), Some(k)) => ConductorDesc::Index { eta, k },
            // Mitsuba's defaults: eta 0, k 1 (a perfect mirror).
            (eta, k) => {
                ConductorDesc::Index { eta: eta.unwrap_or(ColorDesc::Gray(0.0)), k: k.unwrap_or(ColorDesc::Gray(1.0)) }
            }
        }
    };
    Ok(BsdfDesc::RoughConductor(RoughConductorDesc {
        microfacet,
        conductor,
        specular_reflectance: raw.specular_reflectance,
    }))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDielectricLike {
    #[serde(default = "bk7")]
    int_ior: f32,
    #[serde(default = "air")]
    ext_ior: f32,
    #[serde(default = "white")]
    specular_reflectance: ColorDesc,
    #[serde(default = "white")]
    specular_transmittance: ColorDesc,
}

fn parse_rough_dielectric(mut object: Object) -> Result<BsdfDesc, Located> {
    let microfacet = take_microfacet(&mut object)?;
    let raw: RawDielectricLike = rest(object)?;
    Ok(BsdfDesc::RoughDielectric(RoughDielectricDesc {
        microfacet,
        int_ior: raw.int_ior,
        ext_ior: raw.ext_ior,
        specular_reflectance: raw.specular_reflectance,
        specular_transmittance: raw.specular_transmittance,
    }))
}

fn parse_thin_dielectric(object: Object) -> Result<BsdfDesc, Located> {
    let raw: RawDielectricLike = rest(object)?;
    Ok(BsdfDesc::ThinDielectric(ThinDielectricDesc {
        int_ior: raw.int_ior,
        ext_ior: raw.ext_ior,
        specular_reflectance: raw.specular_reflectance,
        specular_transmittance: raw.specular_transmittance,
    }))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPlastic {
    #[serde(default = "half_gray")]
    diffuse_reflectance: ReflectanceDesc,
    #[serde(default = "white")]
    specular_reflectance: ColorDesc,
    #[serde(default = "polypropylene")]
    int_ior: f32,
    #[serde(default = "air")]
    ext_ior: f32,
    #[serde(default)]
    nonlinear: bool,
}

fn plastic_desc(object: Object) -> Result<PlasticDesc, Located> {
    let raw: RawPlastic = rest(object)?;
    Ok(PlasticDesc {
        diffuse_reflectance: raw.diffuse_reflectance,
        specular_reflectance: raw.specular_reflectance,
        int_ior: raw.int_ior,
        ext_ior: raw.ext_ior,
        nonlinear: raw.nonlinear,
    })
}

fn parse_plastic(object: Object) -> Result<BsdfDesc, Located> {
    plastic_desc(object).map(BsdfDesc::Plastic)
}

fn parse_rough_plastic(mut object: Object) -> Result<BsdfDesc, Located> {
    let microfacet = take_microfacet(&mut object)?;
    if let AlphaDesc::Anisotropic { .. } | AlphaDesc::TexturedAnisotropic(_) = microfacet.alpha {
        return Err(Located::new("alpha_u", "roughplastic is isotropic (as in Mitsuba): give `alpha`"));
    }
    if let AlphaDesc::Textured(_) = microfacet.alpha {
        return Err(Located::new(
            "alpha",
            "a textured roughness is not supported for roughplastic (its coating tables are precomputed for one \
             roughness, and Mitsuba 3 refuses a texture there too); expected a number in (0, 1]",
        ));
    }
    let plastic = plastic_desc(object)?;
    Ok(BsdfDesc::RoughPlastic(RoughPlasticDesc { microfacet, plastic }))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTwoSided {
    bsdf: Value,
}

/// One nested `bsdf` object, errors located under `path`.
fn nested(path: &str, value: Value) -> Result<Box<BsdfDesc>, Located> {
    serde_path_to_error::deserialize::<_, BsdfDesc>(value)
        .map(Box::new)
        .map_err(|e| Located::from_path_error(e).under(path))
}

fn parse_two_sided(object: Object) -> Result<BsdfDesc, Located> {
    let raw: RawTwoSided = rest(object)?;
    let (front, back) = match raw.bsdf {
        Value::Array(items) if items.len() == 2 => {
            let mut items = items.into_iter();
            let front = nested("bsdf[0]", items.next().unwrap_or(Value::Null))?;
            let back = nested("bsdf[1]", items.next().unwrap_or(Value::Null))?;
            (front, back)
        }
        Value::Array(items) => {
            return Err(Located::new(
                "bsdf",
                format!("expected one bsdf object or an array of two (front, back), got an array of {}", items.len()),
            ))
        }
        value @ Value::Object(_) => {
            let one = nested("bsdf", value)?;
            (one.clone(), one)
        }
        other => {
            return Err(Located::new(
                "bsdf",
                format!("expected one bsdf object or an array of two (front, back), got {}", describe(&other)),
            ))
        }
    };
    Ok(BsdfDesc::TwoSided(TwoSidedDesc { front, back }))
}
