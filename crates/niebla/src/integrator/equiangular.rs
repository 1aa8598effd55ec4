//! Equiangular sampling (Kulla and Fajardo 2012) of points on a ray segment
//! toward point and spot lights, shared by `single` and `volpath`: the
//! interval to sample (the whole segment, or the hull of its part inside a
//! spot light's cone) and its density.

use crate::light::Light;
use crate::math::{Ray, Vec3};
use crate::sampling::{equiangular_angles, equiangular_pdf_at_angles, sample_equiangular_at_angles};

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
/// the ray's line, closest approach at `t_c`, with the interval's two
/// angles computed once (sampling and densities share them).
#[derive(Clone, Copy, Debug)]
pub(crate) struct EquiangularInterval {
    t_a: f32,
    t_b: f32,
    t_c: f32,
    h: f32,
    angles: (f32, f32),
}

impl EquiangularInterval {
    /// The interval `[t_a, t_b]` toward a point at distance `h > 0` from the
    /// line, closest approach at `t_c`.
    #[inline]
    pub(crate) fn new(t_a: f32, t_b: f32, t_c: f32, h: f32) -> EquiangularInterval {
        EquiangularInterval { t_a, t_b, t_c, h, angles: equiangular_angles(t_a, t_b, t_c, h) }
    }
    /// A distance from a uniform number ([`crate::sampling::sample_equiangular`]).
    #[inline]
    pub(crate) fn sample(&self, u: f32) -> f32 {
        sample_equiangular_at_angles(u, self.t_a, self.t_b, self.t_c, self.h, self.angles)
    }
    /// Distance (world units) from the light to the ray's line.
    #[inline]
    pub(crate) fn h(&self) -> f32 {
        self.h
    }
    /// Whether `t` lies in the interval.
    #[inline]
    pub(crate) fn contains(&self, t: f32) -> bool {
        t >= self.t_a && t <= self.t_b
    }
    /// Density at `t`; zero outside the interval.
    #[inline]
    pub(crate) fn pdf(&self, t: f32) -> f32 {
        if self.contains(t) {
            equiangular_pdf_at_angles(t, self.t_c, self.h, self.angles)
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
    PointLightTarget::Interval(EquiangularInterval::new(t_a, t_b, t_c, h))
}

/// Smallest interval of `[0, t_end)` holding every point of `ray` inside the
/// cone with apex `apex`, unit `axis` and half-angle `acos(cos_cutoff)`;
/// `None` when the ray misses the cone.
///
/// The quadratic of the cone's surface is solved in the parameter
/// `s = t - t_c` about the ray's closest approach `t_c` to the apex, where
/// its coefficients are of the size of the ray's distance to the apex: in
/// `t` they are of the size of the origin's distance, and for a ray passing
/// within about `1e-3` of the apex (guided directions aim there) rounding
/// lost the short part inside the cone, so equiangular sampling missed a
/// part that light sampling from free-flight vertices still reached with
/// its full `1/d^2` (single samples thousands of times the pixel's mean).
pub(crate) fn cone_hull(ray: &Ray, apex: Vec3, axis: Vec3, cos_cutoff: f32, t_end: f32) -> Option<(f32, f32)> {
    let t_c = (apex - ray.o).dot(ray.d);
    // The apex seen from the closest approach, and the segment's ends in `s`.
    let w = ray.o + ray.d * t_c - apex;
    let (s_start, s_end) = (-t_c, t_end - t_c);
    let (da, wa) = (ray.d.dot(axis), w.dot(axis));
    let cos2 = cos_cutoff * cos_cutoff;
    // f(s) = (v.a)^2 - cos^2 |v|^2 with v = w + s d; inside where f > 0 and v.a > 0.
    let qa = da * da - cos2;
    let qb = da * wa - cos2 * ray.d.dot(w);
    let qc = wa * wa - cos2 * w.dot(w);
    // At most the start, two roots (or one), the apex plane and the end: no allocation.
    let mut candidates = [f32::NAN; 4];
    candidates[0] = s_start;
    let disc = qb * qb - qa * qc;
    if qa != 0.0 && disc >= 0.0 {
        // Without cancellation: q = -(qb + sign(qb) sqrt(disc)), roots q/qa and qc/q.
        let q = -(qb + disc.sqrt().copysign(qb));
        candidates[1] = q / qa;
        candidates[2] = if q != 0.0 { qc / q } else { f32::NAN };
    } else if qa == 0.0 && qb != 0.0 {
        candidates[1] = -qc / (2.0 * qb);
    }
    if da != 0.0 {
        candidates[3] = -wa / da;
    }
    let mut breaks = [0.0f32; 5];
    let mut n = 0;
    for s in candidates {
        if s.is_finite() && s >= s_start && s < s_end {
            breaks[n] = s;
            n += 1;
        }
    }
    breaks[n] = s_end;
    n += 1;
    let breaks = &mut breaks[..n];
    breaks.sort_unstable_by(|a, b| a.total_cmp(b));
    let inside = |s: f32| {
        let v = w + ray.d * s;
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
    // Back to the ray's parameter, within [0, t_end].
    hull.map(|(a, b)| ((t_c + a).max(0.0), if b == s_end { t_end } else { (t_c + b).min(t_end) }))
        .filter(|(a, b)| b > a)
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

    /// Rays that pass within `1e-2` to `1e-5` of the apex, from 2 to 6 units
    /// away (a guided direction aims there): the hull holds every point a
    /// fine walk across the apex finds inside the cone. Solved in the ray's
    /// own parameter `t`, rounding lost 5% of these points (11043 of 210206).
    #[test]
    fn cone_hull_keeps_the_part_next_to_the_apex() {
        let mut s = PixelSampler::from_key(91);
        let apex = Vec3::new(0.3, 3.0, -0.2);
        let (mut checked, mut found) = (0, 0);
        for i in 0..4000 {
            let axis = crate::sampling::sample_uniform_sphere(s.next_2d());
            let cos_cutoff = (0.1 + 1.2 * s.next_1d()).cos();
            let d = crate::sampling::sample_uniform_sphere(s.next_2d());
            // A point at distance h from the apex, perpendicular to d.
            let h = [1e-2f32, 1e-3, 1e-4, 1e-5][i % 4];
            let side = crate::sampling::sample_uniform_sphere(s.next_2d());
            let perp = (side - d * side.dot(d)).normalize();
            let back = 2.0 + 4.0 * s.next_1d();
            let o = apex + perp * h - d * back;
            let ray = Ray::new(o, d);
            let t_end = if i % 3 == 0 { f32::INFINITY } else { back + 2.0 };
            let hull = cone_hull(&ray, apex, axis, cos_cutoff, t_end);
            let inside = |t: f32| {
                let v = ray.at(t) - apex;
                v.dot(axis) > cos_cutoff * v.length()
            };
            // Walk 40 h across the apex, away from the cone's surface by a
            // margin of rounding (the walk's own points carry 1e-6 errors).
            let n = 400;
            for k in 0..n {
                let t = back + h * (40.0 * (k as f32 + 0.5) / n as f32 - 20.0);
                let v = ray.at(t) - apex;
                let margin = v.dot(axis) - cos_cutoff * v.length();
                if !inside(t) || margin < 3e-6 {
                    continue;
                }
                checked += 1;
                let held = hull.is_some_and(|(a, b)| t >= a - 1e-6 && t <= b + 1e-6);
                found += held as u32;
                assert!(held, "ray {i} (h {h}): inside at t {t} (margin {margin:.1e}), hull {hull:?}");
            }
        }
        assert!(checked > 20_000, "{checked} inside points checked");
        assert_eq!(found, checked);
    }
}
