//! Direction sampling at a `volpath` vertex mixed with a guide, toward
//! lights inside media ([`LightGuide`]) or toward emissive media
//! ([`EmitterGuide`], at surface and medium vertices): one-sample MIS of
//! phase or BSDF sampling and guided directions.

use crate::bsdf::Bsdf;
use crate::math::Vec3;
use crate::phase::PhaseFunction;
use crate::sampling::PixelSampler;

use super::emitter_guide::EmitterGuide;
use super::layout::{self, Block};
use super::light_guide::LightGuide;

/// What a vertex's guided directions aim at.
#[derive(Clone, Copy)]
pub(super) enum GuideTarget<'a> {
    /// Point and spot lights inside media.
    Lamps(&'a LightGuide),
    /// The emitting region of emissive media.
    Emitters(&'a EmitterGuide),
}

/// Direction guiding at a vertex: the guide and the probability of using it.
#[derive(Clone, Copy)]
pub(super) struct Guiding<'a> {
    pub(super) target: GuideTarget<'a>,
    pub(super) fraction: f32,
}

impl Guiding<'_> {
    /// The one-sample MIS density of direction `w` at `x`, given the density
    /// `pdf` of phase or BSDF sampling there.
    #[inline]
    pub(super) fn mix(&self, x: Vec3, w: Vec3, pdf: f32) -> f32 {
        (1.0 - self.fraction) * pdf + self.fraction * self.pdf(x, w)
    }

    /// Solid-angle density (1/sr) of the guide's own directions from `x` at `w`.
    #[inline]
    fn pdf(&self, x: Vec3, w: Vec3) -> f32 {
        match self.target {
            GuideTarget::Lamps(g) => g.pdf(x, w),
            GuideTarget::Emitters(g) => g.pdf(x, w),
        }
    }

    /// A guided unit direction from `x` (see the targets' `sample`).
    #[inline]
    fn sample(&self, x: Vec3, u_light: f32, u_dir: glam::Vec2, u_r: f32) -> Option<Vec3> {
        match self.target {
            GuideTarget::Lamps(g) => g.sample(x, u_light, u_dir, u_r),
            GuideTarget::Emitters(g) => g.sample(x, u_light, u_dir, u_r),
        }
    }
}

/// Phase sampling at `x`, mixed with guiding toward lights when `guiding` is
/// given (one-sample MIS: the returned `pdf` is the mixture's density and
/// `value` the phase function, so `value / pdf` is the path weight). Without
/// guiding it draws the same random numbers as plain phase sampling.
pub(super) fn sample_phase(
    phase: &PhaseFunction,
    x: Vec3,
    wo: Vec3,
    guiding: Option<Guiding>,
    block: Block,
    sampler: &mut PixelSampler,
) -> Option<crate::phase::PhaseSample> {
    let Some(g) = guiding else {
        block.enter(sampler, layout::DIRECTION);
        return phase.sample(wo, sampler.next_2d());
    };
    let (u_choice, u_light, u_dir, u_r) = guided_numbers(block, sampler);
    let wi = if u_choice < g.fraction { g.sample(x, u_light, u_dir, u_r)? } else { phase.sample(wo, u_dir)?.wi };
    // A phase function's pdf is its value: one evaluation serves both.
    let value = phase.eval(wo, wi);
    let pdf = g.mix(x, wi, value);
    (pdf > 0.0).then_some(crate::phase::PhaseSample { wi, value, pdf })
}

/// BSDF sampling at surface point `p` with outward geometric normal `n`,
/// mixed with guiding toward lights when `guiding` is given (only for
/// non-specular BSDFs; the sample's `f` and `pdf` are then the BSDF value
/// and the mixture's density). Without guiding it draws the same random
/// numbers as plain BSDF sampling.
pub(super) fn sample_bsdf(
    bsdf: &Bsdf,
    n: Vec3,
    p: Vec3,
    wo: Vec3,
    guiding: Option<Guiding>,
    block: Block,
    sampler: &mut PixelSampler,
) -> Option<crate::bsdf::BsdfSample> {
    block.enter(sampler, layout::LOBE);
    let u_lobe = sampler.next_1d();
    let Some(g) = guiding else {
        block.enter(sampler, layout::DIRECTION);
        return bsdf.sample(n, wo, u_lobe, sampler.next_2d());
    };
    let (u_choice, u_light, u_dir, u_r) = guided_numbers(block, sampler);
    let wi =
        if u_choice < g.fraction { g.sample(p, u_light, u_dir, u_r)? } else { bsdf.sample(n, wo, u_lobe, u_dir)?.wi };
    let f = bsdf.eval(n, wo, wi);
    if f.is_black() {
        return None;
    }
    let pdf = g.mix(p, wi, bsdf.pdf(n, wo, wi));
    Some(crate::bsdf::BsdfSample { wi, f, pdf, is_specular: false, is_transmission: false, eta: 1.0 })
}

/// The numbers of a guided direction: strategy choice, light choice,
/// direction pair (shared by both strategies) and radius, drawn in that
/// order from their slots of `block`.
#[inline]
fn guided_numbers(block: Block, sampler: &mut PixelSampler) -> (f32, f32, glam::Vec2, f32) {
    block.enter(sampler, layout::GUIDE);
    let (u_choice, u_light) = (sampler.next_1d(), sampler.next_1d());
    block.enter(sampler, layout::DIRECTION);
    let u_dir = sampler.next_2d();
    block.enter(sampler, layout::GUIDE_RADIUS);
    (u_choice, u_light, u_dir, sampler.next_1d())
}
