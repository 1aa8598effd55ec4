//! Next-event estimation toward emission inside media (the volume light
//! strategy) and its multiple importance sampling against the collision
//! estimator of free flight, in the null-scattering path integral (Miller,
//! Georgiev, Jarosz 2019).
//!
//! From a scattering vertex `x` a point `y` is drawn from [`VolumeLights`]
//! with density `p_V(y)` per unit volume; its density in free flight's
//! measure (direction times distance) is `p_V(y) |x - y|^2`. The shadow ray
//! from `x` to `y` is ratio-tracked; light arrives only if the ray ends in
//! the medium `y` was drawn for. With emission `L_ve` (radiance per unit
//! length) the contribution is `f T(x, y) L_ve(y) / (p_V |x - y|^2)`.
//!
//! Free flight from `x` reaches the same `y` as a tentative collision: the
//! direction with the vertex's own sampling density, the null collisions
//! between with `T_maj sigma_n`, and `y` with `T_maj sigma_maj(y)`. The
//! balance heuristic over both strategies and all channels (pbrt-v4's
//! `r_u`, `r_l` ratios) weights each contribution so that every path counts
//! emission once: the collision estimator's side lives in `path`.

use crate::color::Rgb;
use crate::integrator::{majorant_at, VolumeLights};
use crate::sampling::PixelSampler;
use crate::world::{surface_epsilon, Scene};

use super::channels::Channels;
use super::layout;
use super::nee::{shadow_transmittance, NeeVertex, Scatter};

/// Light sampling of emissive media from `vertex`: one point from
/// `volume_lights`, shadow transmittance by ratio tracking, weighted against
/// free flight's collision estimator of the same emission.
pub(super) fn sample_volume_ld(
    scene: &Scene,
    volume_lights: &VolumeLights,
    vertex: &NeeVertex,
    group: Channels,
    hero: usize,
    sampler: &mut PixelSampler,
) -> Rgb {
    let NeeVertex { p, wo, scatter, medium, medium_behind, beta, r_p, guiding, block, .. } = *vertex;
    block.enter(sampler, layout::VOLUME_LIGHT);
    let u = sampler.next_1d();
    let v = sampler.next_2d();
    let w = sampler.next_1d();
    let Some(s) = volume_lights.sample(u, [v.x, v.y, w]) else {
        return Rgb::ZERO;
    };
    let d = s.p - p;
    let dist2 = d.length_squared();
    if !(dist2 > 0.0) || !(s.pdf > 0.0) {
        return Rgb::ZERO;
    }
    let dist = dist2.sqrt();
    let wi = d / dist;
    let emitter = scene.medium(s.medium);
    let l_ve = emitter.at_time(s.p, sampler.time()).l_ve;
    if l_ve.is_black() {
        return Rgb::ZERO;
    }
    let (f_hat, scatter_pdf) = scatter.eval(wo, wi);
    if f_hat.is_black() {
        return Rgb::ZERO;
    }
    let normal = match scatter {
        Scatter::Surface(_, _, _, ng, _) => Some(ng),
        Scatter::Phase(_) => None,
    };
    let (origin, start) = match normal {
        Some(n) if wi.dot(n) < 0.0 => (p - n * surface_epsilon(p), medium_behind),
        Some(n) => (p + n * surface_epsilon(p), medium),
        None => (p, medium),
    };
    let Some((t_ray, mut r_l, mut r_u, end)) =
        shadow_transmittance(scene, origin, start, wi, (s.p - origin).length(), None, group, hero, sampler)
    else {
        return Rgb::ZERO;
    };
    if end != Some(s.medium) {
        return Rgb::ZERO;
    }
    r_l *= r_p * (s.pdf * dist2);
    let scatter_pdf = guiding.map_or(scatter_pdf, |g| g.mix(p, wi, scatter_pdf));
    r_u *= r_p * majorant_at(emitter, s.p) * scatter_pdf;
    let denominator = group.average(r_l + r_u);
    if !(denominator > 0.0) {
        return Rgb::ZERO;
    }
    beta * f_hat * t_ray * l_ve / denominator
}
