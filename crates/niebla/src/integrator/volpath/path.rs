//! `volpath`'s path loop: free flight with real, null and absorption
//! events, medium emission, surfaces, index-matched boundaries, escape to
//! the environment and Russian roulette.

use crate::aov::{FirstVertex, PathClass, RadianceSum};
use crate::bsdf::{reflect, Bsdf, BsdfSample};
use crate::color::Rgb;
use crate::math::Ray;
use crate::math::Vec3;
use crate::medium::MediumId;
use crate::sampling::PixelSampler;
use crate::tracking::{pass_through_weight, sample_t_maj, MajorantCollision};
use crate::world::{PathRay, Scene};

use super::channels::Channels;
use super::distance_mixture::{mixture_scatter_weights, DistanceMixture};
use super::equiangular_nee::{equiangular_ld, EquiangularSegment, Segment, SegmentTargets};
use super::forced::ForcedCollision;
use super::guiding::{sample_bsdf, sample_phase};
use super::layout::{self, Block, SegmentCounter};
use super::nee::{sample_ld, NeeVertex, Scatter};
use super::volume_nee::sample_volume_ld;
use super::{LightSampling, VolPathIntegrator};

/// How the previous vertex scattered: what light sampling there would have done.
#[derive(Clone, Copy, Debug)]
struct PreviousVertex {
    p: Vec3,
    /// Surface normal (facing the outgoing direction) for surface vertices.
    normal: Option<Vec3>,
    /// Whether the vertex sampled the emissive media as lights (so emission
    /// found by free flight after it is MIS-weighted against that).
    sampled_volume_lights: bool,
}

