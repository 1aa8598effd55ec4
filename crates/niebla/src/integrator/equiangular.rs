//! Equiangular sampling (Kulla and Fajardo 2012) of points on a ray segment
//! toward point and spot lights, shared by `single` and `volpath`: the
//! interval to sample (the whole segment, or the hull of its part inside a
//! spot light's cone) and its density.

use crate::light::Light;
use crate::math::{Ray, Vec3};
use crate::sampling::{equiangular_pdf, sample_equiangular};

/// Where equiangular sampling toward a light applies on a ray segment.
#[derive(Clone, Copy, Debug)]
pub(crate) enum PointLightTarget {
    /// Not a point or spot light: distance sampling only.
    NotPointLike,
    /// The light lies on the ray's line, where equiangular sampling degenerates.
    Degenerate,
    /// A spot light whose cone the segment never enters: no contribution.
    Missed,
    /// Sample equiangularly over this interval.
    Interval(EquiangularInterval),
}

/// Equiangular sampling over `[t_a, t_b]` toward a point at distance `h` from
/// the ray's line, closest approach at `t_c`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EquiangularInterval {
    t_a: f32,
    t_b: f32,
    t_c: f32,
    h: f32,
}

impl EquiangularInterval {
    #[inline]
    pub(crate) fn sample(&self, u: f32) -> f32 {
        sample_equiangular(u, self.t_a, self.t_b, self.t_c, self.h)
    }
    #[inline]
    pub(crate) fn contains(&self, t: f32) -> bool {
        t >= self.t_a && t <= self.t_b
    }
    /// Density at `t`; zero outside the interval.
    #[inline]
    pub(crate) fn pdf(&self, t: f32) -> f32 {
        if self.contains(t) {
            equiangular_pdf(t, self.t_a, self.t_b, self.t_c, self.h)
        } else {
            0.0
        }
    }
}

/// The equiangular interval of `light` on `[0, t_end)` of `ray`: the whole
/// segment for a point light; for a spot light the hull of the parts inside
/// its cone (Kulla and Fajardo 2012 suggest clipping to the cone), which keeps
/// samples where the light can contribute.
pub(crate) fn equiangular_target(light: &Light, ray: &Ray, t_end: f32) -> PointLightTarget {
    let Some(c) = light.point_position() else {
        return PointLightTarget::NotPointLike;
    };
    let Some((t_c, h)) = equiangular_geometry(ray, c) else {
        return PointLightTarget::Degenerate;
    };
    let (t_a, t_b) = match light {
        Light::Spot(spot) => match cone_hull(ray, spot.position, spot.frame.z, spot.cutoff_angle.cos(), t_end) {
            Some(range) => range,
            None => return PointLightTarget::Missed,
        },
        _ => (0.0, t_end),
    };
    PointLightTarget::Interval(EquiangularInterval { t_a, t_b, t_c, h })
}

