//! Single scattering along the camera ray (pbrt 2nd edition
//! `SingleScatteringIntegrator`), with equiangular sampling toward point and
//! spot lights (Kulla and Fajardo 2012) and its MIS combination with distance
//! sampling. Surfaces are lit directly; media emission is included.

use crate::color::Rgb;
use crate::light::Light;
use crate::math::{Ray, Vec3};
use crate::medium::{Medium, MediumId};
use crate::sampling::{balance_heuristic, equiangular_pdf, sample_equiangular, PixelSampler};
use crate::scene::Scene;
use crate::tracking::{majorant_profile, segment_transmittance, MarchStep, TransmittanceMethod};

use super::emission::{emission_segment, march_segment, marched_range};
use super::{default_march_step, light_in_scattered_radiance, trace_camera_ray, Integrator, SegmentRadiance};

/// How the single-scattering integrator picks scattering points on a camera ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SingleSampling {
    /// Stratified jittered ray marching with a shadow ray to every light at
    /// every step.
    March,
    /// Per point or spot light one equiangular sample on each segment; other
    /// lights use one distance sample.
    Equiangular,
    /// Equiangular and distance samples for point and spot lights, combined by
    /// the balance heuristic; other lights use the distance sample.
    Mis,
}

/// The single-scattering integrator.
#[derive(Clone, Copy, Debug)]
pub struct SingleIntegrator {
    /// Ray-march step for `March`; `None` picks [`default_march_step`] per medium.
    pub step: Option<MarchStep>,
    /// Choice of scattering points.
    pub sampling: SingleSampling,
    /// Transmittance estimator for camera and shadow rays.
    pub transmittance: TransmittanceMethod,
}

impl Integrator for SingleIntegrator {
    fn radiance(&self, scene: &Scene, ray: Ray, medium: Option<MediumId>, sampler: &mut PixelSampler) -> Rgb {
        let diagonal = scene.diagonal();
        trace_camera_ray(scene, ray, medium, self.transmittance, sampler, |m, id, ray, t_end, sampler| {
            self.segment_in(scene, m, id, ray, t_end, diagonal, sampler)
        })
    }
}

impl SingleIntegrator {
    /// Emission plus single scattering over `[0, t_end)` of `ray` inside medium
    /// `id` (`t_end` may be infinite), attenuated to the ray origin, and the
    /// transmittance across the segment. Surfaces play no part here except as
    /// occluders of shadow rays.
    pub fn segment(
        &self,
        scene: &Scene,
        id: MediumId,
        ray: &Ray,
        t_end: f32,
        sampler: &mut PixelSampler,
    ) -> SegmentRadiance {
        self.segment_in(scene, scene.medium(id), id, ray, t_end, scene.diagonal(), sampler)
    }

    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn segment_in(
        &self,
        scene: &Scene,
        m: &Medium,
        id: MediumId,
        ray: &Ray,
        t_end: f32,
        diagonal: f32,
        sampler: &mut PixelSampler,
    ) -> SegmentRadiance {
        match self.sampling {
            SingleSampling::March => self.march(scene, m, id, ray, t_end, diagonal, sampler),
            SingleSampling::Equiangular | SingleSampling::Mis => {
                self.sampled(scene, m, id, ray, t_end, diagonal, sampler)
            }
        }
    }

    /// Ray-marched segment: emission as in the emission integrator (closed form
    /// for homogeneous media with analytic transmittance), plus
    /// `sum_i T(0, t_i) sigma_s(t_i) sum_lights p T_l L_l dt` at stratified
    /// jittered points `t_i = (i + u) dt`.
    #[allow(clippy::too_many_arguments)]
    fn march(
        &self,
        scene: &Scene,
        m: &Medium,
        id: MediumId,
        ray: &Ray,
        t_end: f32,
        diagonal: f32,
        sampler: &mut PixelSampler,
    ) -> SegmentRadiance {
        let emitted = emission_segment(m, ray, t_end, self.step, self.transmittance, diagonal, sampler);
        let Some((t_a, t_b)) = marched_range(m, ray, t_end, diagonal) else {
            return emitted;
        };
        let step = self.step.unwrap_or_else(|| default_march_step(m.max_sigma_t(), diagonal));
        let wo = -ray.d;
        let method = self.transmittance;
        let scattered = march_segment(m, ray, t_a, t_b, step, method, sampler, |mp, p, sampler| {
            let mut source = Rgb::ZERO;
            if !mp.sigma_s.is_black() {
                for light in &scene.lights {
                    source += light_in_scattered_radiance(scene, light, p, wo, m.phase(), Some(id), method, sampler);
                }
                source *= mp.sigma_s;
            }
            source
        });
        SegmentRadiance { radiance: emitted.radiance + scattered.radiance, transmittance: emitted.transmittance }
    }

