//! niebla: a physically based renderer for participating media.
//!
//! Conventions (see ARCHITECTURE.md): coefficients are per unit length,
//! radiance is in W/(sr m^2) of whatever length unit the scene uses, phase
//! functions take `wo` and `wi` both pointing away from the scattering point,
//! medium emission `L_ve` is radiance per unit length, and linear RGB uses
//! Rec.709 primaries.

// Negated comparisons such as `!(t < t_end)` are deliberate throughout: they
// also catch NaN, which the rewritten comparison would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod adaptive;
pub mod aov;
pub mod bsdf;
pub mod camera;
pub mod color;
pub mod denoise;
pub mod film;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod limits;
pub mod math;
pub mod medium;
pub mod params;
pub mod phase;
pub mod progressive;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod texture;
pub mod tracking;
pub mod world;
