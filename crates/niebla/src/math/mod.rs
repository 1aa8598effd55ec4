//! Vectors, rays and orthonormal frames.
//!
//! Geometry is `f32` throughout (glam's `Vec3`); world space is right-handed
//! with y up by default. Directions are unit vectors unless a name says
//! otherwise.

mod frame;
mod ray;

pub use frame::Frame;
pub use glam::{Vec2, Vec3};
pub use ray::Ray;

/// pi as f32.
pub const PI: f32 = std::f32::consts::PI;
/// 1 / pi.
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;
/// 1 / (4 pi): the isotropic phase function value, in 1/sr.
pub const INV_4PI: f32 = 0.25 * std::f32::consts::FRAC_1_PI;

/// Relative offset used to move ray origins off surfaces, in scene units per
/// unit of coordinate magnitude.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// A direction from spherical coordinates around +z: `cos_theta` is the cosine
/// to +z and `phi` the azimuth from +x toward +y.
pub fn spherical_direction(sin_theta: f32, cos_theta: f32, phi: f32) -> Vec3 {
    let (sin_phi, cos_phi) = phi.sin_cos();
    Vec3::new(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta)
}

/// `sqrt(max(x, 0))`: safe square root of a value that rounding may push below zero.
#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}
