//! Direct lighting shared by the integrators: light arriving at a surface
//! point or a medium point straight from the lights, with shadow
//! transmittance through the media in between.

use crate::color::Rgb;
use crate::geometry::SurfaceHit;
use crate::math::Vec3;
use crate::medium::MediumId;
use crate::phase::PhaseFunction;
use crate::sampling::PixelSampler;
use crate::tracking::TransmittanceMethod;
use crate::world::{offset_origin, Scene};

/// Radiance scattered toward `wo` at the surface point of `surface`, from
/// one sample of every light, with shadow rays that start in `medium` (the
/// medium on the side of `wo`). The BSDF is evaluated about the shading
/// normal ([`SurfaceHit::shading_normal`]); light from below the geometric
/// surface on the side of `wo` is refused (no leaks through smooth meshes).
pub fn direct_surface_radiance(
    scene: &Scene,
    surface: &SurfaceHit,
    wo: Vec3,
    bsdf: &crate::bsdf::Bsdf,
    medium: Option<MediumId>,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
) -> Rgb {
    let p = surface.p;
    let ns = surface.shading_normal(wo);
    let (n, ng) = if ns.dot(wo) < 0.0 { (-ns, -surface.n) } else { (ns, surface.n) };
    let mut l = Rgb::ZERO;
    for (index, light) in scene.lights.iter().enumerate() {
        let u = sampler.next_2d();
        let Some(ls) = light.sample_li(p, Some(ng), u) else {
            continue;
        };
        let cos = ls.wi.dot(n);
        if cos <= 0.0 || ls.wi.dot(ng) <= 0.0 || ls.pdf == 0.0 {
            continue;
        }
        let f = bsdf.eval(ns, wo, ls.wi);
        if f.is_black() || ls.li.is_black() {
            continue;
        }
        let origin = offset_origin(p, ng);
        let tr = scene.transmittance_ignoring(
            origin,
            medium,
            ls.wi,
            ls.distance,
            scene.light_object(index),
            method,
            sampler,
        );
        l += f * ls.li * tr * (cos / ls.pdf);
    }
    l
}

/// In-scattered radiance `integral p(wo, wi) L_d(wi) dwi` at medium point `p`
/// (without the sigma_s factor), from one sample of every light, with shadow
/// rays through `medium` and the media beyond. Units: radiance (W/(sr m^2)).
pub fn in_scattered_radiance(
    scene: &Scene,
    p: Vec3,
    wo: Vec3,
    phase: &PhaseFunction,
    medium: Option<MediumId>,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
) -> Rgb {
    let mut l = Rgb::ZERO;
    for index in 0..scene.lights.len() {
        l += light_in_scattered_radiance(scene, index, p, wo, phase, medium, method, sampler);
    }
    l
}

/// One light's share of [`in_scattered_radiance`]: `p(wo, wi) T(p, light) L_i / pdf`
/// for one sampled direction `wi` toward light `light_index` of the scene.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn light_in_scattered_radiance(
    scene: &Scene,
    light_index: usize,
    p: Vec3,
    wo: Vec3,
    phase: &PhaseFunction,
    medium: Option<MediumId>,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
) -> Rgb {
    let light = &scene.lights[light_index];
    let u = sampler.next_2d();
    let Some(ls) = light.sample_li(p, None, u) else {
        return Rgb::ZERO;
    };
    if ls.pdf == 0.0 || ls.li.is_black() {
        return Rgb::ZERO;
    }
    let f = phase.eval(wo, ls.wi);
    if f == 0.0 {
        return Rgb::ZERO;
    }
    let ignore = scene.light_object(light_index);
    let tr = scene.transmittance_ignoring(p, medium, ls.wi, ls.distance, ignore, method, sampler);
    ls.li * tr * (f / ls.pdf)
}

#[cfg(test)]
#[path = "direct_tests.rs"]
mod tests;
