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
use crate::texture::Texture;

/// What the builder needs to load textures.
pub(super) struct TextureContext<'a> {
    pub loader: &'a mut TextureLoader,
    pub source: &'a str,
    pub base_dir: &'a Path,
    pub budget: &'a mut MemoryBudget,
}

/// The surface model of `desc` (one of this module's types, found at JSON
/// path `path`, e.g. `shapes[2].bsdf`) and its texture, if a color is
/// textured. At most one parameter of a surface may be textured.
pub(super) fn build_surface(
    desc: &BsdfDesc,
    path: &str,
    ctx: &mut TextureContext,
) -> Result<(Bsdf, Option<Arc<Texture>>), SceneError> {
    let mut texture = None;
    let bsdf = match desc {
        BsdfDesc::RoughConductor(d) => {
            let (b, t) = rough_conductor(d, path, ctx)?;
            texture = t;
            Bsdf::RoughConductor(b)
        }
        BsdfDesc::RoughDielectric(d) => Bsdf::RoughDielectric(RoughDielectric {
            microfacet: microfacet(&d.microfacet),
            eta: d.int_ior / d.ext_ior,
            specular_reflectance: d.specular_reflectance.to_rgb(),
            specular_transmittance: d.specular_transmittance.to_rgb(),
        }),
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
            let (front, t_front) = reflector(&d.front, &format!("{path}.bsdf"), ctx)?;
            let (back, t_back) = reflector(&d.back, &format!("{path}.bsdf"), ctx)?;
            let same = d.front == d.back;
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
    Ok((bsdf, texture))
}

/// A nested model of `twosided` (which must reflect only).
fn reflector(
    desc: &BsdfDesc,
    path: &str,
    ctx: &mut TextureContext,
) -> Result<(Reflector, Option<Arc<Texture>>), SceneError> {
    Ok(match desc {
        BsdfDesc::Diffuse { reflectance } => match reflectance {
            ReflectanceDesc::Color(c) => (Reflector::Diffuse { reflectance: c.to_rgb() }, None),
            ReflectanceDesc::Texture(t) => {
                let field = format!("{path}.reflectance");
                let t = ctx.loader.texture(t, &field, ctx.source, ctx.base_dir, ctx.budget)?;
                (Reflector::Diffuse { reflectance: Rgb::splat(0.5) }, Some(Arc::new(t)))
            }
        },
        BsdfDesc::Conductor(c) => {
            let (eta, k) = conductor_index(c, path, ctx.source, false)?;
            (Reflector::Conductor { eta, k }, None)
        }
        BsdfDesc::RoughConductor(d) => {
            let (b, t) = rough_conductor(d, path, ctx)?;
            (Reflector::RoughConductor(b), t)
        }
        BsdfDesc::Plastic(d) => {
            let (b, t) = plastic(d, path, ctx)?;
            (Reflector::Plastic(b), t)
        }
        BsdfDesc::RoughPlastic(d) => {
            let (b, t) = rough_plastic(d, path, ctx)?;
            (Reflector::RoughPlastic(b), t)
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

fn microfacet(d: &MicrofacetDesc) -> Microfacet {
    match d.alpha {
        AlphaDesc::Isotropic(a) => Microfacet::new(d.distribution, a, a),
        AlphaDesc::Anisotropic { u, v } => Microfacet::new(d.distribution, u, v),
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
    Ok((RoughConductor { microfacet: microfacet(&d.microfacet), eta, k, specular_reflectance }, texture))
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
