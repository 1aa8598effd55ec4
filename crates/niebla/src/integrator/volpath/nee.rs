//! Next-event estimation at `volpath`'s scattering vertices (pbrt-v4's
//! `SampleLd`): which lights are sampled ([`LightChoice`]), one direction
//! toward each, and the shadow ray's transmittance by ratio tracking with the
//! null-scattering MIS weights, across index-matched boundaries.

use std::ops::ControlFlow;

use crate::bsdf::Bsdf;
use crate::color::Rgb;
use crate::light::Light;
use crate::math::{Ray, Vec3};
use crate::medium::MediumId;
use crate::phase::PhaseFunction;
use crate::sampling::PixelSampler;
use crate::tracking::{pass_through_weight, sample_t_maj_without_emission};
use crate::world::{surface_epsilon, walk_shadow_ray, Scene, ShadowSegment};

use super::channels::Channels;
use super::equiangular_nee::{light_weight_against_equiangular, point_light_count, Segment};
use super::guiding::Guiding;
use super::layout::{self, Block};

/// The scattering function at a vertex, for next-event estimation.
#[derive(Clone, Copy)]
pub(super) enum Scatter<'a> {
    Phase(&'a PhaseFunction),
    /// Surface with its outward shading normal (the BSDF's `n`), and its
    /// shading and geometric normals turned to face `wo`. Directions on
    /// `wo`'s side of both facing normals are reflections; for a BSDF with a
    /// rough transmission lobe ([`Bsdf::has_rough_transmission`]) directions
    /// below both are transmissions (radiance mode: `f` carries `1 / etap^2`),
    /// so light sampling reaches lights on either side. Directions between
    /// the two normals (where shading and geometry disagree) get nothing,
    /// unless the last field is true: a mesh that keeps its shading normal
    /// (Mitsuba 3's rule, the same directions its BSDF sampling follows,
    /// [`crate::world::Scene::path_continues`]), where only the side of the
    /// shading normal counts.
    Surface(&'a Bsdf, Vec3, Vec3, Vec3, bool),
}

impl Scatter<'_> {
    /// `f * |cos|` (surfaces) or `p` (media), and the sampling pdf of `wi`.
    #[inline]
    pub(super) fn eval(&self, wo: Vec3, wi: Vec3) -> (Rgb, f32) {
        match *self {
            Scatter::Phase(phase) => {
                // Phase functions are sampled exactly: the pdf is the value.
                let p = phase.eval(wo, wi);
                debug_assert_eq!(p.to_bits(), phase.pdf(wo, wi).to_bits());
                (Rgb::splat(p), p)
            }
            Scatter::Surface(bsdf, ns, n, ng, keeps_ns) => {
                let (cos, cos_g) = (wi.dot(n), wi.dot(ng));
                let reflected = cos > 0.0 && (cos_g > 0.0 || keeps_ns);
                let transmitted = cos < 0.0 && (cos_g < 0.0 || keeps_ns) && bsdf.has_rough_transmission();
                if !reflected && !transmitted {
                    return (Rgb::ZERO, 0.0);
                }
                (bsdf.eval(ns, wo, wi) * cos.abs(), bsdf.pdf(ns, wo, wi))
            }
        }
    }
}

/// How next-event estimation picks lights: every light, each with one
/// sample, when there are few (no variance from the choice, which dominated
/// scenes with a bright spot light and a dim sky); else one chosen uniformly.
/// Only lights [`sampled_by_nee`] take part.
#[derive(Clone, Copy, Debug)]
pub(super) struct LightChoice {
    /// Number of lights next-event estimation samples.
    pub(super) n: usize,
    /// Number of point and spot lights (equiangular sampling's lights).
    pub(super) points: usize,
    /// Bit `i` set: light `i` (of the first 64) is a point or spot light
    /// inside a medium (a lamp in fog).
    pub(super) in_media: u64,
}

/// Up to this many lights, next-event estimation samples each of them.
pub(super) const SAMPLE_ALL_LIGHTS_UP_TO: usize = 4;

