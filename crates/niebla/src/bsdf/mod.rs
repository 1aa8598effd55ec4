//! Surface scattering. A closed set: `Null` marks an index-matched medium
//! boundary that light crosses unchanged; `Diffuse` is an opaque Lambertian
//! reflector.

use crate::color::Rgb;
use crate::math::{Vec3, INV_PI};

/// Surface scattering model of a shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bsdf {
    /// Index-matched boundary: no reflection, rays pass (the default for media containers).
    Null,
    /// Opaque Lambertian surface with hemispherical `reflectance` in [0, 1].
    Diffuse {
        /// Albedo of the surface.
        reflectance: Rgb,
    },
}

impl Bsdf {
    /// BSDF value f(wo, wi) (1/sr) for unit directions on the side of normal `n`;
    /// zero when `wi` and `wo` lie on different sides, and for `Null`.
    #[inline]
    pub fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Bsdf::Null => Rgb::ZERO,
            Bsdf::Diffuse { reflectance } => {
                if n.dot(wo) * n.dot(wi) > 0.0 {
                    *reflectance * INV_PI
                } else {
                    Rgb::ZERO
                }
            }
        }
    }

    /// True for index-matched boundaries that rays cross.
    #[inline]
    pub fn is_null(&self) -> bool {
        matches!(self, Bsdf::Null)
    }
}
