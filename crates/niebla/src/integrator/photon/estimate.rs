//! The photon integrator's camera walk and its density estimates.

use std::collections::BinaryHeap;

use super::kdtree::Neighbor;
use super::maps::PhotonMaps;
use super::VolumeQuery;
use crate::bsdf::Bsdf;
use crate::color::Rgb;
use crate::math::{Ray, Vec3, PI};
use crate::medium::{Medium, MediumId};
use crate::phase::PhaseFunction;
use crate::sampling::PixelSampler;
use crate::tracking::{segment_transmittance, MarchStep, TransmittanceMethod};
use crate::world::{Hit, Scene};

use super::super::emission_absorption::{march_segment, marched_range};
use super::super::{
    default_march_step, direct_surface_radiance, walk_camera_ray, CameraRayVisitor, Integrator, SegmentRadiance,
    SingleIntegrator,
};

/// Smallest cosine between a surface photon's normal and the query's.
const SAME_SURFACE_COS: f32 = 0.7;

/// The density-estimation kernel of one map, resolved to numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kernel {
    /// The `k` nearest photons within `max_radius`.
    Nearest {
        /// Neighbours.
        k: usize,
        /// Radius cap, scene units.
        max_radius: f32,
    },
    /// Every photon within this radius (scene units).
    Radius(f32),
}

/// Photon mapping along camera rays: single scattering and emission from
/// [`SingleIntegrator`], multiple scattering from the volume map, surfaces
/// from direct lighting plus the surface map. See the module docs.
#[derive(Clone, Debug)]
pub struct PhotonIntegrator<'a> {
    /// The maps (with beam radii when `query` is [`VolumeQuery::Beam`]).
    pub maps: &'a PhotonMaps,
    /// Kernel of the volume map's point queries.
    pub volume_kernel: Kernel,
    /// Kernel of the surface map.
    pub surface_kernel: Kernel,
    /// Point or beam queries.
    pub query: VolumeQuery,
    /// Ray-march step of point queries (`None`: [`default_march_step`]).
    pub step: Option<MarchStep>,
    /// Emission and single scattering along camera rays.
    pub single: SingleIntegrator,
}

impl Integrator for PhotonIntegrator<'_> {
    fn radiance(&self, scene: &Scene, ray: Ray, medium: Option<MediumId>, sampler: &mut PixelSampler) -> Rgb {
        let mut visitor = PhotonVisitor { integrator: self, heap: BinaryHeap::new() };
        walk_camera_ray(scene, ray, medium, sampler, &mut visitor)
    }
}

/// The photon integrator's part of the shared camera-ray walk.
struct PhotonVisitor<'a, 'b> {
    integrator: &'a PhotonIntegrator<'b>,
    /// Scratch of the k-nearest queries, reused along the ray.
    heap: BinaryHeap<Neighbor>,
}

impl CameraRayVisitor for PhotonVisitor<'_, '_> {
    /// Emission and single scattering by shadow rays, multiple scattering
    /// from the volume photon map.
    fn segment(
        &mut self,
        scene: &Scene,
        _m: &Medium,
        id: MediumId,
        ray: &Ray,
        t_end: f32,
        sampler: &mut PixelSampler,
    ) -> SegmentRadiance {
        let s = self.integrator.single.segment(scene, id, ray, t_end, sampler);
        let multiple = self.integrator.volume_segment(scene, id, ray, t_end, &mut self.heap, sampler);
        SegmentRadiance { radiance: s.radiance + multiple, transmittance: s.transmittance }
    }

    /// Diffuse surface: direct light by shadow rays, the rest from the
    /// surface photon map.
    fn opaque_surface(
        &mut self,
        scene: &Scene,
        hit: &Hit,
        wo: Vec3,
        medium: Option<MediumId>,
        sampler: &mut PixelSampler,
    ) -> Rgb {
        self.integrator.surface_radiance(scene, hit, wo, medium, sampler, &mut self.heap)
    }
}

