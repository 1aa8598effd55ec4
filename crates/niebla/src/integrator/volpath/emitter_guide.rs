//! `volpath`'s guide toward emissive media at surface and medium vertices
//! ([`EmitterGuide`]): directions toward uniform points of a few boxes
//! around the emitting region, whose density in solid angle has a closed form.
//!
//! A point `y` uniform in an axis-aligned box of volume `V` seen from `x`
//! gives the direction `w = (y - x) / |y - x|` with solid-angle density
//! `p(w) = (1 / V) * integral of s^2 ds` over the part `[s_0, s_1]` of the
//! ray `x + s w` (`s >= 0`) inside the box, that is
//! `(s_1^3 - s_0^3) / (3 V)`: one ray-box intersection. It integrates to 1
//! over the sphere of directions (the box's volume in polar coordinates
//! about `x`) and is positive for every direction that meets the box.

use crate::math::{Ray, Vec2, Vec3};

/// Most boxes an [`EmitterGuide`] aims at separately; more are merged
/// into their common bounding box.
pub(crate) const MAX_GUIDE_BOXES: usize = 4;

/// An axis-aligned box (world) as a target of directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GuideBox {
    min: Vec3,
    max: Vec3,
    inv_volume: f32,
}

impl GuideBox {
    /// The box `[min, max]`; `None` unless every extent is positive and finite.
    pub(crate) fn new(min: Vec3, max: Vec3) -> Option<GuideBox> {
        let extent = max - min;
        let volume = extent.x * extent.y * extent.z;
        (extent.cmpgt(Vec3::ZERO).all() && volume.is_finite() && volume > 0.0).then_some(GuideBox {
            min,
            max,
            inv_volume: 1.0 / volume,
        })
    }

    /// A uniform point of the box from three uniform numbers.
    #[inline]
    pub(crate) fn sample(&self, u: Vec3) -> Vec3 {
        self.min + (self.max - self.min) * u
    }

    /// Solid-angle density (1/sr) that the direction from `x` toward a
    /// uniform point of the box is `w` (unit).
    #[inline]
    pub(crate) fn direction_pdf(&self, x: Vec3, w: Vec3) -> f32 {
        let ray = Ray::new(x, w);
        let inv = ray.d.recip();
        let t0 = (self.min - ray.o) * inv;
        let t1 = (self.max - ray.o) * inv;
        let near = t0.min(t1).max_element().max(0.0);
        let far = t0.max(t1).min_element();
        if !(far > near) {
            return 0.0;
        }
        let (a, b) = (f64::from(near), f64::from(far));
        let pdf = (b * b * b - a * a * a) / 3.0 * f64::from(self.inv_volume);
        if pdf.is_finite() {
            pdf as f32
        } else {
            0.0
        }
    }
}

/// Direction guiding toward emissive media at surface and medium vertices.
///
/// A surface lit by an emissive medium gets its light from the emission
/// itself (sampled by next-event estimation toward the emitting cells) and
/// from light that the medium around the emission scatters, which only
/// paths that enter the medium find; cosine-weighted BSDF sampling sends
/// few directions there when the medium subtends a small solid angle. The
/// guide draws directions toward uniform points of the bounding box of each
/// emitter's emitting region (one box chosen uniformly); `volpath` mixes
/// them with BSDF sampling by one-sample MIS, so every direction keeps the
/// BSDF's share of the density. On the fire showcase a box twice the
/// emitting region's size, alone or mixed with it, was less efficient on
/// the floor than the emitting region's box alone. A scattering vertex in a
/// medium around the emitter (smoke over a fire) is in the same position,
/// with the phase function in place of the BSDF, and mixes the same guide
/// in with a smaller share.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct EmitterGuide {
    boxes: [Option<GuideBox>; MAX_GUIDE_BOXES],
    count: usize,
}

impl EmitterGuide {
    /// The guide toward `boxes`, one chosen uniformly per direction; more
    /// than [`MAX_GUIDE_BOXES`] are replaced by their common bounding box.
    pub(crate) fn new(boxes: impl IntoIterator<Item = GuideBox>) -> EmitterGuide {
        let all: Vec<GuideBox> = boxes.into_iter().collect();
        let mut guide = EmitterGuide::default();
        if all.len() > MAX_GUIDE_BOXES {
            let lo = all.iter().fold(Vec3::splat(f32::INFINITY), |a, b| a.min(b.min));
            let hi = all.iter().fold(Vec3::splat(f32::NEG_INFINITY), |a, b| a.max(b.max));
            guide.boxes[0] = GuideBox::new(lo, hi);
            guide.count = usize::from(guide.boxes[0].is_some());
            return guide;
        }
        for b in all {
            guide.boxes[guide.count] = Some(b);
            guide.count += 1;
        }
        guide
    }