impl LightChoice {
    pub(super) fn new(scene: &Scene) -> LightChoice {
        let mut in_media = 0u64;
        for (i, light) in scene.lights.iter().enumerate().take(64) {
            if light.point_position().is_some_and(|p| scene.medium_at(p).is_some()) {
                in_media |= 1 << i;
            }
        }
        LightChoice {
            n: scene.lights.iter().filter(|l| sampled_by_nee(l)).count(),
            points: point_light_count(scene),
            in_media,
        }
    }

    /// Whether every light is sampled at each vertex.
    #[inline]
    pub(super) fn all(self) -> bool {
        self.n <= SAMPLE_ALL_LIGHTS_UP_TO
    }

    /// Probability that next-event estimation samples a given light.
    #[inline]
    pub(super) fn pmf(self) -> f32 {
        if self.all() {
            1.0
        } else {
            1.0 / self.n as f32
        }
    }

    /// Probability that next-event estimation samples `light` (0 for lights
    /// it leaves to phase/BSDF sampling).
    #[inline]
    pub(super) fn pmf_of(self, light: &Light) -> f32 {
        if sampled_by_nee(light) {
            self.pmf()
        } else {
            0.0
        }
    }

    /// Probability that equiangular sampling on a segment targets a given point light.
    #[inline]
    pub(super) fn point_pmf(self) -> f32 {
        if self.all() {
            1.0
        } else {
            1.0 / self.points as f32
        }
    }
}

/// Whether next-event estimation samples `light`. A uniform environment
/// (`constant`) is not: its radiance is the same in every direction, so
/// phase or BSDF sampling already draws directions in proportion to the
/// integrand wherever the sky is visible, and light sampling (uniform or
/// cosine-weighted directions, blind to visibility as well) could only match
/// it worse while paying a shadow ray. pbrt-v4 skips it the same way
/// (`allowIncompletePDF`); ARCHITECTURE.md gives the measured gain.
pub(super) fn sampled_by_nee(light: &Light) -> bool {
    !matches!(light, Light::Constant(_))
}

/// A scattering vertex at which next-event estimation samples the lights.
#[derive(Clone, Copy)]
pub(super) struct NeeVertex<'a> {
    /// Position (world).
    pub(super) p: Vec3,
    /// Unit direction back along the path.
    pub(super) wo: Vec3,
    /// Phase function or surface there.
    pub(super) scatter: Scatter<'a>,
    /// Medium the vertex lies in (the side of `wo` for surfaces).
    pub(super) medium: Option<MediumId>,
    /// Medium on the other side of a surface, where shadow rays of
    /// transmitted directions start (equal to `medium` for media vertices
    /// and for surfaces that bound no medium).
    pub(super) medium_behind: Option<MediumId>,
    /// Path throughput over the hero channel's pdf, up to the vertex.
    pub(super) beta: Rgb,
    /// Unidirectional path pdfs per channel over the hero's, up to the vertex.
    pub(super) r_p: Rgb,
    /// The medium segment of a free-flight vertex (for the MIS against
    /// equiangular sampling); `None` at surfaces.
    pub(super) segment: Option<Segment<'a>>,
    /// Guiding, when the vertex's own direction sampling mixes it in.
    pub(super) guiding: Option<Guiding<'a>>,
    /// The vertex's block of the Sobol dimension layout.
    pub(super) block: Block,
    /// The vertex lies in the forced-collision medium (`forced`): inside
    /// the scene's lone convex, homogeneous boundary, so a shadow ray
    /// crosses that medium to the boundary and then vacuum, and nothing
    /// else can block it.
    pub(super) lone: bool,
}

