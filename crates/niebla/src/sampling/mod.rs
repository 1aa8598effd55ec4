//! Random numbers and warps.
//!
//! Randomness is counter based: sample `s` of pixel `(x, y)` draws its numbers
//! from a pure function of `(seed, x, y, s, dimension)` (independent hashes or
//! Owen-scrambled Sobol points, [`SamplerKind`]), so an image does not depend
//! on thread count, tile order or machine.

mod distribution;
mod rng;
pub mod sobol;
mod warps;

pub use distribution::{Distribution1D, Distribution2D};
pub use rng::{hash_u64, PixelSampler, SamplerKind};
pub use sobol::{owen_scrambled_sobol_1d, owen_scrambled_sobol_pair, sobol_2d};
pub use warps::*;

/// Balance heuristic weight of a strategy with density `pdf_a` against one with `pdf_b`
/// (Veach 1997), each taking one sample.
#[inline]
pub fn balance_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    if pdf_a + pdf_b > 0.0 {
        pdf_a / (pdf_a + pdf_b)
    } else {
        0.0
    }
}

/// Power heuristic (beta = 2) weight of a strategy with density `pdf_a` against `pdf_b`.
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    let (a, b) = (pdf_a * pdf_a, pdf_b * pdf_b);
    if a.is_infinite() {
        return 1.0;
    }
    if a + b > 0.0 {
        a / (a + b)
    } else {
        0.0
    }
}