/// Smallest interval of `[0, t_end)` holding every point of `ray` inside the
/// cone with apex `apex`, unit `axis` and half-angle `acos(cos_cutoff)`;
/// `None` when the ray misses the cone.
pub(crate) fn cone_hull(ray: &Ray, apex: Vec3, axis: Vec3, cos_cutoff: f32, t_end: f32) -> Option<(f32, f32)> {
    let w = ray.o - apex;
    let (da, wa) = (ray.d.dot(axis), w.dot(axis));
    let cos2 = cos_cutoff * cos_cutoff;
    // f(t) = (v.a)^2 - cos^2 |v|^2 with v = w + t d; inside where f > 0 and v.a > 0.
    let qa = da * da - cos2;
    let qb = da * wa - cos2 * ray.d.dot(w);
    let qc = wa * wa - cos2 * w.dot(w);
    // At most 0, two roots (or one), the apex plane and t_end: no allocation.
    let mut candidates = [f32::NAN; 4];
    candidates[0] = 0.0;
    let disc = qb * qb - qa * qc;
    if qa != 0.0 && disc >= 0.0 {
        let r = disc.sqrt();
        candidates[1] = (-qb - r) / qa;
        candidates[2] = (-qb + r) / qa;
    } else if qa == 0.0 && qb != 0.0 {
        candidates[1] = -qc / (2.0 * qb);
    }
    if da != 0.0 {
        candidates[3] = -wa / da;
    }
    let mut breaks = [0.0f32; 5];
    let mut n = 0;
    for t in candidates {
        if t.is_finite() && t >= 0.0 && t < t_end {
            breaks[n] = t;
            n += 1;
        }
    }
    breaks[n] = t_end;
    n += 1;
    let breaks = &mut breaks[..n];
    breaks.sort_unstable_by(|a, b| a.total_cmp(b));
    let inside = |t: f32| {
        let v = w + ray.d * t;
        let va = v.dot(axis);
        va > 0.0 && va * va > cos2 * v.length_squared()
    };
    let mut hull: Option<(f32, f32)> = None;
    for pair in breaks.windows(2) {
        let (lo, hi) = (pair[0], pair[1]);
        if hi <= lo {
            continue;
        }
        let mid = if hi.is_finite() { 0.5 * (lo + hi) } else { lo + 1.0 + lo.abs() };
        if inside(mid) {
            hull = Some(match hull {
                Some((a, _)) => (a, hi),
                None => (lo, hi),
            });
        }
    }
    hull
}

/// Closest-approach parameter `t_c` and distance `h` of point `c` to the ray's
/// line; `None` when the point lies (numerically) on the line, where
/// equiangular sampling degenerates.
#[inline]
pub(crate) fn equiangular_geometry(ray: &Ray, c: Vec3) -> Option<(f32, f32)> {
    let t_c = (c - ray.o).dot(ray.d);
    let h = (c - ray.at(t_c)).length();
    if h > 1e-6 * (1.0 + t_c.abs()) {
        Some((t_c, h))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::PixelSampler;

    /// The cone hull holds every inside point a fine brute-force walk finds,
    /// and its ends are inside points (up to the walk's resolution).
    #[test]
    fn cone_hull_matches_brute_force_walk() {
        let mut s = PixelSampler::from_key(77);
        let mut nonempty = 0;
        for _ in 0..2000 {
            let o = (s.next_2d().extend(s.next_1d()) - 0.5) * 8.0;
            let d = crate::sampling::sample_uniform_sphere(s.next_2d());
            let apex = (s.next_2d().extend(s.next_1d()) - 0.5) * 4.0;
            let axis = crate::sampling::sample_uniform_sphere(s.next_2d());
            let cos_cutoff = (0.1 + 1.3 * s.next_1d()).cos();
            let t_end = 12.0;
            let ray = Ray::new(o, d);
            let inside = |t: f32| {
                let v = ray.at(t) - apex;
                v.dot(axis) > cos_cutoff * v.length()
            };
            let n = 12_000;
            let (mut first, mut last) = (None, None);
            for i in 0..n {
                let t = (i as f32 + 0.5) / n as f32 * t_end;
                if inside(t) {
                    first.get_or_insert(t);
                    last = Some(t);
                }
            }
            let hull = cone_hull(&ray, apex, axis, cos_cutoff, t_end);
            match (first, hull) {
                (None, None) => {}
                (Some(f), Some((a, b))) => {
                    nonempty += 1;
                    let l = last.unwrap();
                    let tol = 2.0 * t_end / n as f32;
                    assert!(a <= f + 1e-4 && b >= l - 1e-4, "hull {a}..{b} misses {f}..{l}");
                    assert!(a >= f - tol && b <= l + tol, "hull {a}..{b} too wide for {f}..{l}");
                }
                (Some(f), None) => {
                    // Only a sliver thinner than the walk could be missed by rounding.
                    assert!(last.unwrap() - f < 1e-2, "missed inside range {f}..{:?}", last);
                }
                (None, Some((a, b))) => {
                    assert!(b - a < 2.0 * t_end / n as f32, "hull {a}..{b} where the walk finds nothing");
                }
            }
        }
        assert!(nonempty > 200);
    }
}
