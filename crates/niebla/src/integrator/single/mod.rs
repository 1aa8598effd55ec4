//! Single scattering along the camera ray (pbrt 2nd edition
//! `SingleScatteringIntegrator`), with equiangular sampling toward point and
//! spot lights (Kulla and Fajardo 2012) and its MIS combination with distance
//! sampling. Surfaces are lit directly; media emission is included. With
//! `volume_lights`, emissive media also light the scattering points and
//! surfaces (one point drawn from [`VolumeLights`] per shading point).

pub(crate) mod settings;

use std::sync::Arc;

use crate::color::Rgb;
use crate::math::Ray;
use crate::medium::{Medium, MediumId};
use crate::sampling::{balance_heuristic, PixelSampler};
use crate::tracking::{majorant_profile, segment_transmittance, MarchStep, TransmittanceMethod};
use crate::world::Scene;

use super::camera_layout::{self, Slot};
use super::camera_ray::trace_camera_ray_with;
use super::direct::volume_light_in_scattered_radiance;
use super::emission_absorption::{emission_segment, march_segment, marched_range};
use super::equiangular::{equiangular_target, PointLightTarget};
use super::{default_march_step, light_in_scattered_radiance, Integrator, SegmentRadiance, VolumeLights};

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

/// Which slots of the camera-ray layout a point drawn in the emissive media
/// takes: the segment's, or those of a ray-march step.
#[derive(Clone, Copy, Debug)]
enum VolumeSlot {
    Block(Slot),
    Step(u32),
}

/// The single-scattering integrator.
#[derive(Clone, Debug)]
pub struct SingleIntegrator {
    /// Ray-march step for `March`; `None` picks [`default_march_step`] per medium.
    pub step: Option<MarchStep>,
    /// Choice of scattering points.
    pub sampling: SingleSampling,
    /// Transmittance estimator for camera and shadow rays.
    pub transmittance: TransmittanceMethod,
    /// Emissive media as lights (the `volume_lights` setting): the
    /// distribution of points drawn toward them, `None` when off or when the
    /// scene has no sampled emitter. Emission seen along camera rays counts
    /// either way.
    pub volume_lights: Option<Arc<VolumeLights>>,
}

impl Integrator for SingleIntegrator {
    fn radiance(&self, scene: &Scene, ray: Ray, medium: Option<MediumId>, sampler: &mut PixelSampler) -> Rgb {
        let diagonal = scene.diagonal();
        let lights = self.volume_lights.as_deref();
        trace_camera_ray_with::<true>(
            scene,
            ray,
            medium,
            self.transmittance,
            lights,
            sampler,
            |m, id, ray, t_end, sampler| self.segment_in(scene, m, id, ray, t_end, diagonal, sampler),
        )
    }
}

impl SingleIntegrator {
    /// The integrator for `scene`, with emissive media as lights when
    /// `volume_lights` is true (the distribution is built here, once).
    pub fn for_scene(
        scene: &Scene,
        step: Option<MarchStep>,
        sampling: SingleSampling,
        transmittance: TransmittanceMethod,
        volume_lights: bool,
    ) -> SingleIntegrator {
        let volume_lights = volume_lights.then(|| VolumeLights::new(scene)).filter(|l| !l.is_empty()).map(Arc::new);
        SingleIntegrator { step, sampling, transmittance, volume_lights }
    }

    /// In-scattered radiance at `p` from one point of the emissive media
    /// (zero without volume lights).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn volume_in_scattered(
        &self,
        scene: &Scene,
        m: &Medium,
        id: MediumId,
        p: crate::math::Vec3,
        wo: crate::math::Vec3,
        sampler: &mut PixelSampler,
        slot: VolumeSlot,
    ) -> Rgb {
        match &self.volume_lights {
            Some(lights) => {
                match slot {
                    VolumeSlot::Block(slot) => camera_layout::enter(sampler, slot),
                    VolumeSlot::Step(i) => {
                        camera_layout::enter_march_step(sampler, i, camera_layout::STEP_VOLUME_LIGHT)
                    }
                }
                volume_light_in_scattered_radiance(
                    scene,
                    lights,
                    p,
                    wo,
                    m.phase(),
                    Some(id),
                    self.transmittance,
                    sampler,
                )
            }
            None => Rgb::ZERO,
        }
    }

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
        camera_layout::enter(sampler, camera_layout::SCATTER_JITTER);
        // March step `i` takes its own light slots (a no-op outside a
        // laid-out walk); all lights of a step share them.
        let mut i = 0u32;
        let scattered = march_segment(m, ray, t_a, t_b, step, method, sampler, |mp, p, sampler| {
            let mut source = Rgb::ZERO;
            if !mp.sigma_s.is_black() {
                for index in 0..scene.lights.len() {
                    camera_layout::enter_march_step(sampler, i, camera_layout::STEP_LIGHT_POINT);
                    source += light_in_scattered_radiance(scene, index, p, wo, m.phase(), Some(id), method, sampler);
                }
                source += self.volume_in_scattered(scene, m, id, p, wo, sampler, VolumeSlot::Step(i));
                source *= mp.sigma_s;
            }
            i += 1;
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
        camera_layout::enter(sampler, camera_layout::DISTANCE);
        let u_distance = sampler.next_1d();
        if let Some(t) = profile.sample(u_distance) {
            let pdf = profile.pdf(t);
            if pdf > 0.0 && pdf.is_finite() {
                let p = ray.at(t);
                let mp = m.at_time(p, sampler.time());
                if !mp.sigma_s.is_black() {
                    let tr = segment_transmittance(m, ray, 0.0, t, self.transmittance, sampler);
                    let mut li = Rgb::ZERO;
                    for (index, light) in scene.lights.iter().enumerate() {
                        let weight = match equiangular_target(light, ray, t_end) {
                            PointLightTarget::Interval(e) if mis => balance_heuristic(pdf, e.pdf(t)),
                            // Equiangular sampling alone covers its interval.
                            PointLightTarget::Interval(e) if e.contains(t) => 0.0,
                            PointLightTarget::Missed => 0.0,
                            _ => 1.0,
                        };
                        if weight > 0.0 {
                            camera_layout::enter(sampler, camera_layout::LIGHT_POINT);
                            li += light_in_scattered_radiance(
                                scene,
                                index,
                                p,
                                wo,
                                m.phase(),
                                Some(id),
                                self.transmittance,
                                sampler,
                            ) * weight;
                        }
                    }
                    // Emissive media have no equiangular strategy: weight 1.
                    li += self.volume_in_scattered(
                        scene,
                        m,
                        id,
                        p,
                        wo,
                        sampler,
                        VolumeSlot::Block(camera_layout::VOLUME_LIGHT),
                    );
                    seg.radiance += tr * mp.sigma_s * li / pdf;
                }
            }
        }

        // Equiangular samples toward each point-like light.
        for (index, light) in scene.lights.iter().enumerate() {
            if light.point_position().is_none() {
                continue;
            }
            camera_layout::enter(sampler, camera_layout::EQUIANGULAR);
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
            let mp = m.at_time(p, sampler.time());
            if mp.sigma_s.is_black() {
                continue;
            }
            let tr = segment_transmittance(m, ray, 0.0, t, self.transmittance, sampler);
            camera_layout::enter(sampler, camera_layout::EQUIANGULAR_LIGHT_POINT);
            let li = light_in_scattered_radiance(scene, index, p, wo, m.phase(), Some(id), self.transmittance, sampler);
            seg.radiance += tr * mp.sigma_s * li * (weight / pdf);
        }
        seg
    }
}

#[cfg(test)]
#[path = "tests.rs"]
mod tests;
