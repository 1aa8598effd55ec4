//! Direct lighting shared by the integrators: light arriving at a surface
//! point or a medium point straight from the lights, with shadow
//! transmittance through the media in between.

use crate::color::Rgb;
use crate::geometry::SurfaceHit;
use crate::math::Vec3;
use crate::medium::MediumId;
use crate::phase::PhaseFunction;
use crate::sampling::PixelSampler;
use crate::tracking::{segment_transmittance, TransmittanceMethod};
use crate::world::{offset_origin, walk_shadow_ray, Scene};

use super::{camera_layout, VolumeLights};
use std::ops::ControlFlow;

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
    let frame = ShadingFrame::new(surface, wo);
    let ng = frame.ng;
    let mut l = Rgb::ZERO;
    for (index, light) in scene.lights.iter().enumerate() {
        // Every light takes the surface's light slot (a no-op outside a
        // laid-out camera-ray walk): their estimates are added.
        camera_layout::enter(sampler, camera_layout::SURFACE_LIGHT_POINT);
        let u = sampler.next_2d();
        let Some(ls) = light.sample_li(p, Some(ng), u, sampler.time()) else {
            continue;
        };
        if ls.pdf == 0.0 || ls.li.is_black() {
            continue;
        }
        let Some(f_cos) = frame.response(bsdf, wo, ls.wi) else {
            continue;
        };
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
        l += f_cos * ls.li * tr / ls.pdf;
    }
    l
}

