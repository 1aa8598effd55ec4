//! niebla: a physically based renderer for participating media.
//!
//! Conventions (see ARCHITECTURE.md): coefficients are per unit length,
//! radiance is in W/(sr m^2) of whatever length unit the scene uses, phase
//! functions take `wo` and `wi` both pointing away from the scattering point,
//! and linear RGB uses Rec.709 primaries.

pub mod color;
pub mod math;
pub mod sampling;
