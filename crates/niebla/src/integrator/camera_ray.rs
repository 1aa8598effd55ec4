//! The walk along a camera ray shared by the integrators that shade camera
//! rays segment by segment (emission, single, analytic, hegeman, photon):
//! medium segments between surfaces, index-matched boundaries crossed, area
//! lights seen, specular surfaces followed, the first opaque surface shaded,
//! escaping rays see the environment.

use crate::color::Rgb;
use crate::math::{Ray, Vec3};
use crate::medium::{Medium, MediumId};
use crate::sampling::PixelSampler;
use crate::tracking::TransmittanceMethod;
use crate::world::{Hit, PathRay, Scene, MAX_BOUNDARY_CROSSINGS};

use super::camera_layout;
use super::direct::volume_light_surface_radiance;
use super::{direct_surface_radiance, VolumeLights};

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

/// What a camera-ray walk ([`walk_camera_ray`]) computes where an integrator
/// differs: the radiance of a medium segment and of an opaque (non-specular,
/// non-emitting) surface.
pub(crate) trait CameraRayVisitor {
    /// Whether the walk uses the camera-ray dimension layout
    /// (`super::camera_layout`): it then records its step in the sampler
    /// before each medium segment, and the decisions of the segment, the
    /// surface and the direct lighting take their slots. Walks without it
    /// draw in order, as before the layout existed.
    const LAID_OUT: bool = false;

    /// Integrate one medium segment `[0, t_end)` of `ray` (`t_end` infinite
    /// when the ray escapes).
    fn segment(
        &mut self,
        scene: &Scene,
        m: &Medium,
        id: MediumId,
        ray: &Ray,
        t_end: f32,
        sampler: &mut PixelSampler,
    ) -> SegmentRadiance;

    /// Radiance leaving opaque surface `hit` toward `wo`, whose side is in `medium`.
    fn opaque_surface(
        &mut self,
        scene: &Scene,
        hit: &Hit,
        wo: Vec3,
        medium: Option<MediumId>,
        sampler: &mut PixelSampler,
    ) -> Rgb;
}

/// Walk `ray` from the camera through the scene: medium segments (by
/// `visitor.segment`), index-matched boundaries crossed, area lights seen,
/// specular surfaces followed (up to [`MAX_SPECULAR_BOUNCES`]), the first
/// opaque surface shaded by `visitor.opaque_surface`, escaping rays see the
/// environment.
pub(crate) fn walk_camera_ray<V: CameraRayVisitor>(
    scene: &Scene,
    ray: Ray,
    medium: Option<MediumId>,
    sampler: &mut PixelSampler,
    visitor: &mut V,
) -> Rgb {
    let mut l = Rgb::ZERO;
    let mut beta = Rgb::ONE;
    let mut path = PathRay::new(ray, medium, 0.0);
    let mut specular_bounces = 0u32;
    for step in 0..MAX_BOUNDARY_CROSSINGS {
        if V::LAID_OUT {
            sampler.set_layout_block(Some(step));
        }
        let hit = path.intersect(scene);
        let t_end = hit.map_or(f32::INFINITY, |h| h.surface.t);

        // Medium segment up to the next surface (or to infinity).
        if let Some(id) = path.medium {
            let s = visitor.segment(scene, scene.medium(id), id, &path.ray, t_end, sampler);
            l += beta * s.radiance;
            beta *= s.transmittance;
        }
        if beta.is_black() {
            break;
        }

        // Escaped: the environment.
        let Some(hit) = hit else {
            // A transparent film holds out the background seen directly
            // (not through glass or mirrors, which are opaque for alpha).
            if !(scene.transparent_background && specular_bounces == 0) {
                l += beta * scene.escaped_radiance(path.ray.d);
            }
            break;
        };

        // Index-matched boundary: change medium and go on.
        let object = scene.object(&hit);
        if object.bsdf.is_null() {
            // The loop's own bound limits crossings (and bounces) first.
            path.cross(scene, &hit);
            continue;
        }

        // An area light: its emitted radiance (its surface reflects nothing).
        if let Some((le, _)) = scene.emitted_radiance(&hit, -path.ray.d) {
            l += beta * le;
            break;
        }

        // Specular surface (glass, metal): follow the sampled reflection or
        // refraction, as a Whitted-style ray tracer would. A rough
        // dielectric is followed the same way (one sampled direction,
        // weighted f |cos| / pdf), so that media behind frosted glass are seen.
        if object.bsdf.is_specular() || object.bsdf.has_rough_transmission() {
            specular_bounces += 1;
            if specular_bounces > MAX_SPECULAR_BOUNCES {
                break;
            }
            camera_layout::enter(sampler, camera_layout::LOBE);
            let u_lobe = sampler.next_1d();
            let ns = hit.surface.shading_normal(-path.ray.d);
            let bsdf = scene.surface_bsdf(&hit);
            camera_layout::enter(sampler, camera_layout::SPECULAR_DIRECTION);
            let Some(bs) = bsdf.sample(ns, -path.ray.d, u_lobe, sampler.next_2d()) else {
                break;
            };
            if !scene.path_continues(&hit, ns, bs.wi) {
                break;
            }
            beta *= bs.weight(ns);
            path.leave_surface(scene, &hit, bs.wi, bs.is_transmission);
            continue;
        }

        // Opaque surface: shaded by the integrator, then stop.
        l += beta * visitor.opaque_surface(scene, &hit, -path.ray.d, path.medium, sampler);
        break;
    }
    l
}

