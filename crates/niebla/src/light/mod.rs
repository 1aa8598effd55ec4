//! Lights. Radiometric quantities follow Mitsuba 3 so scenes compare 1:1:
//! a point light has `intensity` (W/sr), a spot light `intensity` on its axis
//! (W/sr), a directional light `irradiance` (W/m^2 on a surface perpendicular
//! to its direction of travel), a constant environment `radiance`
//! (W/(sr m^2)).

mod area;
mod emitted_rays;
mod envmap;
mod mesh_light;

pub use area::{AreaLight, AreaLightSample, AreaMotion, AreaShape};
pub use emitted_rays::{spot_falloff_solid_angle, EmittedRay, SceneSphere};
pub use envmap::{latlong_direction, latlong_uv, EnvironmentMap, EnvironmentSample, LightError};
pub use mesh_light::MeshLight;

use crate::color::Rgb;
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere, sample_uniform_sphere, uniform_sphere_pdf};

/// A closed set of lights.
#[derive(Clone, Debug)]
pub enum Light {
    /// Isotropic point light.
    Point(PointLight),
    /// Spot light with Mitsuba 3's linear-in-angle falloff.
    Spot(SpotLight),
    /// Distant light with parallel rays.
    Directional(DirectionalLight),
    /// Uniform environment of constant radiance.
    Constant(ConstantLight),
    /// Emitting rectangle, disk, sphere or triangle mesh of uniform radiance
    /// (its shape is also a scene object, which rays hit).
    Area(AreaLight),
    /// Lat-long environment map, importance sampled.
    Environment(std::sync::Arc<EnvironmentMap>),
}

/// Isotropic point light.
#[derive(Clone, Copy, Debug)]
pub struct PointLight {
    /// Position (world).
    pub position: Vec3,
    /// Radiant intensity, W/sr.
    pub intensity: Rgb,
}

/// Spot light: intensity `I` on the axis, 1 inside `beam_width`, falling
/// linearly in angle to 0 at `cutoff_angle` (Mitsuba 3 `spot`).
#[derive(Clone, Copy, Debug)]
pub struct SpotLight {
    /// Position (world).
    pub position: Vec3,
    /// Frame whose z axis is the unit spot axis.
    pub frame: Frame,
    /// Radiant intensity on the axis, W/sr.
    pub intensity: Rgb,
    /// Cutoff half-angle, radians.
    pub cutoff_angle: f32,
    /// Half-angle of full intensity, radians (<= cutoff).
    pub beam_width: f32,
}

impl SpotLight {
    /// Falloff factor in [0, 1] for a unit direction `w` leaving the light (world).
    #[inline]
    pub fn falloff(&self, w: Vec3) -> f32 {
        let cos_theta = w.dot(self.frame.z);
        if cos_theta <= self.cutoff_angle.cos() {
            return 0.0;
        }
        if cos_theta >= self.beam_width.cos() {
            return 1.0;
        }
        let width = self.cutoff_angle - self.beam_width;
        if width <= 0.0 {
            return 1.0;
        }
        ((self.cutoff_angle - cos_theta.clamp(-1.0, 1.0).acos()) / width).clamp(0.0, 1.0)
    }
}

/// Distant light.
#[derive(Clone, Copy, Debug)]
pub struct DirectionalLight {
    /// Unit direction in which the light travels (world).
    pub direction: Vec3,
    /// Irradiance on a surface perpendicular to `direction`, W/m^2.
    pub irradiance: Rgb,
}

/// Uniform environment.
#[derive(Clone, Copy, Debug)]
pub struct ConstantLight {
    /// Radiance arriving from every direction, W/(sr m^2).
    pub radiance: Rgb,
}

/// A sampled direction toward a light as seen from a receiving point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the receiver toward the light (world).
    pub wi: Vec3,
    /// Distance to the light along `wi` (infinite for distant lights).
    pub distance: f32,
    /// Unoccluded incident radiance (or, for delta lights, irradiance
    /// perpendicular to `wi`) arriving at the receiver, before transmittance.
    pub li: Rgb,
    /// Density of `wi` per steradian; 1 for delta lights.
    pub pdf: f32,
    /// True for point, spot and directional lights (no MIS possible).
    pub is_delta: bool,
}

