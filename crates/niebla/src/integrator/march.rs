//! Ray-march helpers shared by the integrators that march camera rays:
//! the default step, jittered steps through a grid medium, and where an
//! unbounded homogeneous segment stops mattering.

use std::ops::ControlFlow;

use crate::color::Rgb;
use crate::math::Ray;
use crate::sampling::PixelSampler;
use crate::tracking::MarchStep;

/// Ray-march step used when a scene gives none: a quarter of the mean free
/// path of the densest channel, but never coarser than 1/64 of the scene
/// diagonal and at most 4096 steps over the diagonal.
pub fn default_march_step(max_sigma_t: f32, scene_diagonal: f32) -> MarchStep {
    let diag = if scene_diagonal.is_finite() && scene_diagonal > 0.0 { scene_diagonal } else { 10.0 };
    let mfp_step = if max_sigma_t > 0.0 { 0.25 / max_sigma_t } else { f32::INFINITY };
    MarchStep::Length(mfp_step.min(diag / 64.0).max(diag / 4096.0))
}

/// How many times longer the view-ray march step of the interactive
/// integrators (`hegeman`, `zhou`) is in a live viewer's drag frames
/// ([`crate::render::PreparedIntegrator::set_drag_march`]) than in their
/// settings: the march is the largest cost of a drag frame, and it scales
/// with the number of steps. Finished frames march the settings' step.
pub const DRAG_STEP_FACTOR: f32 = 2.0;

/// Jittered steps along the part of a camera-ray segment `[0, t_end]` inside a
/// grid medium's bounds: `n` equal steps (about `step` long, 1 to 4096) with
/// one offset `u` in [0, 1) shared by all, sample `k` at `a + (k + u) dt`.
/// Used by the interactive integrators' view-ray marches.
#[derive(Clone, Copy, Debug)]
pub(crate) struct JitteredSteps {
    /// Start of the clipped segment (ray parameter).
    pub a: f32,
    /// Step length (ray parameter).
    pub dt: f32,
    /// Number of steps.
    pub n: usize,
    /// Offset of the samples within their steps.
    pub u: f32,
}

impl JitteredSteps {
    /// The steps of `ray` within `g`'s bounds up to `t_end`; `None` when the
    /// segment misses the medium.
    pub fn new(
        g: &crate::medium::GridMedium,
        ray: &Ray,
        t_end: f32,
        step: f32,
        sampler: &mut PixelSampler,
    ) -> Option<JitteredSteps> {
        let (a, b) = g.clip(ray, 0.0, t_end)?;
        let n = ((b - a) / step).ceil().clamp(1.0, 4096.0) as usize;
        Some(JitteredSteps { a, dt: (b - a) / n as f32, n, u: sampler.next_1d() })
    }

    /// Ray parameter of sample `k`.
    #[inline]
    pub fn t(&self, k: usize) -> f32 {
        self.a + (k as f32 + self.u) * self.dt
    }

    /// Calls `f` with ranges of step indices, increasing and disjoint,
    /// that hold every step whose sample can see a positive density of
    /// `g` (its density grid, as [`crate::medium::GridMedium::density_at`]
    /// reads it, at rest): the steps within one step of a cell of `g`'s
    /// majorant grid with a positive bound along `ray`, found with the
    /// grid's DDA ([`niebla_volume::MajorantGrid::walk_nonzero`]). A step left out reads a density of exactly zero (the
    /// majorant bounds every voxel the trilinear lookup reads, and the
    /// margin of one step covers the rounding of the sample's position), so
    /// a march that skips steps of zero density gives the same bits over
    /// these ranges as over all steps, without the lookups of empty
    /// space. Stops when `f` breaks.
    pub fn occupied(
        &self,
        g: &crate::medium::GridMedium,
        ray: &Ray,
        mut f: impl FnMut(std::ops::Range<usize>) -> ControlFlow<()>,
    ) -> ControlFlow<()> {
        let (o, d) = g.ray_to_grid(ray);
        let b = self.a + self.n as f32 * self.dt;
        // Step index of ray parameter `t` (fractional: sample k sits at k + u).
        let index = |t: f32| (t - self.a) / self.dt - self.u;
        let mut next = 0usize;
        // Empty cells are left out by the walk (a step per empty 4^3 block).
        g.majorant.walk_nonzero(o.to_array(), d.to_array(), self.a - self.dt, b + self.dt, |_, s| {
            // Past the last step: later cells can add no step (the
            // ranges only grow), so the walk stops.
            if next >= self.n {
                return ControlFlow::Break(());
            }
            if s.max_density <= 0.0 {
                return ControlFlow::Continue(());
            }
            let lo = (index(s.t0).floor() - 1.0).max(0.0) as usize;
            let hi = ((index(s.t1).ceil() + 2.0).max(0.0) as usize).min(self.n);
            let lo = lo.max(next);
            if lo >= hi {
                return ControlFlow::Continue(());
            }
            next = hi;
            f(lo..hi)
        })
    }
}

