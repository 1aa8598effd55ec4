//! Single scattering along the camera ray (pbrt 2nd edition
//! `SingleScatteringIntegrator`), with equiangular sampling toward point and
//! spot lights (Kulla and Fajardo 2012) and its MIS combination with distance
//! sampling. Surfaces are lit directly; media emission is included.

use crate::color::Rgb;
use crate::math::{Ray, Vec3};
use crate::medium::{Medium, MediumId};
use crate::sampling::{
    balance_heuristic, equiangular_pdf, sample_equiangular, sample_truncated_exponential,
    truncated_exponential_pdf, PixelSampler,
};
use crate::scene::Scene;
use crate::tracking::{segment_transmittance, MarchStep, TransmittanceMethod};

use super::emission::{bounded_length, emission_segment, march_segment};
use super::{
    default_march_step, light_in_scattered_radiance, trace_camera_ray, Integrator, SegmentRadiance,
};

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
    fn radiance(
        &self,
        scene: &Scene,
        ray: Ray,
        medium: Option<MediumId>,
        sampler: &mut PixelSampler,
    ) -> Rgb {
        let diagonal = scene.diagonal();
        trace_camera_ray(
            scene,
            ray,
            medium,
            self.transmittance,
            sampler,
            |m, id, ray, t_end, sampler| {
                self.segment_in(scene, m, id, ray, t_end, diagonal, sampler)
            },
        )
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
        self.segment_in(
            scene,
            scene.medium(id),
            id,
            ray,
            t_end,
            scene.diagonal(),
            sampler,
        )
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
        let emitted = emission_segment(
            m,
            ray,
            t_end,
            self.step,
            self.transmittance,
            diagonal,
            sampler,
        );
        let t_max = bounded_length(m, t_end, diagonal);
        let step = self
            .step
            .unwrap_or_else(|| default_march_step(m.max_sigma_t(), diagonal));
        let u = sampler.next_1d();
        let wo = -ray.d;
        let scattered = march_segment(ray, t_max, step, u, |p| {
            let mp = m.at(p);
            let mut source = Rgb::ZERO;
            if !mp.sigma_s.is_black() {
                for light in &scene.lights {
                    source += light_in_scattered_radiance(
                        scene,
                        light,
                        p,
                        wo,
                        m.phase(),
                        Some(id),
                        self.transmittance,
                        sampler,
                    );
                }
                source *= mp.sigma_s;
            }
            (mp.sigma_t(), source)
        });
        SegmentRadiance {
            radiance: emitted.radiance + scattered.radiance,
            transmittance: emitted.transmittance,
        }
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
        let mut seg = emission_segment(
            m,
            ray,
            t_end,
            self.step,
            self.transmittance,
            diagonal,
            sampler,
        );
        let wo = -ray.d;
        let mis = self.sampling == SingleSampling::Mis;

        // Distance sampling: pdf proportional to sigma exp(-sigma t) on [0, t_end)
        // with sigma the channel-averaged extinction (any positive density keeps the
        // estimator unbiased; this one follows the average transmittance).
        let sigma = distance_sampling_sigma(m);
        let can_distance_sample = sigma > 0.0 || t_end.is_finite();
        let u_distance = sampler.next_1d();
        if can_distance_sample {
            let t = sample_truncated_exponential(u_distance, sigma, t_end);
            let pdf = truncated_exponential_pdf(t, sigma, t_end);
            if pdf > 0.0 && pdf.is_finite() {
                let p = ray.at(t);
                let mp = m.at(p);
                if !mp.sigma_s.is_black() {
                    let tr = segment_transmittance(m, ray, 0.0, t, self.transmittance, sampler);
                    let mut li = Rgb::ZERO;
                    for light in &scene.lights {
                        let weight = match light.point_position() {
                            Some(c) if mis => match equiangular_geometry(ray, c) {
                                Some((t_c, h)) => {
                                    balance_heuristic(pdf, equiangular_pdf(t, 0.0, t_end, t_c, h))
                                }
                                None => 1.0,
                            },
                            // Equiangular alone covers point-like lights, except on
                            // the light's own line where it degenerates.
                            Some(c) if equiangular_geometry(ray, c).is_some() => 0.0,
                            Some(_) => 1.0,
                            None => 1.0,
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
            let Some(c) = light.point_position() else {
                continue;
            };
            let u = sampler.next_1d();
            let Some((t_c, h)) = equiangular_geometry(ray, c) else {
                continue;
            };
            let t = sample_equiangular(u, 0.0, t_end, t_c, h);
            let pdf = equiangular_pdf(t, 0.0, t_end, t_c, h);
            if !(pdf > 0.0 && pdf.is_finite()) {
                continue;
            }
            let weight = if mis && can_distance_sample {
                balance_heuristic(pdf, truncated_exponential_pdf(t, sigma, t_end))
            } else {
                1.0
            };
            let p = ray.at(t);
            let mp = m.at(p);
            if mp.sigma_s.is_black() {
                continue;
            }
            let tr = segment_transmittance(m, ray, 0.0, t, self.transmittance, sampler);
            let li = light_in_scattered_radiance(
                scene,
                light,
                p,
                wo,
                m.phase(),
                Some(id),
                self.transmittance,
                sampler,
            );
            seg.radiance += tr * mp.sigma_s * li * (weight / pdf);
        }
        seg
    }
}

/// Extinction used for distance sampling in `m`: the channel average.
fn distance_sampling_sigma(m: &Medium) -> f32 {
    match m.as_homogeneous() {
        Some(h) => h.sigma_t().average(),
        None => m.max_sigma_t(),
    }
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
