//! `volpath`'s fixed dimension layout for Sobol samplers (the idea of
//! pbrt-v4's per-vertex `Get1D`/`Get2D` order and Cycles' `PRNG_BOUNCE_NUM`
//! dimensions per bounce): the camera takes dimensions 0 to 3 (the pixel
//! position 0 and 1, drawn by the render loop, then the instant of the
//! sample, dimension 2, when the camera's shutter is open; 3 is unused);
//! bounce `b` (the path segment that
//! leaves vertex `b`, the camera being vertex 0, and the scattering vertex
//! `b + 1` it reaches) takes the block of [`BLOCK`] dimensions from
//! `CAMERA + b * BLOCK`, with one fixed slot per decision ([`Slot`]).
//! Pairs of dimensions `(2j, 2j + 1)` are the sampler's stratified 2D sets,
//! so 2D decisions take such a pair and 1D decisions that go together share
//! one (free-flight distance and event choice, light choice and roulette).
//!
//! Decisions that repeat within a bounce get independent numbers after their
//! first: the null collisions after the first tentative collision of a
//! segment, the ratio tracking and roulette of shadow rays (past their
//! slot's end), and every decision of a second or later segment of the same
//! bounce (after crossing an index-matched boundary or a thin pane). From
//! bounce [`LAID_OUT_BOUNCES`] on, every number is independent.

use crate::sampling::PixelSampler;

/// Dimensions of the camera sample: the pixel position (0, 1) and the
/// shutter instant (2, see `PerspectiveCamera::sample_ray`); 3 is left
/// free so that the bounce blocks start on a pair. The first bounce must not
/// start at 2, or its first free-flight number would repeat the instant.
pub(super) const CAMERA: u64 = 4;

/// Dimensions per bounce.
pub(super) const BLOCK: u64 = 22;

/// Bounces with Sobol slots; later ones draw independent numbers only.
pub(super) const LAID_OUT_BOUNCES: u32 = 8;

/// A decision's dimensions within a bounce's block: `len` of them from `offset`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Slot {
    offset: u64,
    len: u64,
}

/// Free-flight distance (offset 0) and real/null/absorption choice (1) of
/// the first tentative collision; later collisions are independent.
pub(super) const FREE_FLIGHT: Slot = Slot { offset: 0, len: 2 };
/// Phase or BSDF direction (a pair; guided sampling uses it for both strategies).
pub(super) const DIRECTION: Slot = Slot { offset: 2, len: 2 };
/// Next-event estimation: the point on the light (a pair); the shadow ray's
/// ratio tracking follows with independent numbers.
pub(super) const LIGHT_POINT: Slot = Slot { offset: 4, len: 2 };
/// Next-event estimation: which light.
pub(super) const LIGHT_CHOICE: Slot = Slot { offset: 6, len: 1 };
/// Russian roulette after the vertex.
pub(super) const ROULETTE: Slot = Slot { offset: 7, len: 1 };
/// Equiangular sampling on the segment: distance (8), then the point on the
/// light (the pair 10, 11); transmittances follow with independent numbers.
pub(super) const EQUIANGULAR: Slot = Slot { offset: 8, len: 4 };
/// Equiangular sampling: which point light (the dimension the distance skips).
pub(super) const EQUIANGULAR_CHOICE: Slot = Slot { offset: 9, len: 1 };
/// BSDF lobe choice.
pub(super) const LOBE: Slot = Slot { offset: 12, len: 1 };
/// Thin pane: pass or reflect.
pub(super) const PANE: Slot = Slot { offset: 13, len: 1 };
/// Guiding: strategy choice (14) and light choice (15).
pub(super) const GUIDE: Slot = Slot { offset: 14, len: 2 };
/// Guiding: the radius within a light's volume.
pub(super) const GUIDE_RADIUS: Slot = Slot { offset: 16, len: 1 };
/// Light sampling of emissive media: medium choice (17), a point (the pair
/// 18, 19) and a third coordinate (20); the shadow ray follows.
pub(super) const VOLUME_LIGHT: Slot = Slot { offset: 17, len: 4 };

/// Which use of which bounce's block a decision belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Block {
    /// The bounce: scattering events before the segment (segment decisions)
    /// or before the vertex (vertex decisions).
    pub(super) bounce: u32,
    /// Earlier segments of the same bounce (0: the first, which owns the slots).
    pub(super) repeat: u32,
}

impl Block {
    /// The block of the vertex reached after `depth - 1` scattering events
    /// (`depth >= 1`, the vertex's own depth); its decisions happen once.
    #[inline]
    pub(super) fn vertex(depth: u32) -> Block {
        Block { bounce: depth.saturating_sub(1), repeat: 0 }
    }