/// Next-event estimation (pbrt-v4's `SampleLd`): every light or one chosen
/// uniformly ([`LightChoice`]), one direction toward each, ratio tracking
/// along the shadow ray through every medium and index-matched boundary,
/// weighted against phase/BSDF sampling.
pub(super) fn sample_ld(
    scene: &Scene,
    vertex: &NeeVertex,
    group: Channels,
    hero: usize,
    lights: LightChoice,
    sampler: &mut PixelSampler,
) -> Rgb {
    let n_lights = lights.n;
    if n_lights == 0 {
        return Rgb::ZERO;
    }
    let mut sampled = scene.lights.iter().enumerate().filter(|(_, light)| sampled_by_nee(light)).map(|(i, _)| i);
    if lights.all() {
        let mut l = Rgb::ZERO;
        for index in sampled {
            l += sample_ld_light(scene, vertex, group, hero, lights, index, sampler);
        }
        return l;
    }
    vertex.block.enter(sampler, layout::LIGHT_CHOICE);
    let u_light = sampler.next_1d();
    let k = ((u_light * n_lights as f32) as usize).min(n_lights - 1);
    let Some(index) = sampled.nth(k) else {
        return Rgb::ZERO;
    };
    sample_ld_light(scene, vertex, group, hero, lights, index, sampler)
}

/// [`sample_ld`] for light `light_index`, chosen with probability `lights.pmf()`.
fn sample_ld_light(
    scene: &Scene,
    vertex: &NeeVertex,
    group: Channels,
    hero: usize,
    lights: LightChoice,
    light_index: usize,
    sampler: &mut PixelSampler,
) -> Rgb {
    let NeeVertex { p, wo, scatter, medium, medium_behind, beta, r_p, segment, guiding, block, lone } = *vertex;
    // Every light of `lights.all()` takes the same slot: each light's
    // estimate is unbiased alone, and they are added.
    block.enter(sampler, layout::LIGHT_POINT);
    let u_dir = sampler.next_2d();
    let light: &Light = &scene.lights[light_index];
    let pmf = lights.pmf();
    let normal = match scatter {
        Scatter::Surface(_, _, _, ng, _) => Some(ng),
        Scatter::Phase(_) => None,
    };
    let Some(ls) = light.sample_li(p, normal, u_dir, sampler.time()) else {
        return Rgb::ZERO;
    };
    if ls.li.is_black() || !(ls.pdf > 0.0) {
        return Rgb::ZERO;
    }
    let (f_hat, scatter_pdf) = scatter.eval(wo, ls.wi);
    if f_hat.is_black() {
        return Rgb::ZERO;
    }
    // The shadow ray leaves from the side of `wi`, in the medium there.
    let (origin, medium) = match normal {
        Some(n) if ls.wi.dot(n) < 0.0 => (p - n * surface_epsilon(p), medium_behind),
        Some(n) => (p + n * surface_epsilon(p), medium),
        None => (p, medium),
    };
    let exit = if lone {
        lone_exit_transmittance(scene, origin, medium, ls.wi, ls.distance, group, hero, sampler)
    } else {
        None
    };
    let shadow = exit.unwrap_or_else(|| {
        shadow_transmittance(
            scene,
            origin,
            medium,
            ls.wi,
            ls.distance,
            scene.light_object(light_index),
            group,
            hero,
            sampler,
        )
    });
    let Some((t_ray, mut r_l, mut r_u, _)) = shadow else {
        return Rgb::ZERO;
    };
    let light_pdf = pmf * ls.pdf;
    r_l *= r_p * light_pdf;
    if ls.is_delta {
        // A point or spot light seen from a free-flight vertex: the same path can
        // come from equiangular sampling on the segment (`equiangular_ld`).
        let weight = segment
            .map_or(1.0, |seg| light_weight_against_equiangular(seg, light_index, light, lights, group).unwrap_or(1.0));
        beta * f_hat * t_ray * ls.li * weight / group.average(r_l)
    } else {
        // The density with which this vertex's own direction sampling draws
        // `wi` (only a light that is not a delta can be reached that way).
        let scatter_pdf = guiding.map_or(scatter_pdf, |g| g.mix(p, ls.wi, scatter_pdf));
        r_u *= r_p * scatter_pdf;
        beta * f_hat * t_ray * ls.li / group.average(r_l + r_u)
    }
}

/// A shadow ray's `(T_ray, r_l, r_u, medium)` (see [`shadow_transmittance`]).
pub(super) type ShadowTransmittance = (Rgb, Rgb, Rgb, Option<MediumId>);