impl Light {
    /// Sample incident light at `p` at `time` (frames; a moving area light
    /// is sampled in its pose at that instant, the camera sample's
    /// [`crate::sampling::PixelSampler::time`]). `normal` (if any) lets
    /// environment lights sample the hemisphere around a surface normal with
    /// a cosine density.
    #[inline]
    pub fn sample_li(&self, p: Vec3, normal: Option<Vec3>, u: Vec2, time: f32) -> Option<LightSample> {
        match self {
            Light::Point(l) => {
                let to = l.position - p;
                let d2 = to.length_squared();
                if d2 == 0.0 {
                    return None;
                }
                let distance = d2.sqrt();
                Some(LightSample { wi: to / distance, distance, li: l.intensity / d2, pdf: 1.0, is_delta: true })
            }
            Light::Spot(l) => {
                let to = l.position - p;
                let d2 = to.length_squared();
                if d2 == 0.0 {
                    return None;
                }
                let distance = d2.sqrt();
                let wi = to / distance;
                let f = l.falloff(-wi);
                if f == 0.0 {
                    return None;
                }
                Some(LightSample { wi, distance, li: l.intensity * (f / d2), pdf: 1.0, is_delta: true })
            }
            Light::Directional(l) => Some(LightSample {
                wi: -l.direction,
                distance: f32::INFINITY,
                li: l.irradiance,
                pdf: 1.0,
                is_delta: true,
            }),
            Light::Area(a) => {
                let s = match a.at_time(time) {
                    Some(posed) => posed.sample_li(p, u)?,
                    None => a.sample_li(p, u)?,
                };
                // Stop shadow rays just short of the emitting surface itself.
                let mut distance = s.distance * (1.0 - 1e-4);
                if a.shape.is_mesh() {
                    // A mesh's shadow rays test the mesh itself (other parts
                    // of it may hide the point): a ray leaving a surface
                    // starts up to `surface_epsilon(p)` off `p`, which moves
                    // its end by as much; pulled back by twice that over the
                    // light's geometric |cos|, the end stays in front of
                    // the sampled triangle (at least half the distance is
                    // kept).
                    let cos_light = s.ng.dot(s.wi).abs().max(1e-3);
                    distance = (distance - 2.0 * crate::world::surface_epsilon(p) / cos_light).max(0.5 * s.distance);
                }
                Some(LightSample { wi: s.wi, distance, li: s.li, pdf: s.pdf, is_delta: false })
            }
            Light::Environment(e) => {
                let s = e.sample_li(u)?;
                Some(LightSample { wi: s.wi, distance: f32::INFINITY, li: s.li, pdf: s.pdf, is_delta: false })
            }
            Light::Constant(l) => {
                let (wi, pdf) = match normal {
                    Some(n) => {
                        let local = sample_cosine_hemisphere(u);
                        (Frame::from_z(n).to_world(local), cosine_hemisphere_pdf(local.z))
                    }
                    None => (sample_uniform_sphere(u), uniform_sphere_pdf()),
                };
                if pdf == 0.0 {
                    return None;
                }
                Some(LightSample { wi, distance: f32::INFINITY, li: l.radiance, pdf, is_delta: false })
            }
        }
    }

    /// Density per steradian with which [`Light::sample_li`] at `p` (with the
    /// same `normal` and `time` arguments) returns direction `wi`; 0 for
    /// delta lights.
    #[inline]
    pub fn pdf_li(&self, p: Vec3, normal: Option<Vec3>, wi: Vec3, time: f32) -> f32 {
        match self {
            Light::Area(a) => a.at_time(time).map_or_else(|| a.pdf_li(p, wi), |posed| posed.pdf_li(p, wi)),
            Light::Environment(e) => e.pdf_li(wi),
            Light::Constant(_) => match normal {
                Some(n) => cosine_hemisphere_pdf(wi.dot(n)),
                None => uniform_sphere_pdf(),
            },
            _ => 0.0,
        }
    }

    /// True for lights described by a delta distribution (point, spot,
    /// directional): no ray can hit them, so they take no MIS.
    #[inline]
    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Spot(_) | Light::Directional(_))
    }

    /// True for lights at infinity that escaping rays see.
    #[inline]
    pub fn is_infinite(&self) -> bool {
        matches!(self, Light::Constant(_) | Light::Environment(_))
    }

    /// Radiance seen along a ray that escapes the scene in direction `d`.
    #[inline]
    pub fn le_escaped(&self, d: Vec3) -> Rgb {
        match self {
            Light::Constant(l) => l.radiance,
            Light::Environment(e) => e.le(d),
            _ => Rgb::ZERO,
        }
    }

    /// Position of a point-like light (point, spot), for equiangular sampling.
    #[inline]
    pub fn point_position(&self) -> Option<Vec3> {
        match self {
            Light::Point(l) => Some(l.position),
            Light::Spot(l) => Some(l.position),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spot_falloff_is_one_in_beam_and_zero_past_cutoff() {
        let s = SpotLight {
            position: Vec3::ZERO,
            frame: Frame::from_z(Vec3::Z),
            intensity: Rgb::ONE,
            cutoff_angle: 20f32.to_radians(),
            beam_width: 10f32.to_radians(),
        };
        assert_eq!(s.falloff(Vec3::Z), 1.0);
        let at = |deg: f32| s.falloff(Vec3::new(deg.to_radians().sin(), 0.0, deg.to_radians().cos()));
        assert_eq!(at(9.0), 1.0);
        assert!((at(15.0) - 0.5).abs() < 1e-3);
        assert_eq!(at(21.0), 0.0);
    }

    #[test]
    fn point_light_follows_inverse_square() {
        let l = Light::Point(PointLight { position: Vec3::new(0.0, 2.0, 0.0), intensity: Rgb::splat(8.0) });
        let s = l.sample_li(Vec3::ZERO, None, Vec2::ZERO, 0.0).unwrap();
        assert_eq!(s.li, Rgb::splat(2.0));
        assert!((s.wi - Vec3::Y).length() < 1e-6);
        assert_eq!(s.distance, 2.0);
    }
}
