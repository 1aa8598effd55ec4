//! Building the microfacet and layered surfaces from their descriptions:
//! conductor indices resolved, Mitsuba's derived constants computed, and
//! the one texture an object may carry loaded.

use std::path::Path;
use std::sync::Arc;

use super::build_texture::TextureLoader;
use super::desc::*;
use super::SceneError;
use crate::bsdf::{
    Bsdf, Microfacet, Plastic, Reflector, RoughConductor, RoughDielectric, RoughPlastic, ThinDielectric, TwoSided,
};
use crate::color::Rgb;
use crate::limits::MemoryBudget;
use crate::math::Vec3;
use crate::texture::{AlphaTextures, RoughnessTextures, Texture};

/// What the builder needs to load textures.
pub(super) struct TextureContext<'a> {
    pub loader: &'a mut TextureLoader,
    pub source: &'a str,
    pub base_dir: &'a Path,
    pub budget: &'a mut MemoryBudget,
}

/// The textures of a surface: at most one textured color, and a textured
/// roughness (`roughconductor`, `roughdielectric`, and rough-conductor
/// sides of a `twosided`).
#[derive(Default)]
pub(super) struct SurfaceTextures {
    /// The textured color (see [`Bsdf::with_texture`]).
    pub color: Option<Arc<Texture>>,
    /// The textured roughness (see [`RoughnessTextures::apply`]).
    pub roughness: Option<Arc<RoughnessTextures>>,
}

/// The surface model of `desc` (one of this module's types, found at JSON
/// path `path`, e.g. `shapes[2].bsdf`) and its textures. At most one color
/// of a surface may be textured; the roughness (`alpha`, or `alpha_u` and
/// `alpha_v`) of a `roughconductor` or `roughdielectric`, also as a side of
/// a `twosided`, may be textured too.
pub(super) fn build_surface(
    desc: &BsdfDesc,
    path: &str,
    ctx: &mut TextureContext,
) -> Result<(Bsdf, SurfaceTextures), SceneError> {
    let mut texture = None;
    let mut roughness = None;
    let bsdf = match desc {
        BsdfDesc::RoughConductor(d) => {
            let (b, t) = rough_conductor(d, path, ctx)?;
            texture = t;
            roughness = front_only(roughness_textures(&d.microfacet, path, ctx)?);
            Bsdf::RoughConductor(b)
        }
        BsdfDesc::RoughDielectric(d) => {
            roughness = front_only(roughness_textures(&d.microfacet, path, ctx)?);
            Bsdf::RoughDielectric(RoughDielectric {
                microfacet: microfacet(&d.microfacet),
                eta: d.int_ior / d.ext_ior,
                specular_reflectance: d.specular_reflectance.to_rgb(),
                specular_transmittance: d.specular_transmittance.to_rgb(),
                tangent: Vec3::ZERO,
            })
        }
        BsdfDesc::ThinDielectric(d) => Bsdf::ThinDielectric(ThinDielectric {
            eta: d.int_ior / d.ext_ior,
            specular_reflectance: d.specular_reflectance.to_rgb(),
            specular_transmittance: d.specular_transmittance.to_rgb(),
        }),
        BsdfDesc::Plastic(d) => {
            let (b, t) = plastic(d, path, ctx)?;
            texture = t;
            Bsdf::Plastic(b)
        }
        BsdfDesc::RoughPlastic(d) => {
            let (b, t) = rough_plastic(d, path, ctx)?;
            texture = t;
            Bsdf::RoughPlastic(b)
        }
        BsdfDesc::TwoSided(d) => {
            // Mitsuba's one-child form: one model (and its textures) for both sides.
            let same = d.front == d.back;
            let (front_path, back_path) = if same {
                (format!("{path}.bsdf"), format!("{path}.bsdf"))
            } else {
                (format!("{path}.bsdf[0]"), format!("{path}.bsdf[1]"))
            };
            let (front, t_front, a_front) = reflector(&d.front, &front_path, ctx)?;
            let (back, t_back, a_back) =
                if same { (front, t_front.clone(), a_front.clone()) } else { reflector(&d.back, &back_path, ctx)? };
            if a_front.is_some() || a_back.is_some() {
                roughness = Some(Arc::new(RoughnessTextures { front: a_front, back: a_back }));
            }
            let textured = u8::from(t_front.is_some()) | (u8::from(t_back.is_some()) << 1);
            if !same && t_front.is_some() && t_back.is_some() {
                return Err(SceneError::new(
                    ctx.source,
                    format!("{path}.bsdf[1]"),
                    "only one textured color per surface is supported; the front one is textured already",
                ));
            }
            texture = t_front.or(t_back);
            Bsdf::TwoSided(TwoSided { front, back, textured })
        }
        other => {
            return Err(SceneError::new(ctx.source, path, format!("not a microfacet or layered surface: {other:?}")))
        }
    };
    Ok((bsdf, SurfaceTextures { color: texture, roughness }))
}

