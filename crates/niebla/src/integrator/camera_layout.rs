//! The fixed dimension layout of the camera-ray integrators (`single`,
//! `emission`, `analytic`) for Sobol samplers, the counterpart of
//! `volpath`'s per-bounce layout: the camera takes dimensions 0 to 3 (pixel
//! position 0 and 1, shutter instant 2, 3 unused), then step `k` of the walk
//! along the camera ray (the medium segment up to the next surface and what
//! happens at that surface, see `walk_camera_ray`) takes the block of
//! [`BLOCK`] dimensions from `CAMERA + k * BLOCK`, one fixed slot per
//! decision ([`Slot`]). Pairs `(2j, 2j + 1)` are the sampler's stratified 2D
//! sets, so 2D decisions take such a pair and 1D decisions share one.
//!
//! The walk records its step in the sampler
//! ([`PixelSampler::set_layout_block`]) and the decisions enter their slot
//! with [`enter`]; walks without a layout (`hegeman`, `zhou`, photon
//! gathering) leave the block unset, and [`enter`] then does nothing, so
//! their numbers stay those of draw order. A ray march gives each of its
//! first [`MARCH_STEPS`] steps its own light-sampling slots in a region
//! after the blocks ([`enter_march_step`]).
//!
//! The first collisions of the transmittance estimates across a segment and
//! between march points have slots too (with a tracker they are the main
//! noise of `emission`: left independent, they made it as noisy as
//! independent numbers). Numbers drawn past a slot's end (later collisions,
//! shadow rays) are independent, keyed by the slot; steps from
//! [`LAID_OUT_STEPS`] on, and march steps from [`MARCH_STEPS`] on, draw
//! independent numbers only. Several lights at one point share the light
//! slot: each light's estimate is unbiased alone and they are added.

use crate::sampling::PixelSampler;

/// Dimensions of the camera sample: pixel position (0, 1), shutter instant
/// (2); 3 is left free so that the blocks start on a pair.
pub(crate) const CAMERA: u64 = 4;

/// Dimensions per walk step.
pub(crate) const BLOCK: u64 = 32;

/// Walk steps with Sobol slots; later ones draw independent numbers only.
pub(crate) const LAID_OUT_STEPS: u32 = 4;

/// Ray-march steps per walk step with their own light-sampling slots.
pub(crate) const MARCH_STEPS: u32 = 64;

/// Dimensions per ray-march step ([`STEP_LIGHT_POINT`], [`STEP_VOLUME_LIGHT`],
/// [`STEP_TRANSMITTANCE`]).
pub(crate) const MARCH_BLOCK: u64 = 16;

/// First dimension of the ray-march region, after the blocks.
const MARCH_BASE: u64 = CAMERA + LAID_OUT_STEPS as u64 * BLOCK;

/// A decision's dimensions within a block: `len` of them from `offset`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Slot {
    offset: u64,
    len: u64,
}