/// The walk of the emission and single-scattering style integrators with
/// the camera-ray dimension layout (`super::camera_layout`) for Sobol
/// samplers: `segment(medium, id, ray, t_end, sampler)` integrates one
/// medium segment and opaque surfaces are lit directly (one sample per
/// light, shadow rays by `method`).
pub(crate) fn trace_laid_out_camera_ray(
    scene: &Scene,
    ray: Ray,
    medium: Option<MediumId>,
    method: TransmittanceMethod,
    sampler: &mut PixelSampler,
    segment: impl FnMut(&Medium, MediumId, &Ray, f32, &mut PixelSampler) -> SegmentRadiance,
) -> Rgb {
    trace_camera_ray_with::<true>(scene, ray, medium, method, None, sampler, segment)
}

/// The walk of [`trace_laid_out_camera_ray`] (in draw order unless
/// `LAID_OUT`) whose opaque surfaces are also lit by one point
/// drawn from `volume_lights` (the emission inside media), when given, with
/// the camera-ray dimension layout when `LAID_OUT`.
pub(crate) fn trace_camera_ray_with<const LAID_OUT: bool>(
    scene: &Scene,
    ray: Ray,
    medium: Option<MediumId>,
    method: TransmittanceMethod,
    volume_lights: Option<&VolumeLights>,
    sampler: &mut PixelSampler,
    segment: impl FnMut(&Medium, MediumId, &Ray, f32, &mut PixelSampler) -> SegmentRadiance,
) -> Rgb {
    struct DirectLighting<'a, F, const LAID_OUT: bool> {
        segment: F,
        method: TransmittanceMethod,
        volume_lights: Option<&'a VolumeLights>,
    }
    impl<F: FnMut(&Medium, MediumId, &Ray, f32, &mut PixelSampler) -> SegmentRadiance, const LAID_OUT: bool>
        CameraRayVisitor for DirectLighting<'_, F, LAID_OUT>
    {
        const LAID_OUT: bool = LAID_OUT;

        #[inline]
        fn segment(
            &mut self,
            _scene: &Scene,
            m: &Medium,
            id: MediumId,
            ray: &Ray,
            t_end: f32,
            sampler: &mut PixelSampler,
        ) -> SegmentRadiance {
            (self.segment)(m, id, ray, t_end, sampler)
        }
        #[inline]
        fn opaque_surface(
            &mut self,
            scene: &Scene,
            hit: &Hit,
            wo: Vec3,
            medium: Option<MediumId>,
            sampler: &mut PixelSampler,
        ) -> Rgb {
            let bsdf = &scene.surface_bsdf(hit);
            let mut l = direct_surface_radiance(scene, &hit.surface, wo, bsdf, medium, self.method, sampler);
            if let Some(lights) = self.volume_lights {
                camera_layout::enter(sampler, camera_layout::SURFACE_VOLUME_LIGHT);
                l += volume_light_surface_radiance(scene, lights, &hit.surface, wo, bsdf, medium, self.method, sampler);
            }
            l
        }
    }
    let mut visitor = DirectLighting::<_, LAID_OUT> { segment, method, volume_lights };
    walk_camera_ray(scene, ray, medium, sampler, &mut visitor)
}

#[cfg(test)]
#[path = "camera_ray_tests.rs"]
mod tests;
