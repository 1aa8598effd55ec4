//! What a camera ray meets first, for the alpha, albedo, normal and depth
//! layers (definitions in the `aov` module documentation), estimated
//! independently of the integrator from a random stream of its own.

use crate::bsdf::{Bsdf, Reflector};
use crate::color::Rgb;
use crate::math::{Ray, Vec3};
use crate::medium::MediumId;
use crate::sampling::PixelSampler;
use crate::tracking::{sample_t_maj_without_emission, segment_transmittance, TransmittanceMethod};
use crate::world::{PathRay, Scene, MAX_BOUNDARY_CROSSINGS};

/// The features of one camera sample.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Features {
    /// Transmittance to the background averaged over channels (0 when an
    /// opaque surface blocks the ray); alpha is `1 - transmittance`.
    pub transmittance: f32,
    /// Albedo at the first collision or surface (0 if none).
    pub albedo: Rgb,
    /// Normal there (0 in media and if none).
    pub normal: Vec3,
    /// Distance from the camera to it (0 if none).
    pub depth: f32,
    /// 1 if the ray met a collision or surface, else 0.
    pub coverage: f32,
}

/// Albedo of a surface model for the albedo layer: the diffuse
/// reflectance (a plastic's base), 1 for glass and smooth metal (the
/// denoiser's convention for specular surfaces), a rough metal's specular
/// reflectance, the front side's for `twosided`, 0 for an index-matched
/// boundary.
pub fn surface_albedo(bsdf: &Bsdf) -> Rgb {
    match *bsdf {
        Bsdf::Diffuse { reflectance } => reflectance,
        Bsdf::Null => Rgb::ZERO,
        Bsdf::Dielectric { .. } | Bsdf::Conductor { .. } => Rgb::ONE,
        Bsdf::RoughDielectric(_) | Bsdf::ThinDielectric(_) => Rgb::ONE,
        Bsdf::RoughConductor(b) => b.specular_reflectance,
        Bsdf::Plastic(b) => b.diffuse_reflectance,
        Bsdf::RoughPlastic(b) => b.diffuse_reflectance,
        Bsdf::TwoSided(b) => reflector_albedo(&b.front),
    }
}

/// [`surface_albedo`] of one side of a `twosided` surface.
fn reflector_albedo(r: &Reflector) -> Rgb {
    match *r {
        Reflector::Diffuse { reflectance } => reflectance,
        Reflector::Conductor { .. } => Rgb::ONE,
        Reflector::RoughConductor(b) => b.specular_reflectance,
        Reflector::Plastic(b) => b.diffuse_reflectance,
        Reflector::RoughPlastic(b) => b.diffuse_reflectance,
    }
}

/// Walk the camera ray `ray` (unit direction, starting in `medium`):
/// transmittance to the background by exact transmittance in homogeneous
/// media and ratio tracking in grids, and the first real collision by
/// free-flight sampling with the extinction of a channel drawn uniformly.
pub fn camera_features(scene: &Scene, ray: Ray, medium: Option<MediumId>, sampler: &mut PixelSampler) -> Features {
    let hero = ((sampler.next_1d() * 3.0) as usize).min(2);
    let mut path = PathRay::new(ray, medium, 0.0);
    let mut transmittance = Rgb::ONE;
    // Distance travelled before the current ray's origin.
    let mut travelled = 0.0f32;
    let mut first: Option<(Rgb, Vec3, f32)> = None;
    for _ in 0..MAX_BOUNDARY_CROSSINGS {
        let hit = path.intersect(scene);
        let t_end = hit.map_or(f32::INFINITY, |h| h.surface.t);
        if let Some(id) = path.medium {
            let m = scene.medium(id);
            let r = path.ray;
            if transmittance.max_channel() > 0.0 {
                transmittance *= segment_transmittance(m, &r, 0.0, t_end, TransmittanceMethod::Analytic, sampler);
            }
            if first.is_none() {
                sample_t_maj_without_emission(m, &r, t_end, hero, sampler, |c, sampler| {
                    let sigma_t = c.point.sigma_t();
                    if sampler.next_1d() * c.sigma_maj[hero] < sigma_t[hero] {
                        let albedo = c.point.sigma_s.safe_div(sigma_t);
                        first = Some((albedo, Vec3::ZERO, travelled + c.t));
                        return false;
                    }
                    true
                });
            }
        }
        let Some(hit) = hit else {
            break;
        };
        let object = scene.object(&hit);
        if object.bsdf.is_null() {
            travelled += hit.surface.t;
            if !path.cross(scene, &hit) {
                transmittance = Rgb::ZERO;
                break;
            }
            continue;
        }
        // Any other surface is opaque for alpha (lamps, glass and metal too).
        transmittance = Rgb::ZERO;
        if first.is_none() {
            let wo = -path.ray.d;
            let albedo = if object.emitter.is_some() { Rgb::ZERO } else { surface_albedo(&scene.surface_bsdf(&hit)) };
            let ns = hit.surface.shading_normal(wo);
            let normal = if ns.dot(wo) < 0.0 { -ns } else { ns };
            first = Some((albedo, normal, travelled + hit.surface.t));
        }
        break;
    }
    let (albedo, normal, depth, coverage) = match first {
        Some((a, n, d)) => (a, n, d, 1.0),
        None => (Rgb::ZERO, Vec3::ZERO, 0.0, 0.0),
    };
    Features { transmittance: transmittance.average(), albedo, normal, depth, coverage }
}