/// Distance sampled on the segment for in-scattering (`single`'s `mis` and
/// `equiangular`, `analytic`'s lights without a closed form); its pair
/// partner is [`EQUIANGULAR`].
pub(crate) const DISTANCE: Slot = Slot { offset: 0, len: 1 };
/// Equiangular distance toward a point-like light (all of them share it).
pub(crate) const EQUIANGULAR: Slot = Slot { offset: 1, len: 1 };
/// Point on a light seen from the distance-sampled point (a pair).
pub(crate) const LIGHT_POINT: Slot = Slot { offset: 2, len: 2 };
/// Point on the light seen from the equiangular point (a pair).
pub(crate) const EQUIANGULAR_LIGHT_POINT: Slot = Slot { offset: 4, len: 2 };
/// Jitter of the emission ray march (its pair partner is [`SCATTER_JITTER`]).
pub(crate) const EMISSION_JITTER: Slot = Slot { offset: 6, len: 1 };
/// Jitter of `single`'s in-scattering ray march.
pub(crate) const SCATTER_JITTER: Slot = Slot { offset: 7, len: 1 };
/// Point on a light seen from the opaque surface (a pair).
pub(crate) const SURFACE_LIGHT_POINT: Slot = Slot { offset: 8, len: 2 };
/// Direction sampled at a specular or rough-transmission surface (a pair).
pub(crate) const SPECULAR_DIRECTION: Slot = Slot { offset: 10, len: 2 };
/// Lobe choice at that surface.
pub(crate) const LOBE: Slot = Slot { offset: 12, len: 1 };
/// Point in the emissive media seen from the distance-sampled point: medium
/// choice (13), a point (the pair 14, 15) and a third coordinate (16).
pub(crate) const VOLUME_LIGHT: Slot = Slot { offset: 13, len: 4 };
/// Point in the emissive media seen from the opaque surface (17; 18, 19; 20).
pub(crate) const SURFACE_VOLUME_LIGHT: Slot = Slot { offset: 17, len: 4 };
/// The first numbers of the transmittance estimate across a segment without
/// an emission march (the collisions of a tracker, one number each).
pub(crate) const TRANSMITTANCE: Slot = Slot { offset: 22, len: 8 };

/// Point on a light seen from a ray-march point (a pair).
pub(crate) const STEP_LIGHT_POINT: Slot = Slot { offset: 0, len: 2 };
/// Point in the emissive media seen from a ray-march point (3; 4, 5; 6).
pub(crate) const STEP_VOLUME_LIGHT: Slot = Slot { offset: 3, len: 4 };
/// The first numbers of the transmittance estimate from the previous
/// ray-march point to this one (tracking collisions): the main noise of a
/// march through a grid with a tracker, so they are stratified too.
pub(crate) const STEP_TRANSMITTANCE: Slot = Slot { offset: 8, len: 8 };

/// The first dimension of `slot` in the block of walk step `step`.
#[inline]
pub(crate) fn start(step: u32, slot: Slot) -> u64 {
    CAMERA + step as u64 * BLOCK + slot.offset
}

/// The first dimension of `slot` of ray-march step `i` in walk step `step`.
#[inline]
pub(crate) fn march_start(step: u32, i: u32, slot: Slot) -> u64 {
    MARCH_BASE + (step as u64 * MARCH_STEPS as u64 + i as u64) * MARCH_BLOCK + slot.offset
}

/// Take the next numbers of `sampler` from `slot` of the current walk step
/// ([`PixelSampler::use_slots`]): its dimensions in a laid-out step, else
/// independent numbers keyed by the slot and the step. Does nothing when no
/// walk step is set (estimates without this layout).
#[inline]
pub(crate) fn enter(sampler: &mut PixelSampler, slot: Slot) {
    let Some(step) = sampler.layout_block() else {
        return;
    };
    if step < LAID_OUT_STEPS {
        sampler.use_slots(start(step, slot), slot.len, 0);
    } else {
        // Keyed by the slot in block 0 and the step (repeat >= 1 never
        // meets the keys of laid-out slots).
        sampler.use_slots(start(0, slot), 0, step);
    }
}

/// [`enter`] for `slot` of ray-march step `i` of the current walk step.
#[inline]
pub(crate) fn enter_march_step(sampler: &mut PixelSampler, i: u32, slot: Slot) {
    let Some(step) = sampler.layout_block() else {
        return;
    };
    if step < LAID_OUT_STEPS && i < MARCH_STEPS {
        sampler.use_slots(march_start(step, i, slot), slot.len, 0);
    } else {
        // One key per (walk step, slot), one repeat per march step.
        sampler.use_slots(MARCH_BASE + step as u64 * MARCH_BLOCK + slot.offset, 0, i.saturating_add(1));
    }
}

#[cfg(test)]
#[path = "camera_layout_tests.rs"]
mod tests;
