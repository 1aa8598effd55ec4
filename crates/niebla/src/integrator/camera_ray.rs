//! The walk along a camera ray shared by the emission and single-scattering
//! integrators: medium segments between surfaces, index-matched boundaries
//! crossed, opaque surfaces lit directly, escaping rays see the environment.

use crate::color::Rgb;
use crate::math::Ray;
use crate::medium::{Medium, MediumId};
use crate::sampling::PixelSampler;
use crate::scene::{surface_epsilon, Scene, MAX_BOUNDARY_CROSSINGS};
use crate::tracking::TransmittanceMethod;

use super::direct_surface_radiance;

/// Largest number of specular reflections and refractions a camera ray follows.
pub const MAX_SPECULAR_BOUNCES: u32 = 16;

/// What a medium segment adds: radiance leaving the segment toward the camera
/// (emission and in-scattering, attenuated to the segment's start) and the
/// transmittance across the whole segment.
#[derive(Clone, Copy, Debug)]
pub struct SegmentRadiance {
    /// Radiance added at the segment's start, W/(sr m^2).
    pub radiance: Rgb,
    /// Transmittance from the segment's start to its end.
    pub transmittance: Rgb,
}

/// Walk `ray` from the camera through the scene. `segment(medium, id, ray,
/// t_end, sampler)` integrates one medium segment `[0, t_end)` of `ray`
/// (`t_end` infinite when the ray escapes).
pub(crate) fn trace_camera_ray(
    scene: &Scene,
    mut ray: Ray,
    mut medium: Option<MediumId>,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
    mut segment: impl FnMut(&Medium, MediumId, &Ray, f32, &mut PixelSampler) -> SegmentRadiance,
) -> Rgb {
    let mut l = Rgb::ZERO;
    let mut beta = Rgb::ONE;
    let mut t_min = 0.0;
    let mut specular_bounces = 0u32;
    for _ in 0..MAX_BOUNDARY_CROSSINGS {
        let hit = scene.intersect(&ray, t_min, f32::INFINITY);
        let t_end = hit.map_or(f32::INFINITY, |h| h.surface.t);

        // Medium segment up to the next surface (or to infinity).
        if let Some(id) = medium {
            let s = segment(scene.medium(id), id, &ray, t_end, sampler);
            l += beta * s.radiance;
            beta *= s.transmittance;
        }
        if beta.is_black() {
            break;
        }

        // Escaped: the environment.
        let Some(hit) = hit else {
            l += beta * scene.escaped_radiance(ray.d);
            break;
        };

        // Index-matched boundary: change medium and go on.
        let object = scene.object(&hit);
        if object.bsdf.is_null() {
            // Continue from the hit point itself so no path length is lost.
            medium = scene.medium_after_crossing(&hit, ray.d, medium);
            ray = Ray::new(hit.surface.p, ray.d);
            t_min = surface_epsilon(hit.surface.p);
            continue;
        }

        // An area light: its emitted radiance (its surface reflects nothing).
        if let Some((le, _)) = scene.emitted_radiance(&hit, -ray.d) {
            l += beta * le;
            break;
        }

        // Specular surface (glass, metal): follow the sampled reflection or
        // refraction, as a Whitted-style ray tracer would.
        if object.bsdf.is_specular() {
            specular_bounces += 1;
            if specular_bounces > MAX_SPECULAR_BOUNCES {
                break;
            }
            let u_lobe = sampler.next_1d();
            let Some(bs) = object.bsdf.sample(hit.surface.n, -ray.d, u_lobe, sampler.next_2d()) else {
                break;
            };
            beta *= bs.weight(hit.surface.n);
            if bs.is_transmission {
                medium = scene.medium_after_crossing(&hit, bs.wi, medium);
            }
            ray = Ray::new(hit.surface.p, bs.wi);
            t_min = surface_epsilon(hit.surface.p);
            continue;
        }

        // Opaque surface: direct lighting, then stop.
        l += beta
            * direct_surface_radiance(
                scene,
                hit.surface.p,
                hit.surface.n,
                -ray.d,
                &object.bsdf,
                medium,
                method,
                sampler,
            );
        break;
    }
    l
}
