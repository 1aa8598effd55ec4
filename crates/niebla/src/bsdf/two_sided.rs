//! Mitsuba 3's `twosided`: a reflecting model seen from either side. Seen
//! from behind the normal, directions are mirrored through the surface
//! (local `z -> -z`) and the back model is used, as Mitsuba does.

use super::fresnel::fresnel_complex;
use super::{LocalSample, Microfacet, Plastic, RoughConductor, RoughPlastic};
use crate::color::Rgb;
use crate::math::{Vec2, Vec3, INV_PI};
use crate::sampling::sample_cosine_hemisphere;

/// A reflecting (non-transmitting) model, evaluated in the local frame with
/// `wo` above the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reflector {
    /// Lambertian reflection.
    Diffuse {
        /// Albedo in [0, 1].
        reflectance: Rgb,
    },
    /// Smooth conductor (delta reflection).
    Conductor {
        /// Real part of the index per channel.
        eta: Rgb,
        /// Extinction coefficient per channel.
        k: Rgb,
    },
    /// Rough conductor.
    RoughConductor(RoughConductor),
    /// Smooth plastic.
    Plastic(Plastic),
    /// Rough plastic.
    RoughPlastic(RoughPlastic),
}

impl Reflector {
    /// The model with its textured color set to `color` (diffuse
    /// `reflectance`, (rough) plastic `diffuse_reflectance`, rough conductor
    /// `specular_reflectance`); unchanged for a smooth conductor.
    #[inline]
    pub fn with_texture(self, color: Rgb) -> Reflector {
        match self {
            Reflector::Diffuse { .. } => Reflector::Diffuse { reflectance: color },
            Reflector::Conductor { .. } => self,
            Reflector::RoughConductor(b) => {
                Reflector::RoughConductor(RoughConductor { specular_reflectance: color, ..b })
            }
            Reflector::Plastic(b) => Reflector::Plastic(Plastic { diffuse_reflectance: color, ..b }),
            Reflector::RoughPlastic(b) => Reflector::RoughPlastic(RoughPlastic { diffuse_reflectance: color, ..b }),
        }
    }

    /// The model with its roughness set to `alpha_u`, `alpha_v` (each
    /// raised to [`MIN_ALPHA`](super::microfacet::MIN_ALPHA)): a rough
    /// conductor's distribution; other models unchanged (the scene builder
    /// gives a textured roughness to no others).
    #[inline]
    pub fn with_alpha_uv(self, alpha_u: f32, alpha_v: f32) -> Reflector {
        match self {
            Reflector::RoughConductor(b) => Reflector::RoughConductor(RoughConductor {
                microfacet: Microfacet::new(b.microfacet.kind, alpha_u, alpha_v),
                ..b
            }),
            other => other,
        }
    }

    /// The model with `t` as its microfacet distribution's tangent (see
    /// [`Bsdf::with_tangent`](super::Bsdf::with_tangent)); other models unchanged.
    #[inline]
    pub fn with_tangent(self, t: Vec3) -> Reflector {
        match self {
            Reflector::RoughConductor(b) => Reflector::RoughConductor(RoughConductor { tangent: t, ..b }),
            other => other,
        }
    }

    /// The microfacet distribution of a rough conductor; `None` for other
    /// models.
    #[inline]
    pub fn microfacet(&self) -> Option<Microfacet> {
        match self {
            Reflector::RoughConductor(b) => Some(b.microfacet),
            _ => None,
        }
    }

    /// True for delta-only models.
    pub fn is_specular(&self) -> bool {
        matches!(self, Reflector::Conductor { .. })
    }

    /// `f` (1/sr) for `wo.z > 0`.
    #[inline]
    fn eval_local(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Reflector::Diffuse { reflectance } => {
                if wo.z > 0.0 && wi.z > 0.0 {
                    *reflectance * INV_PI
                } else {
                    Rgb::ZERO
                }
            }
            Reflector::Conductor { .. } => Rgb::ZERO,
            Reflector::RoughConductor(b) => b.eval_local(wo, wi),
            Reflector::Plastic(b) => b.eval_local(wo, wi),
            Reflector::RoughPlastic(b) => b.eval_local(wo, wi),
        }
    }

    #[inline]
    fn pdf_local(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Reflector::Diffuse { .. } => {
                if wo.z > 0.0 && wi.z > 0.0 {
                    wi.z * INV_PI
                } else {
                    0.0
                }
            }
            Reflector::Conductor { .. } => 0.0,
            Reflector::RoughConductor(b) => b.pdf_local(wo, wi),
            Reflector::Plastic(b) => b.pdf_local(wo, wi),
            Reflector::RoughPlastic(b) => b.pdf_local(wo, wi),
        }
    }

    #[inline]
    fn sample_local(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<LocalSample> {
        if wo.z <= 0.0 {
            return None;
        }
        match self {
            Reflector::Diffuse { reflectance } => {
                let wi = sample_cosine_hemisphere(u);
                let pdf = wi.z * INV_PI;
                (pdf > 0.0).then_some(LocalSample { wi, f: *reflectance * INV_PI, pdf, specular: false })
            }
            Reflector::Conductor { eta, k } => {
                let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                let f = fresnel_complex(wo.z, *eta, *k) / wi.z;
                Some(LocalSample { wi, f, pdf: 1.0, specular: true })
            }
            Reflector::RoughConductor(b) => {
                let (wi, f, pdf) = b.sample_local(wo, u)?;
                Some(LocalSample { wi, f, pdf, specular: false })
            }
            Reflector::Plastic(b) => b.sample_local(wo, u_lobe, u),
            Reflector::RoughPlastic(b) => b.sample_local(wo, u_lobe, u),
        }
    }
}

/// Front and back models (equal for Mitsuba's one-child form).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoSided {
    /// Model on the side the normal points to.
    pub front: Reflector,
    /// Model on the other side.
    pub back: Reflector,
    /// Which sides take the object's texture: bit 0 the front, bit 1 the back.
    pub textured: u8,
}

#[inline]
fn mirror(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.y, -v.z)
}

impl TwoSided {
    /// `f` (1/sr) in the local frame; zero when `wo` and `wi` lie on
    /// different sides.
    #[inline]
    pub fn eval_local(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z > 0.0 {
            self.front.eval_local(wo, wi)
        } else {
            self.back.eval_local(mirror(wo), mirror(wi))
        }
    }

    /// Sampling density (1/sr) in the local frame.
    #[inline]
    pub fn pdf_local(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z > 0.0 {
            self.front.pdf_local(wo, wi)
        } else {
            self.back.pdf_local(mirror(wo), mirror(wi))
        }
    }

    /// Sample with the model of `wo`'s side.
    #[inline]
    pub(super) fn sample_local(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<LocalSample> {
        if wo.z > 0.0 {
            self.front.sample_local(wo, u_lobe, u)
        } else {
            let mut s = self.back.sample_local(mirror(wo), u_lobe, u)?;
            s.wi = mirror(s.wi);
            Some(s)
        }
    }
}
