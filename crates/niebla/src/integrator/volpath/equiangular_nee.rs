//! Equiangular next-event estimation on `volpath`'s medium segments (Kulla
//! and Fajardo 2012, "Importance sampling techniques for path tracing in
//! participating media"), and its balance-heuristic MIS against the
//! free-flight vertices' light sampling.

use crate::color::Rgb;
use crate::light::Light;
use crate::math::Ray;
use crate::medium::{Medium, MediumId};
use crate::sampling::PixelSampler;
use crate::tracking::{majorant_profile, segment_transmittance, TransmittanceMethod};
use crate::world::Scene;

use super::channels::{per_channel, Channels};
use super::distance_mixture::DistanceMixture;
use super::layout::{self, Block};
use super::nee::LightChoice;
use crate::integrator::equiangular::{equiangular_target, EquiangularInterval, PointLightTarget};

/// The medium segment on which a free-flight vertex was found.
#[derive(Clone, Copy)]
pub(super) struct Segment<'a> {
    /// The path's ray; the segment is `[0, t_end)` of it.
    pub(super) ray: &'a Ray,
    pub(super) t_end: f32,
    /// Ray parameter of the vertex.
    pub(super) t: f32,
    /// The medium of the segment.
    pub(super) medium: &'a Medium,
    /// The equiangular targets [`equiangular_ld`] found on the segment.
    pub(super) targets: &'a SegmentTargets,
    /// The distance mixture that placed the vertex, if any (else free flight).
    pub(super) mixture: Option<&'a DistanceMixture>,
}

/// Most equiangular targets a [`SegmentTargets`] keeps: one per light when
/// next-event estimation samples every light.
const MAX_SEGMENT_TARGETS: usize = super::nee::SAMPLE_ALL_LIGHTS_UP_TO;

/// The equiangular intervals [`equiangular_ld`] found on one medium
/// segment, by light (index into the scene's lights): the MIS weight of the
/// light sample at the segment's free-flight vertex needs the same ones,
/// and finding them again cost a cone intersection and two `atan`s per
/// light. Lights not kept are found again ([`equiangular_target`]).
#[derive(Clone, Copy, Default)]
pub(super) struct SegmentTargets {
    found: [Option<(usize, PointLightTarget)>; MAX_SEGMENT_TARGETS],
}

impl SegmentTargets {
    /// Keep `target` of light `light_index` (dropped when full).
    #[inline]
    fn keep(&mut self, light_index: usize, target: PointLightTarget) {
        if let Some(slot) = self.found.iter_mut().find(|slot| slot.is_none()) {
            *slot = Some((light_index, target));
        }
    }

    /// The target of light `light_index` on `[0, t_end)` of `ray`: the one
    /// kept for it, else found and kept.
    #[inline]
    pub(super) fn find(&mut self, light_index: usize, light: &Light, ray: &Ray, t_end: f32) -> PointLightTarget {
        if let Some(&(_, target)) = self.found.iter().flatten().find(|(i, _)| *i == light_index) {
            return target;
        }
        let target = equiangular_target(light, ray, t_end);
        self.keep(light_index, target);
        target
    }

    /// Find the targets of every point and spot light of `scene` on
    /// `[0, t_end)` of `ray` (as many as fit).
    pub(super) fn find_all(&mut self, scene: &Scene, ray: &Ray, t_end: f32) {
        for (index, light) in scene.lights.iter().enumerate().filter(|(_, l)| l.point_position().is_some()) {
            self.find(index, light, ray, t_end);
        }
    }

    /// The equiangular intervals kept, in the order found, of the lights
    /// whose bit is set in `lights` (bit `i`: light `i`, the first 64) and
    /// that pass within `max_h` of the ray's line.
    #[inline]
    pub(super) fn intervals(&self, lights: u64, max_h: f32) -> impl Iterator<Item = &EquiangularInterval> {
        self.found.iter().flatten().filter_map(move |(index, target)| match target {
            PointLightTarget::Interval(e) if *index < 64 && lights & (1 << index) != 0 && e.h() <= max_h => Some(e),
            _ => None,
        })
    }

    /// The target of light `light_index` on `[0, t_end)` of `ray`: the one
    /// kept for it, else found.
    #[inline]
    fn get(&self, light_index: usize, light: &Light, ray: &Ray, t_end: f32) -> PointLightTarget {
        match self.found.iter().flatten().find(|(i, _)| *i == light_index) {
            Some(&(_, target)) => target,
            None => equiangular_target(light, ray, t_end),
        }
    }
}

/// Density (per unit length) with which free flight on the segment produces a
/// real scattering at `t`, averaged over the channels: `avg_c sigma_s,c(t)
/// T_c(0, t)`, with the transmittance exact in homogeneous media and from the
/// majorants in grids (a deterministic stand-in; MIS weights only need to be
/// consistent). The average, not the hero channel's density, is what the
/// spectral MIS of the free-flight strategy amounts to once the hero is
/// averaged out, so the two strategies' weights sum to one per channel
/// (a hero-channel density biased chromatic media by about 0.5%).
pub(super) fn free_flight_scatter_density(m: &Medium, ray: &Ray, t_end: f32, t: f32, group: Channels) -> f32 {
    let sigma_s = m.at(ray.at(t)).sigma_s;
    let sigma_t = m.sigma_t_per_density();
    let depth_per_unit_sigma = match m.as_homogeneous() {
        Some(_) => t,
        // exp(-D(t)) with D the integral of the majorant density.
        None => -majorant_profile(m, ray, 0.0, t_end, 1.0).transmittance(t).ln(),
    };
    group.average(per_channel(|c| sigma_s[c] * (-sigma_t[c] * depth_per_unit_sigma).exp()))
}

