//! Textured roughness: the microfacet roughness of an object looked up at
//! each hit's uv (Mitsuba 3's `alpha`, `alpha_u` and `alpha_v` given as
//! textures), for a rough conductor or rough dielectric, or for either side
//! of a `twosided` whose side is a rough conductor.

use std::sync::Arc;

use super::Texture;
use crate::bsdf::{Bsdf, Microfacet};
use crate::math::Vec2;

/// The textured roughness of one microfacet model. A texture gives its
/// [`Texture::scalar`] (Mitsuba 3's `eval_1`).
#[derive(Clone, Debug)]
pub enum AlphaTextures {
    /// `alpha`: one texture for both axes.
    Isotropic(Arc<Texture>),
    /// `alpha_u` (along the tangent) and `alpha_v` (along the bitangent),
    /// each a texture or, `None`, the model's constant.
    Anisotropic {
        /// Texture of `alpha_u`.
        u: Option<Arc<Texture>>,
        /// Texture of `alpha_v`.
        v: Option<Arc<Texture>>,
    },
}

impl AlphaTextures {
    /// `(alpha_u, alpha_v)` at `uv`; an axis without a texture keeps its
    /// constant in `m`.
    #[inline]
    pub fn eval(&self, uv: Vec2, m: &Microfacet) -> (f32, f32) {
        match self {
            AlphaTextures::Isotropic(t) => {
                let a = t.scalar(uv);
                (a, a)
            }
            AlphaTextures::Anisotropic { u, v } => {
                (u.as_ref().map_or(m.alpha_u, |t| t.scalar(uv)), v.as_ref().map_or(m.alpha_v, |t| t.scalar(uv)))
            }
        }
    }
}

/// The textured roughness of an object: of its model, or of each side of
/// a `twosided` (both sides share the textures of Mitsuba's one-child form).
#[derive(Clone, Debug, Default)]
pub struct RoughnessTextures {
    /// Of the model (a `twosided`'s front side).
    pub front: Option<AlphaTextures>,
    /// Of a `twosided`'s back side; unused for other models.
    pub back: Option<AlphaTextures>,
}

impl RoughnessTextures {
    /// `bsdf` with the roughness looked up at `uv` (see
    /// [`Bsdf::with_alpha_uv`]); models without a microfacet distribution
    /// are returned unchanged.
    #[inline]
    pub fn apply(&self, bsdf: Bsdf, uv: Vec2) -> Bsdf {
        match bsdf {
            Bsdf::TwoSided(mut b) => {
                if let (Some(a), Some(m)) = (&self.front, b.front.microfacet()) {
                    let (u, v) = a.eval(uv, &m);
                    b.front = b.front.with_alpha_uv(u, v);
                }
                if let (Some(a), Some(m)) = (&self.back, b.back.microfacet()) {
                    let (u, v) = a.eval(uv, &m);
                    b.back = b.back.with_alpha_uv(u, v);
                }
                Bsdf::TwoSided(b)
            }
            other => match (&self.front, other.microfacet()) {
                (Some(a), Some(m)) => {
                    let (u, v) = a.eval(uv, &m);
                    other.with_alpha_uv(u, v)
                }
                _ => other,
            },
        }
    }
}