    /// Sampled segment: emission as in the emission integrator, in-scattering
    /// from one distance sample (all lights) plus one equiangular sample per
    /// point-like light.
    #[allow(clippy::too_many_arguments)]
    fn sampled(
        &self,
        scene: &Scene,
        m: &Medium,
        id: MediumId,
        ray: &Ray,
        t_end: f32,
        diagonal: f32,
        sampler: &mut PixelSampler,
    ) -> SegmentRadiance {
        let mut seg = emission_segment(m, ray, t_end, self.step, self.transmittance, diagonal, sampler);
        let wo = -ray.d;
        let mis = self.sampling == SingleSampling::Mis;

        // Distance sampling: a piecewise-exponential density over the majorant
        // segments with the channel-averaged extinction (for a homogeneous
        // medium, sigma_t_avg exp(-sigma_t_avg t) truncated to the segment).
        // Any density that covers the medium keeps the estimator unbiased; this
        // one is computable exactly, so MIS can weigh it against equiangular.
        let profile = majorant_profile(m, ray, 0.0, t_end, m.sigma_t_per_density().average());
        let can_distance_sample = !profile.is_empty();
        let u_distance = sampler.next_1d();
        if let Some(t) = profile.sample(u_distance) {
            let pdf = profile.pdf(t);
            if pdf > 0.0 && pdf.is_finite() {
                let p = ray.at(t);
                let mp = m.at(p);
                if !mp.sigma_s.is_black() {
                    let tr = segment_transmittance(m, ray, 0.0, t, self.transmittance, sampler);
                    let mut li = Rgb::ZERO;
                    for light in &scene.lights {
                        let weight = match equiangular_target(light, ray, t_end) {
                            PointLightTarget::Interval(e) if mis => balance_heuristic(pdf, e.pdf(t)),
                            // Equiangular sampling alone covers its interval.
                            PointLightTarget::Interval(e) if e.contains(t) => 0.0,
                            PointLightTarget::Missed => 0.0,
                            _ => 1.0,
                        };
                        if weight > 0.0 {
                            li += light_in_scattered_radiance(
                                scene,
                                light,
                                p,
                                wo,
                                m.phase(),
                                Some(id),
                                self.transmittance,
                                sampler,
                            ) * weight;
                        }
                    }
                    seg.radiance += tr * mp.sigma_s * li / pdf;
                }
            }
        }

        // Equiangular samples toward each point-like light.
        for light in &scene.lights {
            if light.point_position().is_none() {
                continue;
            }
            let u = sampler.next_1d();
            let PointLightTarget::Interval(e) = equiangular_target(light, ray, t_end) else {
                continue;
            };
            let t = e.sample(u);
            let pdf = e.pdf(t);
            if !(pdf > 0.0 && pdf.is_finite()) {
                continue;
            }
            let weight = if mis && can_distance_sample { balance_heuristic(pdf, profile.pdf(t)) } else { 1.0 };
            let p = ray.at(t);
            let mp = m.at(p);
            if mp.sigma_s.is_black() {
                continue;
            }
            let tr = segment_transmittance(m, ray, 0.0, t, self.transmittance, sampler);
            let li = light_in_scattered_radiance(scene, light, p, wo, m.phase(), Some(id), self.transmittance, sampler);
            seg.radiance += tr * mp.sigma_s * li * (weight / pdf);
        }
        seg
    }
}

/// Where equiangular sampling toward a light applies on a ray segment.
#[derive(Clone, Copy, Debug)]
enum PointLightTarget {
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
struct EquiangularInterval {
    t_a: f32,
    t_b: f32,
    t_c: f32,
    h: f32,
}

impl EquiangularInterval {
    #[inline]
    fn sample(&self, u: f32) -> f32 {
        sample_equiangular(u, self.t_a, self.t_b, self.t_c, self.h)
    }
    #[inline]
    fn contains(&self, t: f32) -> bool {
        t >= self.t_a && t <= self.t_b
    }
    /// Density at `t`; zero outside the interval.
    #[inline]
    fn pdf(&self, t: f32) -> f32 {
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
fn equiangular_target(light: &Light, ray: &Ray, t_end: f32) -> PointLightTarget {
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
fn cone_hull(ray: &Ray, apex: Vec3, axis: Vec3, cos_cutoff: f32, t_end: f32) -> Option<(f32, f32)> {
    let w = ray.o - apex;
    let (da, wa) = (ray.d.dot(axis), w.dot(axis));
    let cos2 = cos_cutoff * cos_cutoff;
    // f(t) = (v.a)^2 - cos^2 |v|^2 with v = w + t d; inside where f > 0 and v.a > 0.
    let qa = da * da - cos2;
    let qb = da * wa - cos2 * ray.d.dot(w);
    let qc = wa * wa - cos2 * w.dot(w);
    let mut breaks = vec![0.0f32];
    let disc = qb * qb - qa * qc;
    if qa != 0.0 && disc >= 0.0 {
        let r = disc.sqrt();
        breaks.push((-qb - r) / qa);
        breaks.push((-qb + r) / qa);
    } else if qa == 0.0 && qb != 0.0 {
        breaks.push(-qc / (2.0 * qb));
    }
    if da != 0.0 {
        breaks.push(-wa / da);
    }
    breaks.retain(|t| t.is_finite() && *t >= 0.0 && *t < t_end);
    breaks.push(t_end);
    breaks.sort_by(|a, b| a.total_cmp(b));
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
fn equiangular_geometry(ray: &Ray, c: Vec3) -> Option<(f32, f32)> {
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