/// [`shadow_transmittance`] from a point inside the scene's lone convex
/// boundary (see [`NeeVertex::lone`]): the transmittance to the boundary,
/// found by one distance query (exact in a homogeneous medium, by ratio
/// tracking otherwise), then vacuum. The same numbers as the general walk,
/// without its occlusion query and hit records; `None` (use the walk) when
/// the boundary is not found before `distance`.
#[allow(clippy::too_many_arguments)]
#[inline]
fn lone_exit_transmittance(
    scene: &Scene,
    p: Vec3,
    medium: Option<MediumId>,
    wi: Vec3,
    distance: f32,
    group: Channels,
    hero: usize,
    sampler: &mut PixelSampler,
) -> Option<Option<ShadowTransmittance>> {
    let m = scene.medium(medium?);
    if let Some(homogeneous) = m.as_homogeneous() {
        let t = scene.hit_distance(&Ray::new(p, wi), 0.0, distance)?;
        let tr = homogeneous_transmittance(homogeneous.sigma_t(), t);
        return Some(Some((tr, Rgb::ONE, tr, None)));
    }
    let ray = Ray::at_time(p, wi, sampler.time());
    let t_end = scene.hit_distance(&ray, 0.0, distance)?;
    let mut w = ShadowWeights::default();
    let piece = ShadowSegment { medium, ray: &ray, t_end, pane: None };
    let reached = w.visit(scene, &piece, group, hero, sampler).is_continue();
    Some(reached.then_some((w.t_ray, w.r_l, w.r_u, None)))
}

/// `exp(-sigma_t t)` per channel (0 where the product is NaN), one
/// exponential when the channels are equal.
#[inline]
fn homogeneous_transmittance(sigma_t: Rgb, t: f32) -> Rgb {
    let tau = (sigma_t * t).map(|x| if x.is_nan() { 0.0 } else { x });
    if tau[0] == tau[1] && tau[1] == tau[2] {
        Rgb::splat((-tau[0]).exp())
    } else {
        tau.exp_neg()
    }
}

/// Ratio tracking along a shadow ray with the null-scattering MIS weights of
/// pbrt-v4: returns `(T_ray, r_l, r_u, medium)` or `None` when the ray is
/// blocked by an opaque surface or its estimate was terminated; `medium` is
/// the medium of the last segment walked (the one at the ray's end, unless
/// the end lies within a surface offset past a boundary).
#[allow(clippy::too_many_arguments)]
pub(super) fn shadow_transmittance(
    scene: &Scene,
    p: Vec3,
    medium: Option<MediumId>,
    wi: Vec3,
    distance: f32,
    ignore: Option<u32>,
    group: Channels,
    hero: usize,
    sampler: &mut PixelSampler,
) -> Option<ShadowTransmittance> {
    let mut w = ShadowWeights::default();
    let mut last = medium;
    let reached = walk_shadow_ray(scene, p, sampler.time(), medium, wi, distance, ignore, |s| {
        last = s.medium;
        w.visit(scene, &s, group, hero, sampler)
    });
    reached.then_some((w.t_ray, w.r_l, w.r_u, last))
}

/// A shadow ray's transmittance estimate and path-pdf ratios so far.
struct ShadowWeights {
    /// The transmittance estimate, per channel.
    t_ray: Rgb,
    /// Light-sampling path pdf ratios (ratio tracking's majorant factors).
    r_l: Rgb,
    /// Unidirectional path pdf ratios (free flight passing).
    r_u: Rgb,
}

impl Default for ShadowWeights {
    fn default() -> ShadowWeights {
        ShadowWeights { t_ray: Rgb::ONE, r_l: Rgb::ONE, r_u: Rgb::ONE }
    }
}