/// The textures of a textured roughness (`alpha`, or `alpha_u` and
/// `alpha_v`, at `path.alpha...`); `None` for a constant roughness.
fn roughness_textures(
    d: &MicrofacetDesc,
    path: &str,
    ctx: &mut TextureContext,
) -> Result<Option<AlphaTextures>, SceneError> {
    let mut load = |t: &TextureDesc, name: &str| -> Result<Arc<Texture>, SceneError> {
        let field = format!("{path}.{name}");
        Ok(Arc::new(ctx.loader.texture(t, &field, ctx.source, ctx.base_dir, ctx.budget)?))
    };
    Ok(match &d.alpha {
        AlphaDesc::Textured(t) => Some(AlphaTextures::Isotropic(load(t, "alpha")?)),
        AlphaDesc::TexturedAnisotropic(pair) => {
            let mut one = |value: &AlphaValue, name: &str| match value {
                AlphaValue::Number(_) => Ok(None),
                AlphaValue::Texture(t) => load(t, name).map(Some),
            };
            let u = one(&pair.u, "alpha_u")?;
            let v = one(&pair.v, "alpha_v")?;
            Some(AlphaTextures::Anisotropic { u, v })
        }
        AlphaDesc::Isotropic(_) | AlphaDesc::Anisotropic { .. } => None,
    })
}

/// The roughness textures of a model that is not a `twosided`.
fn front_only(front: Option<AlphaTextures>) -> Option<Arc<RoughnessTextures>> {
    front.map(|a| Arc::new(RoughnessTextures { front: Some(a), back: None }))
}

/// Why `roughplastic` takes a constant roughness only.
const ROUGH_PLASTIC_WHY: &str = "for roughplastic (its coating tables are precomputed for one roughness, and \
                                 Mitsuba 3 refuses a texture there too)";

/// An error for a textured roughness where niebla takes a constant one.
fn constant_roughness(d: &MicrofacetDesc, path: &str, source: &str, why: &str) -> Result<(), SceneError> {
    if d.alpha.is_textured() {
        let field = if let AlphaDesc::TexturedAnisotropic(_) = d.alpha { "alpha_u" } else { "alpha" };
        return Err(SceneError::new(
            source,
            format!("{path}.{field}"),
            format!("a textured roughness is not supported {why}; expected a number in (0, 1]"),
        ));
    }
    Ok(())
}

/// A side of a `twosided`: its model, textured color and textured roughness.
type Side = (Reflector, Option<Arc<Texture>>, Option<AlphaTextures>);

/// A nested model of `twosided` (which must reflect only), its textured
/// color and its textured roughness (a rough conductor's).
fn reflector(desc: &BsdfDesc, path: &str, ctx: &mut TextureContext) -> Result<Side, SceneError> {
    Ok(match desc {
        BsdfDesc::Diffuse { reflectance } => match reflectance {
            ReflectanceDesc::Color(c) => (Reflector::Diffuse { reflectance: c.to_rgb() }, None, None),
            ReflectanceDesc::Texture(t) => {
                let field = format!("{path}.reflectance");
                let t = ctx.loader.texture(t, &field, ctx.source, ctx.base_dir, ctx.budget)?;
                (Reflector::Diffuse { reflectance: Rgb::splat(0.5) }, Some(Arc::new(t)), None)
            }
        },
        BsdfDesc::Conductor(c) => {
            let (eta, k) = conductor_index(c, path, ctx.source, false)?;
            (Reflector::Conductor { eta, k }, None, None)
        }
        BsdfDesc::RoughConductor(d) => {
            let (b, t) = rough_conductor(d, path, ctx)?;
            let alpha = roughness_textures(&d.microfacet, path, ctx)?;
            (Reflector::RoughConductor(b), t, alpha)
        }
        BsdfDesc::Plastic(d) => {
            let (b, t) = plastic(d, path, ctx)?;
            (Reflector::Plastic(b), t, None)
        }
        BsdfDesc::RoughPlastic(d) => {
            let (b, t) = rough_plastic(d, path, ctx)?;
            (Reflector::RoughPlastic(b), t, None)
        }
        _ => {
            return Err(SceneError::new(
                ctx.source,
                path,
                "twosided takes a reflecting bsdf (diffuse, conductor, roughconductor, plastic or roughplastic)",
            ))
        }
    })
}