/// Distance beyond which an unbounded homogeneous segment contributes less
/// than 1e-6 of its total (transmittance of the least attenuated channel that
/// matters drops below 1e-6); `None` when some channel does not attenuate.
#[inline]
pub(crate) fn negligible_distance(sigma_t: Rgb) -> Option<f32> {
    let min = sigma_t.min_channel();
    if min > 0.0 {
        Some(13.8155 / min)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;
    use crate::medium::Medium;
    use crate::scene::{build_scene, parse_scene_str};

    /// A procedural plume (much empty space in its box) placed off the origin.
    fn plume() -> crate::medium::GridMedium {
        let text = r#"{"version": 1,
          "camera": {"type": "perspective", "position": [0, 1, 5], "target": [0, 1, 0], "width": 4, "height": 4},
          "media": {"plume": {"type": "grid",
             "density": {"type": "procedural", "shape": "plume", "seed": 7, "resolution": 32},
             "sigma_t": 10, "albedo": 0.9, "to_world": {"scale": 2, "translate": [-1, 0, -1]}}},
          "ambient_medium": "plume"}"#;
        let built = build_scene(&parse_scene_str(text, "plume.json").unwrap(), "plume.json", ".".as_ref()).unwrap();
        match &built.scene.media[0] {
            Medium::Grid(g) => g.clone(),
            Medium::Homogeneous(_) => unreachable!("a grid medium"),
        }
    }

    #[test]
    fn steps_outside_the_occupied_ranges_read_zero_density() {
        let g = plume();
        // A small LCG: rays from points around and inside the box, every direction.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let (mut skipped, mut total, mut rays) = (0usize, 0usize, 0usize);
        while rays < 2000 {
            let o = Vec3::new(6.0 * uniform() - 3.0, 6.0 * uniform() - 2.0, 6.0 * uniform() - 3.0);
            let d = Vec3::new(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5);
            if d.length() < 0.05 {
                continue;
            }
            let ray = Ray::new(o, d.normalize());
            let Some((a, b)) = g.clip(&ray, 0.0, 100.0) else { continue };
            rays += 1;
            for n in [1, 7, 48, 333] {
                for u in [0.0, 0.37, 0.999_999] {
                    let steps = JitteredSteps { a, dt: (b - a) / n as f32, n, u };
                    let mut visited = vec![false; n];
                    let mut last = 0;
                    let _ = steps.occupied(&g, &ray, |range| {
                        assert!(range.start >= last && range.start < range.end && range.end <= n, "{range:?}");
                        last = range.end;
                        visited[range].iter_mut().for_each(|v| *v = true);
                        ControlFlow::Continue(())
                    });
                    for (k, seen) in visited.iter().enumerate() {
                        total += 1;
                        if !seen {
                            skipped += 1;
                            let density = g.density_at(ray.at(steps.t(k)));
                            assert!(density <= 0.0, "step {k} of {n} (u {u}) skipped at density {density}: {ray:?}");
                        }
                    }
                }
            }
        }
        // The point of the ranges: much of the box is empty.
        eprintln!("skipped {skipped} of {total} steps");
        assert!(skipped * 5 > total, "only {skipped} of {total} steps skipped");
    }

    /// The march's density reader gives the bits of `density_at` along
    /// rays through and around the plume (a dense f32 grid: the unpacked
    /// lookup).
    #[test]
    fn density_reader_matches_density_at_bit_for_bit() {
        let g = plume();
        assert!(matches!(g.density_reader(), crate::medium::DensityReader::DenseF32 { .. }));
        let reader = g.density_reader();
        let mut state = 0x5851_f42d_4c95_7f2du64;
        let mut uniform = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut positive = 0;
        for _ in 0..500 {
            let o = Vec3::new(6.0 * uniform() - 3.0, 6.0 * uniform() - 2.0, 6.0 * uniform() - 3.0);
            let d = Vec3::new(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5);
            let ray = Ray::new(o, d.normalize_or_zero());
            for k in 0..200 {
                let x = ray.at(k as f32 * 0.03);
                let (fast, slow) = (reader.at(x), g.density_at(x));
                assert_eq!(fast.to_bits(), slow.to_bits(), "at {x:?}");
                positive += (slow > 0.0) as usize;
            }
        }
        // 359 with this seed: enough non-zero values to compare.
        assert!(positive > 200, "only {positive} lookups inside the plume");
    }

    #[test]
    fn a_break_stops_the_ranges() {
        let g = plume();
        // The first horizontal ray through the middle that crosses an occupied range.
        let (ray, steps) = (1..40)
            .map(|i| {
                let ray = Ray::new(Vec3::new(0.0, 0.05 * i as f32, 5.0), Vec3::new(0.0, 0.0, -1.0));
                let (a, b) = g.clip(&ray, 0.0, 100.0).unwrap();
                (ray, JitteredSteps { a, dt: (b - a) / 200.0, n: 200, u: 0.5 })
            })
            .find(|(ray, steps)| {
                let mut ranges = 0;
                let _ = steps.occupied(&g, ray, |_| {
                    ranges += 1;
                    ControlFlow::Continue(())
                });
                ranges >= 1
            })
            .expect("a ray through the plume");
        let mut calls = 0;
        let flow = steps.occupied(&g, &ray, |_| {
            calls += 1;
            ControlFlow::Break(())
        });
        assert_eq!((flow, calls), (ControlFlow::Break(()), 1));
    }
}