impl PhotonIntegrator<'_> {
    /// Radiance leaving the opaque surface `hit` toward `wo`: direct light
    /// by shadow rays plus the surface map's estimate.
    pub(crate) fn surface_radiance(
        &self,
        scene: &Scene,
        hit: &Hit,
        wo: Vec3,
        medium: Option<MediumId>,
        sampler: &mut PixelSampler,
        heap: &mut BinaryHeap<Neighbor>,
    ) -> Rgb {
        let p = hit.surface.p;
        let ns = hit.surface.shading_normal(wo);
        let n = if ns.dot(wo) < 0.0 { -ns } else { ns };
        let method = self.single.transmittance;
        let bsdf = scene.surface_bsdf(hit);
        direct_surface_radiance(scene, &hit.surface, wo, &bsdf, medium, method, sampler)
            + self.surface_estimate(p, ns, n, wo, &bsdf, heap)
    }

    /// Multiple scattering over `[0, t_end)` of `ray` in medium `id`,
    /// attenuated to the ray's origin.
    fn volume_segment(
        &self,
        scene: &Scene,
        id: MediumId,
        ray: &Ray,
        t_end: f32,
        heap: &mut BinaryHeap<Neighbor>,
        sampler: &mut PixelSampler,
    ) -> Rgb {
        if self.maps.volume.is_empty() {
            return Rgb::ZERO;
        }
        let m = scene.medium(id);
        match self.query {
            VolumeQuery::Beam => self.beam_estimate(m, id, ray, t_end, sampler),
            VolumeQuery::March => {
                let diagonal = scene.diagonal();
                let Some((t_a, t_b)) = marched_range(m, ray, t_end, diagonal) else {
                    return Rgb::ZERO;
                };
                let step = self.step.unwrap_or_else(|| default_march_step(m.max_sigma_t(), diagonal));
                let wo = -ray.d;
                let method = TransmittanceMethod::Analytic;
                march_segment(m, ray, t_a, t_b, step, method, sampler, |mp, p, _| {
                    if mp.sigma_s.is_black() {
                        Rgb::ZERO
                    } else {
                        self.volume_estimate(p, wo, m.phase(), id, heap)
                    }
                })
                .radiance
            }
        }
    }

    /// In-scattered radiance `sigma_s integral p L dw` at `x` toward `wo`
    /// (per unit length) from the volume map: `sum p(wo, wi_k) Phi_k / (4/3 pi r^3)`
    /// over photons stored in the same medium.
    pub fn volume_estimate(
        &self,
        x: Vec3,
        wo: Vec3,
        phase: &PhaseFunction,
        id: MediumId,
        heap: &mut BinaryHeap<Neighbor>,
    ) -> Rgb {
        let tree = &self.maps.volume;
        let mut sum = Rgb::ZERO;
        let r2 = match self.volume_kernel {
            Kernel::Radius(r) => {
                tree.for_each_within(x, r * r, |photon, _| {
                    if photon.tag == id.0 {
                        sum += photon.power * phase.eval(wo, photon.wi);
                    }
                });
                r * r
            }
            Kernel::Nearest { k, max_radius } => {
                let r2 = tree.nearest(x, k, max_radius * max_radius, |p| p.tag == id.0, heap);
                for nb in heap.iter() {
                    let photon = &tree.photons()[nb.index as usize];
                    sum += photon.power * phase.eval(wo, photon.wi);
                }
                r2
            }
        };
        if !(r2 > 0.0) || sum.is_black() {
            return Rgb::ZERO;
        }
        sum / (4.0 / 3.0 * PI * r2 * r2.sqrt())
    }

    /// Reflected radiance at surface point `x` (outward shading normal `ns`,
    /// the BSDF's; `n` the normal facing `wo`) from the surface map:
    /// `sum f(wo, wi_k) Phi_k / (pi r^2)` over photons on the same side of a
    /// surface of about the same orientation.
    pub fn surface_estimate(
        &self,
        x: Vec3,
        ns: Vec3,
        n: Vec3,
        wo: Vec3,
        bsdf: &Bsdf,
        heap: &mut BinaryHeap<Neighbor>,
    ) -> Rgb {
        let tree = &self.maps.surface;
        if tree.is_empty() {
            return Rgb::ZERO;
        }
        let same_surface = |photon: &super::Photon| photon.normal().dot(n) > SAME_SURFACE_COS;
        let mut sum = Rgb::ZERO;
        let r2 = match self.surface_kernel {
            Kernel::Radius(r) => {
                tree.for_each_within(x, r * r, |photon, _| {
                    if same_surface(photon) {
                        sum += photon.power * bsdf.eval(ns, wo, photon.wi);
                    }
                });
                r * r
            }
            Kernel::Nearest { k, max_radius } => {
                let r2 = tree.nearest(x, k, max_radius * max_radius, same_surface, heap);
                for nb in heap.iter() {
                    let photon = &tree.photons()[nb.index as usize];
                    sum += photon.power * bsdf.eval(ns, wo, photon.wi);
                }
                r2
            }
        };
        if !(r2 > 0.0) || sum.is_black() {
            return Rgb::ZERO;
        }
        sum / (PI * r2)
    }

    /// Beam radiance estimate over `[0, t_end)` of `ray` in medium `id`
    /// (Jarosz, Zwicker, Jensen 2008): every photon of the medium whose
    /// sphere the ray crosses, with the 2D kernel `1 / (pi r_k^2)` and the
    /// transmittance to the photon's projection (exact in homogeneous media;
    /// a product of ratio-tracking estimates between consecutive projections
    /// in grids, unbiased).
    fn beam_estimate(&self, m: &Medium, id: MediumId, ray: &Ray, t_end: f32, sampler: &mut PixelSampler) -> Rgb {
        let wo = -ray.d;
        let phase = m.phase();
        if let Some(h) = m.as_homogeneous() {
            let sigma_t = h.sigma_t();
            let mut sum = Rgb::ZERO;
            self.maps.volume.for_each_crossed(ray, 0.0, t_end, |photon, t, _, r| {
                if photon.tag == id.0 {
                    let tr = (sigma_t * t).exp_neg();
                    sum += tr * photon.power * (phase.eval(wo, photon.wi) / (PI * r * r));
                }
            });
            return sum;
        }
        let mut found: Vec<(f32, Rgb)> = Vec::new();
        self.maps.volume.for_each_crossed(ray, 0.0, t_end, |photon, t, _, r| {
            if photon.tag == id.0 {
                found.push((t, photon.power * (phase.eval(wo, photon.wi) / (PI * r * r))));
            }
        });
        found.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut sum = Rgb::ZERO;
        let mut tr = Rgb::ONE;
        let mut t_prev = 0.0;
        for (t, contribution) in found {
            tr *= segment_transmittance(m, ray, t_prev, t, TransmittanceMethod::Analytic, sampler);
            if tr.is_black() {
                break;
            }
            sum += tr * contribution;
            t_prev = t;
        }
        sum
    }
}