/// The distribution of `d`. A textured roughness has no constant: every
/// hit sets its own ([`RoughnessTextures::apply`]); the model keeps
/// Mitsuba's default 0.1 for it until then.
fn microfacet(d: &MicrofacetDesc) -> Microfacet {
    let constant = |a: &AlphaValue| match a {
        AlphaValue::Number(a) => *a,
        AlphaValue::Texture(_) => 0.1,
    };
    match &d.alpha {
        AlphaDesc::Isotropic(a) => Microfacet::new(d.distribution, *a, *a),
        AlphaDesc::Anisotropic { u, v } => Microfacet::new(d.distribution, *u, *v),
        AlphaDesc::Textured(_) => Microfacet::new(d.distribution, 0.1, 0.1),
        AlphaDesc::TexturedAnisotropic(pair) => Microfacet::new(d.distribution, constant(&pair.u), constant(&pair.v)),
    }
}

/// `(eta, k)` of a conductor description. With `mitsuba_names`, a name that
/// is exactly one of Mitsuba's (`"Au"`) takes Mitsuba's RGB values (the
/// choice of `roughconductor`, a new type); else the smooth `conductor`'s
/// lookup, unchanged for existing scenes ([`crate::bsdf::conductor_preset`]).
fn conductor_index(c: &ConductorDesc, path: &str, source: &str, mitsuba_names: bool) -> Result<(Rgb, Rgb), SceneError> {
    Ok(match c {
        ConductorDesc::Material(name) => {
            let mitsuba = crate::bsdf::MITSUBA_CONDUCTORS.iter().find(|p| mitsuba_names && p.name == *name);
            let p = mitsuba.copied().or_else(|| crate::bsdf::conductor_preset(name)).ok_or_else(|| {
                SceneError::new(source, format!("{path}.material"), format!("unknown conductor \"{name}\""))
            })?;
            (p.eta, p.k)
        }
        ConductorDesc::Index { eta, k } => (eta.to_rgb(), k.to_rgb()),
        ConductorDesc::Reflectance(r) => crate::bsdf::conductor_from_reflectance(r.to_rgb()),
    })
}

fn rough_conductor(
    d: &RoughConductorDesc,
    path: &str,
    ctx: &mut TextureContext,
) -> Result<(RoughConductor, Option<Arc<Texture>>), SceneError> {
    let (eta, k) = conductor_index(&d.conductor, path, ctx.source, true)?;
    let (specular_reflectance, texture) =
        color_or_texture(&d.specular_reflectance, &format!("{path}.specular_reflectance"), ctx)?;
    Ok((
        RoughConductor { microfacet: microfacet(&d.microfacet), eta, k, specular_reflectance, tangent: Vec3::ZERO },
        texture,
    ))
}

fn plastic(
    d: &PlasticDesc,
    path: &str,
    ctx: &mut TextureContext,
) -> Result<(Plastic, Option<Arc<Texture>>), SceneError> {
    let (diffuse, texture) = color_or_texture(&d.diffuse_reflectance, &format!("{path}.diffuse_reflectance"), ctx)?;
    let specular = d.specular_reflectance.to_rgb();
    let diffuse_mean = match &texture {
        Some(t) => t.mean(),
        None => diffuse.average(),
    };
    let eta = d.int_ior / d.ext_ior;
    Ok((Plastic::new(eta, diffuse, specular, d.nonlinear, diffuse_mean, specular.average()), texture))
}

fn rough_plastic(
    d: &RoughPlasticDesc,
    path: &str,
    ctx: &mut TextureContext,
) -> Result<(RoughPlastic, Option<Arc<Texture>>), SceneError> {
    constant_roughness(&d.microfacet, path, ctx.source, ROUGH_PLASTIC_WHY)?;
    let p = &d.plastic;
    let (diffuse, texture) = color_or_texture(&p.diffuse_reflectance, &format!("{path}.diffuse_reflectance"), ctx)?;
    let specular = p.specular_reflectance.to_rgb();
    let diffuse_mean = match &texture {
        Some(t) => t.mean(),
        None => diffuse.average(),
    };
    let b = RoughPlastic::new(
        microfacet(&d.microfacet),
        p.int_ior / p.ext_ior,
        diffuse,
        specular,
        p.nonlinear,
        diffuse_mean,
        specular.average(),
    );
    Ok((b, texture))
}

/// A constant color, or a texture (the constant then 0.5, unused).
fn color_or_texture(
    r: &ReflectanceDesc,
    field: &str,
    ctx: &mut TextureContext,
) -> Result<(Rgb, Option<Arc<Texture>>), SceneError> {
    Ok(match r {
        ReflectanceDesc::Color(c) => (c.to_rgb(), None),
        ReflectanceDesc::Texture(t) => {
            let t = ctx.loader.texture(t, field, ctx.source, ctx.base_dir, ctx.budget)?;
            (Rgb::splat(0.5), Some(Arc::new(t)))
        }
    })
}