/// [`direct_surface_radiance`] whose shadow rays take the transmittance of
/// a medium segment from `lookup` where it gives one: `lookup(light, id,
/// ray, t_end)` for light index `light` of the scene and the segment
/// `[0, t_end]` of `ray` (unit direction toward the sampled light point)
/// in medium `id`; `None` falls back to `method`. Surfaces block and
/// thin panes weigh the shadow ray as in [`Scene::transmittance_ignoring`].
/// The sampler's draws per light are those of [`direct_surface_radiance`]
/// plus `method`'s for the segments that fall back.
#[allow(clippy::too_many_arguments)]
pub(crate) fn direct_surface_radiance_with<F>(
    scene: &Scene,
    surface: &SurfaceHit,
    wo: Vec3,
    bsdf: &crate::bsdf::Bsdf,
    medium: Option<MediumId>,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
    mut lookup: F,
) -> Rgb
where
    F: FnMut(usize, MediumId, &crate::math::Ray, f32) -> Option<Rgb>,
{
    let p = surface.p;
    let frame = ShadingFrame::new(surface, wo);
    let ng = frame.ng;
    let mut l = Rgb::ZERO;
    for (index, light) in scene.lights.iter().enumerate() {
        camera_layout::enter(sampler, camera_layout::SURFACE_LIGHT_POINT);
        let u = sampler.next_2d();
        let Some(ls) = light.sample_li(p, Some(ng), u, sampler.time()) else {
            continue;
        };
        if ls.pdf == 0.0 || ls.li.is_black() {
            continue;
        }
        let Some(f_cos) = frame.response(bsdf, wo, ls.wi) else {
            continue;
        };
        let origin = offset_origin(p, ng);
        let mut tr = Rgb::ONE;
        let ignore = scene.light_object(index);
        let reached = walk_shadow_ray(scene, origin, sampler.time(), medium, ls.wi, ls.distance, ignore, |s| {
            if let Some(id) = s.medium {
                tr *= match lookup(index, id, s.ray, s.t_end) {
                    Some(t) => t,
                    None => segment_transmittance(scene.medium(id), s.ray, 0.0, s.t_end, method, sampler),
                };
            }
            if let Some(pane) = s.pane {
                tr *= pane.weight;
            }
            if tr.is_black() {
                return ControlFlow::Break(());
            }
            ControlFlow::Continue(())
        });
        if reached {
            l += f_cos * ls.li * tr / ls.pdf;
        }
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
    let Some(ls) = light.sample_li(p, None, u, sampler.time()) else {
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

/// A point drawn in the emissive media as seen from `p`: its direction `wi`,
/// distance, and `L_ve(y) / (p_V(y) |p - y|^2)`, the emission per unit
/// length over the point's density in solid angle times distance (before
/// shadow transmittance). `None` when nothing was drawn or nothing is emitted.
struct VolumeLightPoint {
    wi: Vec3,
    distance: f32,
    medium: MediumId,
    le_over_pdf: Rgb,
}

/// Draw a point of `lights` seen from `p` (three uniform numbers).
#[inline]
fn sample_volume_light(
    scene: &Scene,
    lights: &VolumeLights,
    p: Vec3,
    sampler: &mut PixelSampler,
) -> Option<VolumeLightPoint> {
    let u = sampler.next_1d();
    let v = sampler.next_2d();
    let w = sampler.next_1d();
    let s = lights.sample(u, [v.x, v.y, w])?;
    let d = s.p - p;
    let dist2 = d.length_squared();
    if !(dist2 > 0.0) || !(s.pdf > 0.0) {
        return None;
    }
    let l_ve = scene.medium(s.medium).at_time(s.p, sampler.time()).l_ve;
    if l_ve.is_black() {
        return None;
    }
    let distance = dist2.sqrt();
    Some(VolumeLightPoint { wi: d / distance, distance, medium: s.medium, le_over_pdf: l_ve / (s.pdf * dist2) })
}

/// Transmittance from `origin` (in `medium`) along `wi` over `distance`,
/// zero unless the ray ends inside medium `target` (a point drawn in an
/// emitter's bounding region may lie outside its shapes).
#[allow(clippy::too_many_arguments)]
fn transmittance_into_medium(
    scene: &Scene,
    origin: Vec3,
    medium: Option<MediumId>,
    wi: Vec3,
    distance: f32,
    target: MediumId,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
) -> Rgb {
    let mut tr = Rgb::ONE;
    let mut last = medium;
    let reached = walk_shadow_ray(scene, origin, sampler.time(), medium, wi, distance, None, |s| {
        last = s.medium;
        if let Some(id) = s.medium {
            tr *= segment_transmittance(scene.medium(id), s.ray, 0.0, s.t_end, method, sampler);
        }
        if let Some(pane) = s.pane {
            tr *= pane.weight;
        }
        if tr.is_black() {
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    });
    if reached && last == Some(target) {
        tr
    } else {
        Rgb::ZERO
    }
}

/// In-scattered radiance `integral p(wo, wi) L_d(wi) dwi` at medium point
/// `p` (without the sigma_s factor) from the emission inside media, one
/// point drawn from `lights` (next-event estimation toward emissive media):
/// `p(wo, wi) T(p, y) L_ve(y) / (p_V(y) |p - y|^2)`, with `L_ve` the
/// emitted radiance per unit length and `p_V` the point's density per unit
/// volume. Shadow rays start in `medium` and use `method`.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn volume_light_in_scattered_radiance(
    scene: &Scene,
    lights: &VolumeLights,
    p: Vec3,
    wo: Vec3,
    phase: &PhaseFunction,
    medium: Option<MediumId>,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
) -> Rgb {
    let Some(y) = sample_volume_light(scene, lights, p, sampler) else {
        return Rgb::ZERO;
    };
    let f = phase.eval(wo, y.wi);
    if f == 0.0 {
        return Rgb::ZERO;
    }
    let tr = transmittance_into_medium(scene, p, medium, y.wi, y.distance, y.medium, method, sampler);
    y.le_over_pdf * tr * f
}

/// Radiance scattered toward `wo` at the surface point of `surface` from the
/// emission inside media, one point drawn from `lights`:
/// `f(wo, wi) |cos| T L_ve / (p_V |p - y|^2)`, with the conventions of
/// [`direct_surface_radiance`] (shading normal, no light from below the
/// geometric surface on the side of `wo`, shadow rays from `medium`).
#[allow(clippy::too_many_arguments)]
pub fn volume_light_surface_radiance(
    scene: &Scene,
    lights: &VolumeLights,
    surface: &SurfaceHit,
    wo: Vec3,
    bsdf: &crate::bsdf::Bsdf,
    medium: Option<MediumId>,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
) -> Rgb {
    let p = surface.p;
    let Some(y) = sample_volume_light(scene, lights, p, sampler) else {
        return Rgb::ZERO;
    };
    let frame = ShadingFrame::new(surface, wo);
    let Some(f_cos) = frame.response(bsdf, wo, y.wi) else {
        return Rgb::ZERO;
    };
    let origin = offset_origin(p, frame.ng);
    let distance = (p + y.wi * y.distance - origin).length();
    let tr = transmittance_into_medium(scene, origin, medium, y.wi, distance, y.medium, method, sampler);
    f_cos * y.le_over_pdf * tr
}

/// The normals of a surface point as seen from `wo`: the shading normal
/// `ns` (as the BSDF takes it), and the shading and geometric normals `n`,
/// `ng` flipped to the side of `wo`.
struct ShadingFrame {
    ns: Vec3,
    n: Vec3,
    ng: Vec3,
}

impl ShadingFrame {
    #[inline]
    fn new(surface: &SurfaceHit, wo: Vec3) -> ShadingFrame {
        let ns = surface.shading_normal(wo);
        let (n, ng) = if ns.dot(wo) < 0.0 { (-ns, -surface.n) } else { (ns, surface.n) };
        ShadingFrame { ns, n, ng }
    }

    /// `f(wo, wi) |cos|` about the shading normal for light arriving from
    /// `wi`; `None` when `wi` lies below the shading or the geometric
    /// surface on the side of `wo` (no leaks through smooth meshes) or the
    /// BSDF gives nothing.
    #[inline]
    fn response(&self, bsdf: &crate::bsdf::Bsdf, wo: Vec3, wi: Vec3) -> Option<Rgb> {
        let cos = wi.dot(self.n);
        if cos <= 0.0 || wi.dot(self.ng) <= 0.0 {
            return None;
        }
        let f = bsdf.eval(self.ns, wo, wi);
        if f.is_black() {
            return None;
        }
        Some(f * cos)
    }
}

#[cfg(test)]
#[path = "direct_tests.rs"]
mod tests;