    /// The first dimension of `slot` in this block.
    #[inline]
    pub(super) fn start(self, slot: Slot) -> u64 {
        CAMERA + self.bounce as u64 * BLOCK + slot.offset
    }

    /// Take the next numbers from `slot` ([`PixelSampler::use_slots`]):
    /// its dimensions on the first use in a laid-out bounce, else
    /// independent numbers keyed by the slot and the repeat.
    #[inline]
    pub(super) fn enter(self, sampler: &mut PixelSampler, slot: Slot) {
        let len = if self.bounce < LAID_OUT_BOUNCES { slot.len } else { 0 };
        sampler.use_slots(self.start(slot), len, self.repeat);
    }
}

/// Counts the segments of each bounce that draw numbers (segments through
/// vacuum draw none and are not counted): [`SegmentCounter::next`] gives
/// the block of such a segment.
#[derive(Clone, Copy, Debug)]
pub(super) struct SegmentCounter {
    last: Block,
}

impl Default for SegmentCounter {
    fn default() -> SegmentCounter {
        SegmentCounter { last: Block { bounce: u32::MAX, repeat: 0 } }
    }
}

impl SegmentCounter {
    /// The block of a segment that draws numbers after `depth` scattering events.
    #[inline]
    pub(super) fn next(&mut self, depth: u32) -> Block {
        self.last = if self.last.bounce == depth {
            Block { bounce: depth, repeat: self.last.repeat + 1 }
        } else {
            Block { bounce: depth, repeat: 0 }
        };
        self.last
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{hash_u64, SamplerKind};
    use glam::Vec2;

    /// Every slot lies inside the block, and no two slots share a dimension.
    #[test]
    fn slots_are_disjoint_and_inside_the_block() {
        let slots = [
            FREE_FLIGHT,
            DIRECTION,
            LIGHT_POINT,
            LIGHT_CHOICE,
            ROULETTE,
            EQUIANGULAR,
            EQUIANGULAR_CHOICE,
            LOBE,
            PANE,
            GUIDE,
            GUIDE_RADIUS,
            VOLUME_LIGHT,
        ];
        let mut owner = [usize::MAX; BLOCK as usize];
        for (i, s) in slots.iter().enumerate() {
            for d in s.offset..s.offset + s.len {
                // The equiangular slot skips dimension 9 (its pair starts at 10).
                if i == 5 && d == 9 {
                    continue;
                }
                assert!(d < BLOCK, "slot {i} leaves the block");
                assert_eq!(owner[d as usize], usize::MAX, "dimension {d} of slots {} and {i}", owner[d as usize]);
                owner[d as usize] = i;
            }
        }
        // 2D decisions take whole pairs.
        for s in [FREE_FLIGHT, DIRECTION, LIGHT_POINT] {
            assert_eq!((CAMERA + s.offset) % 2, 0);
        }
        assert_eq!((CAMERA + EQUIANGULAR.offset + 2) % 2, 0);
        assert_eq!((CAMERA + VOLUME_LIGHT.offset + 1) % 2, 0);
        assert_eq!(BLOCK % 2, 0);
    }

    /// The numbers of one camera sample as a path with `nulls` null
    /// collisions before its first real one and `shadow` shadow-ray draws
    /// would draw them (in `path.rs`'s order): the direction pair of vertex 1.
    fn direction_of_vertex_1(kind: SamplerKind, s: u64, nulls: u64, shadow: u64) -> Vec2 {
        let mut sampler = PixelSampler::for_pixel(kind, 9, 5, 3, s);
        let _pixel = sampler.next_2d();
        let segment = SegmentCounter::default().next(0);
        segment.enter(&mut sampler, EQUIANGULAR);
        let _ = (sampler.next_1d(), sampler.next_2d());
        segment.enter(&mut sampler, FREE_FLIGHT);
        for _ in 0..=nulls {
            let _distance_and_event = (sampler.next_1d(), sampler.next_1d());
        }
        let vertex = Block::vertex(1);
        vertex.enter(&mut sampler, LIGHT_CHOICE);
        let _ = sampler.next_1d();
        vertex.enter(&mut sampler, LIGHT_POINT);
        let _ = sampler.next_2d();
        for _ in 0..shadow {
            let _ = sampler.next_1d();
        }
        vertex.enter(&mut sampler, DIRECTION);
        sampler.next_2d()
    }

    /// How many elementary intervals `2^-a x 2^-(k-a)` of `points` (`2^k`
    /// of them) hold other than exactly one point.
    fn bad_intervals(points: &[Vec2], k: u32) -> usize {
        let mut bad = 0;
        for a in 0..=k {
            let (nx, ny) = (1usize << a, 1usize << (k - a));
            let mut count = vec![0u32; nx * ny];
            for p in points {
                let (i, j) = ((p.x * nx as f32) as usize, (p.y * ny as f32) as usize);
                count[j.min(ny - 1) * nx + i.min(nx - 1)] += 1;
            }
            bad += count.iter().filter(|&&c| c != 1).count();
        }
        bad
    }

    /// The direction pair of vertex 1 over the first `2^k` samples of a
    /// pixel is a (0, k, 2)-net (one point in every elementary interval),
    /// whatever the number of null collisions and shadow-ray draws before
    /// it; in draw order (`sobol_sequential`) it is not.
    #[test]
    fn vertex_direction_is_stratified_whatever_came_before() {
        let k = 8;
        let events = |s: u64| (hash_u64(s) % 7, hash_u64(s ^ 0xABCD) % 5);
        let points = |kind| -> Vec<Vec2> {
            (0..1u64 << k)
                .map(|s| {
                    let (nulls, shadow) = events(s);
                    direction_of_vertex_1(kind, s, nulls, shadow)
                })
                .collect()
        };
        assert_eq!(bad_intervals(&points(SamplerKind::Sobol), k), 0);
        // Without the layout, the pair lands on a dimension that varies with
        // the events: far from a net (an independent set of 256 points
        // leaves about 1/e of the 9 * 256 intervals empty).
        let sequential = bad_intervals(&points(SamplerKind::SobolSequential), k);
        assert!(sequential > 500, "{sequential}");
        // With a fixed number of events, the sequential layout is stratified too.
        let fixed: Vec<Vec2> =
            (0..1u64 << k).map(|s| direction_of_vertex_1(SamplerKind::SobolSequential, s, 2, 3)).collect();
        assert_eq!(bad_intervals(&fixed, k), 0);
    }

    /// Every number drawn under the layout is uniform: mean 1/2 and
    /// variance 1/12 of the free-flight numbers beyond the slot, and of
    /// the deep (not laid out) bounces (4096 draws each: standard errors
    /// 4.5e-3 and 1.3e-3, bounds at 5 of them).
    #[test]
    fn numbers_beyond_slots_are_uniform() {
        for bounce in [0, LAID_OUT_BOUNCES + 3] {
            let v: Vec<f64> = (0..4096u64)
                .map(|s| {
                    let mut sampler = PixelSampler::for_pixel(SamplerKind::Sobol, 1, 2, 3, s);
                    Block { bounce, repeat: 0 }.enter(&mut sampler, FREE_FLIGHT);
                    for _ in 0..5 {
                        sampler.next_1d();
                    }
                    sampler.next_1d() as f64
                })
                .collect();
            let n = v.len() as f64;
            let mean = v.iter().sum::<f64>() / n;
            let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n;
            assert!((mean - 0.5).abs() < 5.0 * 4.5e-3, "bounce {bounce}: mean {mean}");
            assert!((var - 1.0 / 12.0).abs() < 5.0 * 1.3e-3, "bounce {bounce}: variance {var}");
        }
    }

    /// A repeated slot gives other numbers than its first use, and the
    /// first use is the slot's Sobol dimensions.
    #[test]
    fn repeated_slots_draw_other_numbers() {
        let mut a = PixelSampler::for_pixel(SamplerKind::Sobol, 4, 1, 1, 17);
        let mut b = a.clone();
        Block { bounce: 2, repeat: 0 }.enter(&mut a, DIRECTION);
        Block { bounce: 2, repeat: 1 }.enter(&mut b, DIRECTION);
        let first = a.next_2d();
        assert_ne!(first, b.next_2d());
        // The same sequence in draw order, at the slot's dimension.
        let mut c = PixelSampler::for_pixel(SamplerKind::SobolSequential, 4, 1, 1, 17);
        for _ in 0..(Block { bounce: 2, repeat: 0 }).start(DIRECTION) {
            c.next_1d();
        }
        assert_eq!(first, c.next_2d());
    }

    #[test]
    fn segments_of_a_bounce_are_counted() {
        let mut c = SegmentCounter::default();
        assert_eq!(c.next(0), Block { bounce: 0, repeat: 0 });
        assert_eq!(c.next(0), Block { bounce: 0, repeat: 1 });
        assert_eq!(c.next(1), Block { bounce: 1, repeat: 0 });
        assert_eq!(c.next(1), Block { bounce: 1, repeat: 1 });
        assert_eq!(c.next(1), Block { bounce: 1, repeat: 2 });
        assert_eq!(c.next(2), Block { bounce: 2, repeat: 0 });
    }
}