impl ShadowWeights {
    /// Ratio tracking (or exact transmittance) over one piece of the shadow
    /// ray, with the pane it ends at; `Break` once the estimate is 0.
    #[inline]
    fn visit(
        &mut self,
        scene: &Scene,
        s: &ShadowSegment,
        group: Channels,
        hero: usize,
        sampler: &mut PixelSampler,
    ) -> ControlFlow<()> {
        let ShadowWeights { t_ray, r_l, r_u } = self;
        if let Some(id) = s.medium {
            let m = scene.medium(id);
            if let Some(homogeneous) = m.as_homogeneous() {
                // Exact transmittance: the light-sampling path pdf is unchanged,
                // the unidirectional one (free flight passing) gains T per channel.
                let tr = homogeneous_transmittance(homogeneous.sigma_t(), s.t_end);
                *t_ray *= tr;
                *r_u *= tr;
            } else {
                // Ratio tracking reads no emission: skip its lookups.
                let t_maj = sample_t_maj_without_emission(m, s.ray, s.t_end, hero, sampler, |c, sampler| {
                    let w = c.ratio_tracking_weights(hero);
                    *t_ray *= w.throughput;
                    *r_l *= w.majorant;
                    *r_u *= w.throughput;
                    // Russian roulette on the MIS-normalized transmittance (pbrt-v4).
                    let tr = *t_ray * group.indicator() / group.average(*r_l + *r_u);
                    if tr.max_channel() < 0.05 {
                        if sampler.next_1d() < 0.75 {
                            *t_ray = Rgb::ZERO;
                        } else {
                            *t_ray /= 0.25;
                        }
                    }
                    !t_ray.is_black()
                });
                match pass_through_weight(t_maj, hero) {
                    Some(w) => {
                        *t_ray *= w;
                        *r_l *= w;
                        *r_u *= w;
                    }
                    // The hero channel cannot pass but others can: the hero-based pdfs are 0.
                    None if !t_maj.is_black() => return ControlFlow::Break(()),
                    None => {}
                }
            }
        }
        // A thin pane: a weight for light sampling; a path sampling the pane
        // passes it with probability `1 - R'`, which its pdf gains.
        if let Some(pane) = s.pane {
            *t_ray *= pane.weight;
            *r_u *= pane.pass_probability;
        }
        if t_ray.is_black() || !t_ray.is_finite() {
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::{Microfacet, MicrofacetKind, RoughDielectric};
    use crate::scene::{build_scene, parse_scene_str};

    /// Inside a lone box of procedural cloud, the one-query shadow ray gives
    /// the same bits as the general walk (same numbers drawn, same ratio
    /// tracking), blocked or not, toward a sun and toward point lights
    /// inside (the walk is used) and outside the box; and the sampler ends
    /// in the same state.
    #[test]
    fn lone_shadow_rays_equal_the_walk_in_a_grid() {
        let json = r#"{"version": 1,
            "camera": {"type": "perspective", "position": [0.5, 0.5, 4], "target": [0.5, 0.5, 0.5], "fov_y": 40,
                       "width": 4, "height": 4},
            "media": {"cloud": {"type": "grid", "sigma_t": 12, "albedo": 0.9,
                      "density": {"type": "procedural", "shape": "cloud", "resolution": 24, "seed": 3}}},
            "shapes": [{"type": "box", "min": [0, 0, 0], "max": [1, 1, 1], "interior": "cloud", "bsdf": {"type": "null"}}],
            "lights": [{"type": "directional", "direction": [-0.3, -1, -0.2], "irradiance": 2}]}"#;
        let desc = parse_scene_str(json, "lone.json").unwrap();
        let scene = build_scene(&desc, "lone.json", ".".as_ref()).unwrap().scene;
        let id = super::super::forced::lone_boundary_medium(&scene);
        assert!(id.is_some());
        let (mut lone_used, mut reached) = (0, 0);
        for i in 0..400u64 {
            let mut s = PixelSampler::from_key(1000 + i);
            let p = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d()) * 0.98 + Vec3::splat(0.01);
            let wi = crate::sampling::sample_uniform_sphere(s.next_2d());
            // A sun (unbounded), a light outside the box, or one inside it.
            let distance = [f32::INFINITY, 3.0, 0.05][(i % 3) as usize];
            let mut a = s.clone();
            let mut b = s.clone();
            let lone = lone_exit_transmittance(&scene, p, id, wi, distance, Channels::ALL, 1, &mut a);
            let walk = shadow_transmittance(&scene, p, id, wi, distance, None, Channels::ALL, 1, &mut b);
            let Some(lone) = lone else {
                continue;
            };
            lone_used += 1;
            reached += lone.is_some() as u32;
            let bits = |r: Option<ShadowTransmittance>| {
                r.map(|(t, l, u, _)| [t, l, u].map(|c| [c[0], c[1], c[2]].map(f32::to_bits)))
            };
            assert_eq!(bits(lone), bits(walk), "ray {i}");
            assert_eq!(a.next_1d().to_bits(), b.next_1d().to_bits(), "sampler state after ray {i}");
        }
        // Both kinds of outcome were exercised (the in-box light falls back).
        assert!(lone_used >= 250 && reached >= 20 && reached < lone_used, "{lone_used} {reached}");
    }