impl VolPathIntegrator {
    /// One path for the channels of `group` (the other channels of the
    /// result are 0), with the hero channel and spectral MIS over that group.
    pub(super) fn trace<S: RadianceSum>(
        &self,
        scene: &Scene,
        ray: Ray,
        medium: Option<MediumId>,
        group: Channels,
        light_sampling: LightSampling,
        sampler: &mut PixelSampler,
    ) -> S {
        let LightSampling {
            lights,
            guiding,
            emitter_guiding,
            medium_emitter_guiding,
            volume,
            forced: forced_medium,
            lone: lone_medium,
        } = light_sampling;
        // Medium vertices: lamp guiding where it applies, else guiding
        // toward the emissive media (when they are sampled as lights).
        let medium_guiding = guiding.or(medium_emitter_guiding);
        // The hero channel cycles over the pixel's samples (stratified), so the
        // discrete choice adds no variance over each group of samples.
        let hero = group.nth(sampler.stratified_choice(group.len() as u64) as usize);
        // Contributions, split by path class when `S` keeps the split.
        let mut l = S::default();
        let mut first = FirstVertex::None;
        let mut beta = group.indicator();
        let mut r_u = Rgb::ONE;
        let mut r_l = Rgb::ONE;
        let mut depth = 0u32;
        let mut specular_bounce = false;
        // Product of etap^2 over refractions: radiance scaling that Russian
        // roulette must not mistake for lost energy (pbrt-v4's etaScale).
        let mut eta_scale = 1.0f32;
        let mut previous = PreviousVertex { p: ray.o, normal: None, sampled_volume_lights: false };
        let mut path = PathRay::new(ray, medium, 0.0);
        // Which block of the Sobol dimension layout each segment uses; only
        // segments that draw numbers (in a medium, or ending on a pane)
        // count as uses of their bounce's block.
        let mut segments = SegmentCounter::default();

        loop {
            let (ray, medium) = (path.ray, path.medium);
            let mut block = None;
            // Inside the scene's lone boundary the path mostly scatters
            // before it: its distance is enough, the hit record is found only
            // if the path passes after all.
            let lone = medium.is_some() && medium == lone_medium;
            // The forced-collision medium (it is the lone boundary's).
            let forcing = medium.is_some() && medium == forced_medium;
            let mut hit = None;
            let t_end = if lone {
                scene.hit_distance(&ray, path.t_min, f32::INFINITY).unwrap_or(f32::INFINITY)
            } else {
                hit = path.intersect(scene);
                hit.map_or(f32::INFINITY, |h| h.surface.t)
            };

            // Free flight through the medium up to the surface.
            if let Some(id) = medium {
                let m = scene.medium(id);
                let block = *block.insert(segments.next(depth));
                // Equiangular sampling toward point and spot lights along this
                // segment, MIS-weighted against the free-flight vertices' NEE
                // (which reuse its intervals).
                let mut targets = SegmentTargets::default();
                // The next vertex's distance by free flight or equiangular
                // sampling toward lamps in media (one-sample MIS) on
                // homogeneous segments, every point light's interval found
                // first (the mixture's density needs them all).
                let mut mixture = None;
                if depth < self.max_depth {
                    if let Some(h) = m.as_homogeneous() {
                        if !forcing && lights.in_media != 0 && lights.all() && self.distance_mixture > 0.0 {
                            targets.find_all(scene, &ray, t_end);
                            mixture = DistanceMixture::new(self.distance_mixture, h, t_end, &targets, lights.in_media);
                        }
                    }
                    let throughput = beta / group.average(r_u);
                    let segment = EquiangularSegment { ray: &ray, t_end, medium: m, id, throughput, block, mixture };
                    let v = equiangular_ld(scene, &segment, group, lights, &mut targets, sampler);
                    let at = if depth == 0 { FirstVertex::Medium } else { first };
                    l.add(v, || PathClass::of(at, depth + 1));
                }
                let mut scattered: Option<(Vec3, Vec3)> = None;
                let mut terminated = false;
                let wo = -ray.d;
                block.enter(sampler, layout::FREE_FLIGHT);
                // Where leaving the medium gathers nothing, the collision is
                // forced within the segment (its first number, as free
                // flight's distance) and the weights take the probability.
                let forced = match m.as_homogeneous() {
                    Some(h) if forcing => ForcedCollision::sample(h, &ray, t_end, hero, group, sampler.next_1d()),
                    _ => None,
                };
                if let Some(f) = &forced {
                    let (beta_factor, r_u_factor) = f.weights(hero);
                    beta *= beta_factor;
                    r_u *= r_u_factor;
                }
                let forced_here = forced.is_some();
                // `pdfs`: the per-channel path pdfs of a mixture vertex.
                let mut collide = |c: MajorantCollision, pdfs: Option<Rgb>, sampler: &mut PixelSampler| {
                    // Medium emission, a collision estimator at every tentative collision.
                    if depth < self.max_depth && !c.point.l_ve.is_black() {
                        let pdf = c.sigma_maj[hero] * c.t_maj[hero];
                        let beta_e = beta * c.t_maj / pdf;
                        let r_e = r_u * c.sigma_maj * c.t_maj / pdf;
                        // The same point drawn by light sampling at the previous
                        // vertex: density p_V |x - y|^2, reached by ratio tracking
                        // (its majorant factors are in `r_l`, the last segment's
                        // is `t_maj`; homogeneous media are crossed exactly).
                        let r_le = match volume {
                            Some(v) if previous.sampled_volume_lights => {
                                let p_v = v.pdf(id, c.p);
                                let last = if m.as_homogeneous().is_some() { Rgb::ONE } else { c.t_maj };
                                r_l * last * (p_v * (c.p - previous.p).length_squared() / pdf)
                            }
                            _ => Rgb::ZERO,
                        };
                        let denominator = group.average(r_e + r_le);
                        if denominator > 0.0 {
                            l.add(beta_e * c.point.l_ve / denominator, || PathClass::of(first, depth));
                        }
                    }
                    // A forced collision in a homogeneous medium (majorant
                    // sigma_t) is real for sure: no number for the event.
                    if forced_here || c.is_real(hero, sampler.next_1d()) {
                        // Real collision, scattering weighted by the albedo.
                        if depth >= self.max_depth {
                            terminated = true;
                            return false;
                        }
                        depth += 1;
                        if depth == 1 {
                            first = FirstVertex::Medium;
                        }
                        let weights = match pdfs {
                            Some(pdfs) => mixture_scatter_weights(&c, pdfs, hero),
                            None => c.real_scatter_weights(hero).map(|w| (w.throughput, w.majorant)),
                        };
                        let Some((w_throughput, w_majorant)) = weights else {
                            terminated = true;
                            return false;
                        };
                        beta *= w_throughput;
                        r_u *= w_majorant;
                        if beta.is_black() || !(group.average(r_u) > 0.0) {
                            terminated = true;
                            return false;
                        }
                        let phase = m.phase();
                        let segment = Segment {
                            ray: &ray,
                            t_end,
                            t: c.t,
                            medium: m,
                            targets: &targets,
                            mixture: mixture.as_ref(),
                        };
                        let vertex = NeeVertex {
                            p: c.p,
                            wo,
                            scatter: Scatter::Phase(phase),
                            medium: Some(id),
                            medium_behind: Some(id),
                            beta,
                            r_p: r_u,
                            segment: Some(segment),
                            guiding: medium_guiding,
                            block: Block::vertex(depth),
                            lone,
                        };
                        let v = sample_ld(scene, &vertex, group, hero, lights, sampler);
                        l.add(v, || PathClass::of(first, depth));
                        let volume_here = volume.filter(|_| depth < self.max_depth);
                        if let Some(volume_lights) = volume_here {
                            let v = sample_volume_ld(scene, volume_lights, &vertex, group, hero, sampler);
                            l.add(v, || PathClass::of(first, depth));
                        }
                        let Some(ps) = sample_phase(phase, c.p, wo, medium_guiding, vertex.block, sampler) else {
                            terminated = true;
                            return false;
                        };
                        beta *= ps.value / ps.pdf;
                        r_l = r_u / ps.pdf;
                        // Russian roulette on the MIS-normalized throughput,
                        // after this vertex's light sample.
                        let rr_beta = beta * eta_scale / group.average(r_u);
                        vertex.block.enter(sampler, layout::ROULETTE);
                        let u = sampler.next_1d();
                        if let Some(q) = roulette_survival(rr_beta.max_channel(), depth) {
                            if u >= q {
                                terminated = true;
                                return false;
                            }
                            beta /= q;
                        }
                        previous =
                            PreviousVertex { p: c.p, normal: None, sampled_volume_lights: volume_here.is_some() };
                        specular_bounce = false;
                        scattered = Some((c.p, ps.wi));
                        return false;
                    }
                    // Null collision: continue with the null-scattering weights.
                    let Some(w) = c.null_weights(hero) else {
                        beta = Rgb::ZERO;
                        return false;
                    };
                    beta *= w.throughput;
                    r_u *= w.throughput;
                    r_l *= w.majorant;
                    !beta.is_black() && group.average(r_u) > 0.0
                };
                let t_maj = match forced {
                    // A forced collision is real: the callback scattered or
                    // ended the path (it never asks to go on).
                    Some(f) => {
                        if collide(f.collision, None, sampler) {
                            terminated = true;
                        }
                        Rgb::ONE
                    }
                    None => match &mixture {
                        Some(mixture) => mixture.flight(&ray, t_end, hero, &targets, sampler, |c, pdfs, sampler| {
                            collide(c, Some(pdfs), sampler)
                        }),
                        None => sample_t_maj(m, &ray, t_end, hero, sampler, |c, sampler| collide(c, None, sampler)),
                    },
                };
                if terminated || beta.is_black() || !(group.average(r_u) > 0.0) || !beta.is_finite() {
                    return l;
                }
                if let Some((p, wi)) = scattered {
                    path.scatter_in_medium(p, wi);
                    continue;
                }
                // Passed through: the hero channel's majorant transmittance was the
                // free-flight probability of reaching the surface.
                let Some(w) = pass_through_weight(t_maj, hero) else {
                    return l;
                };
                beta *= w;
                r_u *= w;
                let h = t_maj[hero];
                // Light sampling crosses homogeneous segments with exact
                // transmittance (no sampling pdf), so there its path pdf gains
                // no transmittance factor; elsewhere ratio tracking's does.
                if m.as_homogeneous().is_some() {
                    r_l /= h;
                } else {
                    r_l *= w;
                }
            }

            if lone {
                hit = path.intersect(scene);
            }
            // Escaped: environment lights, MIS against light sampling.
            let Some(hit) = hit else {
                for light in scene.lights.iter().filter(|l| l.is_infinite()) {
                    let le = light.le_escaped(ray.d);
                    if le.is_black() {
                        continue;
                    }
                    if depth == 0 && scene.transparent_background {
                        // Held out: the background is left to the compositor (alpha).
                        continue;
                    }
                    if depth == 0 || specular_bounce {
                        l.add(beta * le / group.average(r_u), || PathClass::of(first, depth));
                    } else {
                        let pmf = lights.pmf_of(light);
                        let r_l_env = r_l * (pmf * light.pdf_li(previous.p, previous.normal, ray.d, ray.time));
                        l.add(beta * le / group.average(r_u + r_l_env), || PathClass::of(first, depth));
                    }
                }
                return l;
            };

            // Index-matched boundary: cross it without counting a bounce.
            let object = scene.object(&hit);
            if object.bsdf.is_null() {
                if !path.cross(scene, &hit) {
                    return l;
                }
                continue;
            }

            // An area light: emitted radiance, MIS-weighted against light
            // sampling from the previous vertex; its black surface ends the path.
            if let Some((le, index)) = scene.emitted_radiance(&hit, -ray.d) {
                if !le.is_black() {
                    if depth == 0 || specular_bounce {
                        l.add(beta * le / group.average(r_u), || PathClass::of(first, depth));
                    } else {
                        let light = &scene.lights[index as usize];
                        let pmf = lights.pmf_of(light);
                        let r_l_hit = r_l * (pmf * light.pdf_li(previous.p, previous.normal, ray.d, ray.time));
                        l.add(beta * le / group.average(r_u + r_l_hit), || PathClass::of(first, depth));
                    }
                }
                return l;
            }

            // A thin dielectric pane: reflect with probability R' (a specular
            // bounce, below) or pass straight through like an index-matched
            // boundary (Mitsuba 3's null transmission lobe: no bounce, the
            // previous vertex and specular flag kept). Light sampling reaches
            // through the pane with it as a weight, so relative to this path's
            // pdf, which chose to pass with probability 1 - R', the
            // light-sampling pdf drops by that factor (a null collision's update).
            let mut pane_reflection = None;
            if let Bsdf::ThinDielectric(pane) = object.bsdf {
                let wo = -ray.d;
                let ns = hit.surface.shading_normal(wo);
                let cos = ns.dot(wo);
                let pass = pane.pass_probability(cos);
                block.unwrap_or_else(|| segments.next(depth)).enter(sampler, layout::PANE);
                if sampler.next_1d() < pass {
                    beta *= pane.specular_transmittance;
                    r_l /= pass;
                    if !path.cross(scene, &hit) {
                        return l;
                    }
                    continue;
                }
                let r = 1.0 - pass;
                if cos == 0.0 || !(r > 0.0) {
                    return l;
                }
                let f = pane.specular_reflectance * (r / cos.abs());
                let wi = reflect(wo, ns);
                pane_reflection =
                    Some(BsdfSample { wi, f, pdf: r, is_specular: true, is_transmission: false, eta: 1.0 });
            }

            // Opaque surface: next-event estimation, then BSDF sampling.
            if depth >= self.max_depth {
                return l;
            }
            depth += 1;
            if depth == 1 {
                first = FirstVertex::Surface;
            }
            let wo = -ray.d;
            // The BSDF is evaluated about the shading normal `ns` (outward),
            // light sampling faces `wo`'s side (`n`, and the geometric `ng`).
            let ns = hit.surface.shading_normal(wo);
            let (n, mut ng) = if ns.dot(wo) < 0.0 { (-ns, -hit.surface.n) } else { (ns, hit.surface.n) };
            // A mesh that keeps its shading normal (Mitsuba 3's rule) may
            // have `wo` behind `ns` but in front of the triangle: shadow rays
            // leave on their own geometric side, in the medium there.
            let keeps_ns = scene.object(&hit).shape.keeps_shading_normal();
            if keeps_ns && ng.dot(wo) < 0.0 {
                ng = -ng;
            }
            let p = hit.surface.p;
            // Guiding toward lights inside a medium, for non-specular surfaces
            // whose side of `wo` lies in a medium.
            let bsdf = scene.surface_bsdf(&hit);
            // Else guiding toward emissive media, when they are sampled as lights.
            let surface_guiding = guiding
                .filter(|_| medium.is_some())
                .or(emitter_guiding)
                .filter(|_| !bsdf.is_specular() && !bsdf.has_rough_transmission());
            if !bsdf.is_specular() {
                let vertex = NeeVertex {
                    p,
                    wo,
                    scatter: Scatter::Surface(&bsdf, ns, n, ng, keeps_ns),
                    medium,
                    medium_behind: scene.medium_after_crossing(&hit, -wo, medium),
                    beta,
                    r_p: r_u,
                    segment: None,
                    guiding: surface_guiding,
                    block: Block::vertex(depth),
                    lone: false,
                };
                let v = sample_ld(scene, &vertex, group, hero, lights, sampler);
                l.add(v, || PathClass::of(first, depth));
                if let Some(volume_lights) = volume.filter(|_| depth < self.max_depth) {
                    let v = sample_volume_ld(scene, volume_lights, &vertex, group, hero, sampler);
                    l.add(v, || PathClass::of(first, depth));
                }
            }
            let vertex_block = Block::vertex(depth);
            let Some(bs) =
                pane_reflection.or_else(|| sample_bsdf(&bsdf, ns, p, wo, surface_guiding, vertex_block, sampler))
            else {
                return l;
            };
            if !(bs.pdf > 0.0) || !scene.path_continues(&hit, ns, bs.wi) {
                return l;
            }
            beta *= bs.weight(ns);
            r_l = r_u / bs.pdf;
            // Light sampling covers both sides of a non-specular surface
            // (rough transmission included), so only delta lobes skip MIS.
            specular_bounce = bs.is_specular;
            if bs.is_transmission {
                eta_scale *= bs.eta * bs.eta;
            }
            let side = if hit.surface.n.dot(bs.wi) < 0.0 { -hit.surface.n } else { hit.surface.n };
            previous = PreviousVertex {
                p,
                normal: Some(side),
                sampled_volume_lights: volume.is_some() && depth < self.max_depth && !bs.is_specular,
            };
            path.leave_surface(scene, &hit, bs.wi, bs.is_transmission);

            // Russian roulette on the MIS-normalized throughput.
            let rr_beta = beta * eta_scale / group.average(r_u);
            vertex_block.enter(sampler, layout::ROULETTE);
            let u = sampler.next_1d();
            if let Some(q) = roulette_survival(rr_beta.max_channel(), depth) {
                if u >= q {
                    return l;
                }
                beta /= q;
            }
        }
    }
}

/// Vertices up to this depth are never rouletted.
const ROULETTE_FREE_DEPTH: u32 = 3;

/// Survival probability `m^(1/4)` of Russian roulette after the scattering vertex at
/// `depth` (medium or surface), from the largest channel `m` of the
/// MIS-normalized throughput; `None` when the path goes on for sure.
///
/// The policy was measured (relative MSE times CPU time on the bench
/// scenes, bench/README.md): survival `m` from depth 2 (pbrt-v4's rule,
/// which in a gray medium kills paths exactly as often as analog absorption
/// does) against gentler ones. `m^(1/4)` with the first three vertices
/// exempt was 1.1-1.8x more efficient on every scene: killing a path with
/// throughput `m` saves the cost of its remaining vertices but loses their
/// next-event estimates, which in scattering media carry most of the light.
/// Survival 1 (no roulette) was as good on most scenes but unbounded in
/// cost for deep paths of low throughput.
#[inline]
fn roulette_survival(m: f32, depth: u32) -> Option<f32> {
    if depth <= ROULETTE_FREE_DEPTH || !(m < 1.0) {
        return None;
    }
    Some(m.max(0.0).sqrt().sqrt())
}