    /// Whether some box is guided toward.
    #[inline]
    pub(crate) fn is_active(&self) -> bool {
        self.count > 0
    }

    /// A unit direction from `x` toward a uniform point of one box (chosen
    /// uniformly with `u_box`, the point from `u_dir` and `u_r`); `None`
    /// when that point is `x`.
    #[inline]
    pub(crate) fn sample(&self, x: Vec3, u_box: f32, u_dir: Vec2, u_r: f32) -> Option<Vec3> {
        let k = ((u_box * self.count as f32) as usize).min(self.count.saturating_sub(1));
        let to = self.boxes[k]?.sample(Vec3::new(u_dir.x, u_dir.y, u_r)) - x;
        let length = to.length();
        (length > 1e-6 * (1.0 + x.abs().max_element())).then(|| to / length)
    }

    /// Solid-angle density (1/sr) of [`EmitterGuide::sample`] from `x` at `w`.
    #[inline]
    pub(crate) fn pdf(&self, x: Vec3, w: Vec3) -> f32 {
        let sum: f32 = self.boxes[..self.count].iter().flatten().map(|b| b.direction_pdf(x, w)).sum();
        sum / self.count.max(1) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::volpath::guide_checks::{sampled_and_integrated, sphere_integral};
    use crate::sampling::PixelSampler;

    /// Two overlapping boxes, as two emitters' regions.
    fn guide() -> EmitterGuide {
        let fire = GuideBox::new(Vec3::new(-0.4, 0.05, -0.3), Vec3::new(0.35, 0.8, 0.4)).unwrap();
        let smoke = GuideBox::new(Vec3::new(-0.8, 0.3, -0.7), Vec3::new(0.8, 1.6, 0.7)).unwrap();
        EmitterGuide::new([fire, smoke])
    }

    /// The direction density integrates to 1 over the sphere of directions
    /// (Monte Carlo with uniform directions, 400k samples, within 4 standard
    /// errors), from outside both boxes, inside one only, and inside both.
    #[test]
    fn direction_pdf_integrates_to_one() {
        let g = guide();
        // Outside both, inside the larger only, inside both.
        for x in [Vec3::new(0.2, 0.0, 2.0), Vec3::new(0.6, 0.5, 0.0), Vec3::new(0.0, 0.4, 0.0)] {
            let (mean, se) = sphere_integral(&mut PixelSampler::from_key(17), 400_000, |w| g.pdf(x, w));
            assert!((mean - 1.0).abs() < 4.0 * se, "from {x}: {mean} +- {se}");
        }
    }

    /// Sampled directions follow the density: the mean of `min(p, c)` over
    /// the guide's own samples equals the integral of `p min(p, c)` estimated
    /// with uniform directions (400k samples each; within 2 %).
    #[test]
    fn sampled_directions_follow_the_density() {
        let g = guide();
        let x = Vec3::new(0.3, 0.0, 1.8);
        let sample = |s: &mut PixelSampler| {
            let (u_box, u_dir, u_r) = (s.next_1d(), s.next_2d(), s.next_1d());
            Some(g.sample(x, u_box, u_dir, u_r).unwrap())
        };
        let (a, b) = sampled_and_integrated(&mut PixelSampler::from_key(23), 400_000, 3.0, sample, |w| g.pdf(x, w));
        assert!((a - b).abs() < 0.02 * b, "sampled {a} vs integrated {b}");
    }

    /// More boxes than [`MAX_GUIDE_BOXES`] become their common bounding box.
    #[test]
    fn many_boxes_merge_into_one() {
        let unit = |x: f32| GuideBox::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 1.0, 1.0)).unwrap();
        let g = EmitterGuide::new((0..5).map(|k| unit(2.0 * k as f32)));
        assert_eq!(g.count, 1);
        assert_eq!(g.boxes[0], GuideBox::new(Vec3::ZERO, Vec3::new(9.0, 1.0, 1.0)));
        let h = EmitterGuide::new((0..3).map(|k| unit(2.0 * k as f32)));
        assert_eq!(h.count, 3);
    }
}