    /// Light sampling at a rough dielectric reaches both sides (the
    /// transmitted pair with `f |cos|` and the BSDF's own pdf), at a diffuse
    /// surface only `wo`'s side; directions where the shading and geometric
    /// normals disagree get nothing, except on a mesh that keeps its
    /// shading normal.
    #[test]
    fn surface_scatter_covers_the_transmission_side_of_rough_dielectrics_only() {
        let glass = Bsdf::RoughDielectric(RoughDielectric {
            microfacet: Microfacet::new(MicrofacetKind::Ggx, 0.3, 0.3),
            eta: 1.5,
            specular_reflectance: Rgb::ONE,
            specular_transmittance: Rgb::ONE,
            tangent: Vec3::ZERO,
        });
        let diffuse = Bsdf::Diffuse { reflectance: Rgb::splat(0.5) };
        let n = Vec3::Z;
        let wo = Vec3::new(0.3, 0.0, 1.0).normalize();
        let wi = Vec3::new(-0.2, 0.1, -1.0).normalize();
        let (f, pdf) = Scatter::Surface(&glass, n, n, n, false).eval(wo, wi);
        let expected = glass.eval(n, wo, wi) * wi.z.abs();
        assert!(f[0] > 0.0 && (f[0] - expected[0]).abs() <= 1e-6 * expected[0], "{f:?} vs {expected:?}");
        assert!(pdf > 0.0 && (pdf - glass.pdf(n, wo, wi)).abs() <= 1e-6 * pdf);
        // From inside (wo below the outward normal): the facing normal is -n.
        let (f_in, _) = Scatter::Surface(&glass, n, -n, -n, false).eval(-wo, -wi);
        assert!(f_in[0] > 0.0);
        assert_eq!(Scatter::Surface(&diffuse, n, n, n, false).eval(wo, wi), (Rgb::ZERO, 0.0));
        // Shading normal says "through", geometry says "same side": refused.
        let tilted = Vec3::new(0.0, 0.9, 0.2).normalize();
        let wi_between = Vec3::new(0.0, -1.0, 0.05).normalize();
        assert!(wi_between.dot(tilted) < 0.0 && wi_between.dot(n) > 0.0);
        assert_eq!(Scatter::Surface(&glass, tilted, tilted, n, false).eval(wo, wi_between), (Rgb::ZERO, 0.0));
        // A mesh that keeps its shading normal (Mitsuba 3's rule): such a
        // direction is a transmission about `tilted`, with the BSDF's values
        // (seen from `wo_near`, close to `tilted`, whose refraction lies near it).
        let wo_near = Vec3::new(0.0, 0.9, 0.3).normalize();
        assert_eq!(Scatter::Surface(&glass, tilted, tilted, n, false).eval(wo_near, wi_between), (Rgb::ZERO, 0.0));
        let (f_keep, pdf_keep) = Scatter::Surface(&glass, tilted, tilted, n, true).eval(wo_near, wi_between);
        let expected = glass.eval(tilted, wo_near, wi_between) * wi_between.dot(tilted).abs();
        assert!(f_keep[0] > 0.0 && (f_keep[0] - expected[0]).abs() <= 1e-6 * expected[0], "{f_keep:?}");
        assert!(pdf_keep > 0.0 && (pdf_keep - glass.pdf(tilted, wo_near, wi_between)).abs() <= 1e-6 * pdf_keep);
        // A diffuse surface still reflects nothing below its shading normal.
        assert_eq!(Scatter::Surface(&diffuse, tilted, tilted, n, true).eval(wo_near, wi_between), (Rgb::ZERO, 0.0));
    }
}