/// Number of point and spot lights (the lights equiangular sampling chooses from).
pub(super) fn point_light_count(scene: &Scene) -> usize {
    scene.lights.iter().filter(|l| l.point_position().is_some()).count()
}

/// Balance-heuristic weight of light sampling from a free-flight vertex
/// (light `light_index` chosen with probability 1/N) against equiangular sampling of the
/// same vertex (point light chosen with probability 1/P); `None` when the
/// light is not point-like or equiangular sampling cannot produce the vertex.
pub(super) fn light_weight_against_equiangular(
    seg: Segment,
    light_index: usize,
    light: &Light,
    lights: LightChoice,
    group: Channels,
) -> Option<f32> {
    let PointLightTarget::Interval(e) = seg.targets.get(light_index, light, seg.ray, seg.t_end) else {
        return None;
    };
    let p_eq = e.pdf(seg.t) * lights.point_pmf();
    let p_d = match seg.mixture {
        Some(mixture) => mixture.scatter_density(seg.t, group, seg.targets),
        None => free_flight_scatter_density(seg.medium, seg.ray, seg.t_end, seg.t, group),
    } * lights.pmf();
    (p_d + p_eq > 0.0).then(|| p_d / (p_d + p_eq))
}

/// A medium segment on which [`equiangular_ld`] samples points.
pub(super) struct EquiangularSegment<'a> {
    /// The path's ray; the segment is `[0, t_end)` of it.
    pub(super) ray: &'a Ray,
    pub(super) t_end: f32,
    /// The medium the segment lies in, and its id.
    pub(super) medium: &'a Medium,
    pub(super) id: MediumId,
    /// MIS-normalized path throughput at the segment's start.
    pub(super) throughput: Rgb,
    /// The segment's block of the Sobol dimension layout.
    pub(super) block: Block,
    /// The distance mixture of the segment's free flight, if any.
    pub(super) mixture: Option<DistanceMixture>,
}

/// Equiangular next-event estimation on a medium segment (Kulla and Fajardo
/// 2012, combined by MIS with free-flight sampling as Cycles does): every
/// point or spot light, or one chosen uniformly ([`LightChoice`]), one point
/// sampled equiangularly toward each (within the spot's cone), camera-side
/// and light-side transmittance exact (homogeneous) or by ratio tracking.
/// The intervals found are kept in `targets`.
pub(super) fn equiangular_ld(
    scene: &Scene,
    segment: &EquiangularSegment,
    group: Channels,
    lights: LightChoice,
    targets: &mut SegmentTargets,
    sampler: &mut PixelSampler,
) -> Rgb {
    let count = lights.points;
    if count == 0 {
        return Rgb::ZERO;
    }
    let mut point_lights = scene.lights.iter().enumerate().filter(|(_, l)| l.point_position().is_some());
    if lights.all() {
        let mut l = Rgb::ZERO;
        for (index, light) in point_lights {
            l += equiangular_ld_light(scene, segment, group, lights, (index, light), targets, sampler);
        }
        return l;
    }
    segment.block.enter(sampler, layout::EQUIANGULAR_CHOICE);
    let u_light = sampler.next_1d();
    let k = ((u_light * count as f32) as usize).min(count - 1);
    let Some((index, light)) = point_lights.nth(k) else {
        return Rgb::ZERO;
    };
    equiangular_ld_light(scene, segment, group, lights, (index, light), targets, sampler)
}

/// [`equiangular_ld`] toward `light` (with its index in the scene's
/// lights), chosen with probability `lights.point_pmf()`.
fn equiangular_ld_light(
    scene: &Scene,
    segment: &EquiangularSegment,
    group: Channels,
    lights: LightChoice,
    (index, light): (usize, &Light),
    targets: &mut SegmentTargets,
    sampler: &mut PixelSampler,
) -> Rgb {
    let EquiangularSegment { ray, t_end, medium: m, id, throughput, block, mixture } = *segment;
    block.enter(sampler, layout::EQUIANGULAR);
    let (u_t, u_dir) = (sampler.next_1d(), sampler.next_2d());
    let target = targets.find(index, light, ray, t_end);
    let PointLightTarget::Interval(e) = target else {
        return Rgb::ZERO;
    };
    let t = e.sample(u_t);
    let pdf_eq = e.pdf(t);
    if !(pdf_eq > 0.0 && pdf_eq.is_finite()) {
        return Rgb::ZERO;
    }
    let p = ray.at(t);
    let sigma_s = m.at_time(p, sampler.time()).sigma_s;
    if sigma_s.is_black() {
        return Rgb::ZERO;
    }
    let Some(ls) = light.sample_li(p, None, u_dir, sampler.time()) else {
        return Rgb::ZERO;
    };
    let f = m.phase().eval(-ray.d, ls.wi);
    if f == 0.0 || ls.li.is_black() {
        return Rgb::ZERO;
    }
    let tr_camera = segment_transmittance(m, ray, 0.0, t, TransmittanceMethod::Analytic, sampler);
    if tr_camera.is_black() {
        return Rgb::ZERO;
    }
    let tr_light = scene.transmittance(p, Some(id), ls.wi, ls.distance, TransmittanceMethod::Analytic, sampler);
    let p_eq = pdf_eq * lights.point_pmf();
    let p_d = match &mixture {
        Some(mixture) => mixture.scatter_density(t, group, targets),
        None => free_flight_scatter_density(m, ray, t_end, t, group),
    } * lights.pmf();
    let weight = p_eq / (p_eq + p_d);
    throughput * tr_camera * sigma_s * tr_light * ls.li * (f * weight / p_eq)
}
