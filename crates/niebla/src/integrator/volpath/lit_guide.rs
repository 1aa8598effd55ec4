//! Directions toward the surfaces that point lights inside media light
//! brightly ([`LitSurfaces`]), a component of `volpath`'s lamp guide.
//!
//! A diffuse object next to a lamp in fog is a bright secondary source:
//! phase sampling at a medium vertex finds it with a probability of its
//! solid angle, and its radiance (many times the fog's) makes those rare
//! hits a heavy tail. Each such object is bounded by a sphere; seen from a
//! point `x` outside it, the sphere subtends a cone of solid angle
//! `Omega_k(x)`. Directions are drawn by picking object `k` with probability
//! `L_k Omega_k(x) / sum_j L_j Omega_j(x)` and a direction uniform in its
//! cone, where `L_k` is an estimate of the object's radiance fixed when the
//! scene is built. The solid-angle density of direction `w` is then
//! `sum_{k: w in cone k} L_k / sum_j L_j Omega_j(x)`: exact, whatever the
//! estimates, and as cheap to evaluate as to sample.

use crate::bsdf::Bsdf;
use crate::geometry::Shape;
use crate::light::Light;
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::sample_uniform_cone;

/// Most objects a [`LitSurfaces`] aims at (the brightest by estimate).
const MAX_LIT_TARGETS: usize = 8;

/// Radius of a non-spherical object's target sphere, as a fraction of the
/// distance from its brightest lamp to its bounding box: on
/// bench/scenes/fog_point.json (48 px, 8 renders of 64 spp, guide fraction
/// 0.4, share 0.3) 0.6, 0.75 and 0.85 gave relative MSE 3.35e-3, 3.28e-3
/// and 3.33e-3; the whole bounding box's sphere as the target gave 3.78e-3
/// (fraction 0.35, share 0.3; 3.55e-3 at share 0.1).
const SPOT_RADIUS: f32 = 0.75;

/// One lit object: its bounding sphere and radiance estimate.
#[derive(Clone, Copy, Debug, Default)]
struct Target {
    center: Vec3,
    /// Square of the bounding sphere's radius, world units^2.
    radius2: f32,
    /// Estimated radiance of the object's lit side (luminance, W/(m^2 sr)
    /// per unit of the scene's light units); the component's weight per sr.
    radiance: f32,
}

/// Direction sampling toward diffuse objects lit by point lights inside
/// media, by cones around their bounding spheres (see the module comment).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LitSurfaces {
    targets: [Target; MAX_LIT_TARGETS],
    count: usize,
}

/// The cone of a bounding sphere seen from `x`: unit axis, cosine of the
/// half-angle, `1 - cos` (accurate for narrow cones), and the distance to
/// the center; `None` when `x` is inside the sphere.
#[inline]
fn cone(t: &Target, x: Vec3) -> Option<(Vec3, f32, f32, f32)> {
    let to = t.center - x;
    let d2 = to.length_squared();
    if !(d2 > t.radius2) {
        return None;
    }
    let sin2 = t.radius2 / d2;
    let cos = (1.0 - sin2).sqrt();
    let one_minus_cos = sin2 / (1.0 + cos);
    let d = d2.sqrt();
    Some((to / d, cos, one_minus_cos, d))
}

impl LitSurfaces {
    /// The objects of `objects` with a constant diffuse BSDF (no texture,
    /// no emission) lit by the point lights among `lights` whose positions
    /// satisfy `guided` (those inside a medium). Each object's target is a
    /// sphere: a sphere's own, else one around the point of the object's
    /// bounding box nearest its brightest lamp (radius [`SPOT_RADIUS`] times
    /// that distance); objects whose target holds a lamp are left out (a
    /// light's own guide covers those). The radiance estimate of an object is its reflectance's
    /// luminance times the sum over lights of `I / (pi d^2)`, `I` the
    /// intensity's luminance and `d` the distance from the light to the
    /// object's bounding box; the brightest [`MAX_LIT_TARGETS`] are kept, in
    /// a fixed order (brightest first, then by object index).
    pub(crate) fn new(
        objects: &[crate::world::SceneObject],
        lights: &[Light],
        guided: impl Fn(Vec3) -> bool,
    ) -> LitSurfaces {
        let lamps: Vec<(Vec3, f32)> = lights
            .iter()
            .filter_map(|l| match l {
                Light::Point(p) if guided(p.position) => Some((p.position, p.intensity.luminance())),
                _ => None,
            })
            .filter(|&(_, i)| i > 0.0 && i.is_finite())
            .collect();
        let mut candidates: Vec<(f32, usize, Target)> = Vec::new();
        if lamps.is_empty() {
            return LitSurfaces::default();
        }
        for (index, object) in objects.iter().enumerate() {
            let Bsdf::Diffuse { reflectance } = object.bsdf else {
                continue;
            };
            if object.texture.is_some() || object.emitter.is_some() || matches!(object.shape, Shape::Moving(_)) {
                continue;
            }
            let albedo = reflectance.luminance();
            let (lo, hi) = object.shape.bounds();
            let (center, radius) = match &object.shape {
                Shape::Sphere(s) => (s.center, s.radius),
                // The part of the object next to the lamp that lights it
                // most: a sphere around the box's point nearest that lamp,
                // of radius 3/4 of that lamp's distance to it (the
                // irradiance of a plane at the sphere's rim is ~0.36 of its
                // peak), within the box's half diagonal.
                _ => {
                    let p = lamps
                        .iter()
                        .max_by(|a, b| {
                            let e = |&(p, i): &(Vec3, f32)| i / (p.clamp(lo, hi) - p).length_squared();
                            e(a).total_cmp(&e(b))
                        })
                        .map_or(Vec3::ZERO, |l| l.0);
                    let near = p.clamp(lo, hi);
                    (near, (SPOT_RADIUS * (near - p).length()).min(0.5 * (hi - lo).length()))
                }
            };
            if !(albedo > 0.0 && radius > 0.0 && radius.is_finite() && center.is_finite()) {
                continue;
            }
            let radius2 = radius * radius;
            if lamps.iter().any(|&(p, _)| (p - center).length_squared() <= radius2) {
                continue;
            }
            let irradiance: f32 = lamps
                .iter()
                .map(|&(p, i)| {
                    let d = (p.clamp(lo, hi) - p).length().max(1e-3 * radius);
                    i / (std::f32::consts::PI * d * d)
                })
                .sum();
            let radiance = albedo * irradiance;
            if radiance > 0.0 && radiance.is_finite() {
                candidates.push((radiance, index, Target { center, radius2, radiance }));
            }
        }
        candidates.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let mut guide = LitSurfaces::default();
        for (_, _, t) in candidates.into_iter().take(MAX_LIT_TARGETS) {
            guide.targets[guide.count] = t;
            guide.count += 1;
        }
        guide
    }

    /// Whether some object is aimed at.
    #[inline]
    pub(crate) fn is_active(&self) -> bool {
        self.count > 0
    }

    /// `sum_j L_j Omega_j(x)` (sr x radiance): 0 when `x` sees no target
    /// from outside its bounding sphere, and then nothing can be sampled.
    #[inline]
    pub(crate) fn total(&self, x: Vec3) -> f32 {
        self.targets[..self.count]
            .iter()
            .filter_map(|t| cone(t, x).map(|(_, _, omc, _)| t.radiance * 2.0 * std::f32::consts::PI * omc))
            .sum()
    }

    /// A unit direction from `x` into one target's cone, the target chosen
    /// with `u_pick` in proportion to `L_k Omega_k(x)` (`total` is
    /// [`LitSurfaces::total`] at `x`, positive); uniform in the cone with
    /// `u_dir`.
    pub(crate) fn sample(&self, x: Vec3, total: f32, u_pick: f32, u_dir: Vec2) -> Option<Vec3> {
        let mut goal = u_pick * total;
        let mut chosen = None;
        for t in &self.targets[..self.count] {
            if let Some(c) = cone(t, x) {
                chosen = Some(c);
                goal -= t.radiance * 2.0 * std::f32::consts::PI * c.2;
                if goal < 0.0 {
                    break;
                }
            }
        }
        let (axis, cos, _, _) = chosen?;
        Some(Frame::from_z(axis).to_world(sample_uniform_cone(u_dir, cos)).normalize())
    }

    /// Solid-angle density (1/sr) of [`LitSurfaces::sample`] from `x` at
    /// unit `w`, given `total` = [`LitSurfaces::total`] at `x` (0 when it
    /// is not positive).
    #[cfg(test)]
    pub(crate) fn pdf(&self, x: Vec3, total: f32, w: Vec3) -> f32 {
        if !(total > 0.0) {
            return 0.0;
        }
        self.density(x, w).1 / total
    }

    /// [`LitSurfaces::total`] at `x` and the sum of `L_k` over the cones
    /// holding unit `w`, in one pass (the density is their ratio).
    #[inline]
    pub(crate) fn density(&self, x: Vec3, w: Vec3) -> (f32, f32) {
        let (mut total, mut inside) = (0.0f32, 0.0f32);
        for t in &self.targets[..self.count] {
            if let Some((axis, cos, one_minus_cos, _)) = cone(t, x) {
                total += t.radiance * 2.0 * std::f32::consts::PI * one_minus_cos;
                if w.dot(axis) >= cos {
                    inside += t.radiance;
                }
            }
        }
        (total, inside)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::volpath::guide_checks::{sampled_and_integrated, sphere_integral};
    use crate::sampling::PixelSampler;

    /// Three targets: a far small one, a near large one and one that holds
    /// the second query point.
    fn guide() -> LitSurfaces {
        let mut g = LitSurfaces::default();
        for (center, radius, radiance) in
            [(Vec3::new(3.0, 0.5, -1.0), 0.2, 2.0), (Vec3::new(-1.0, 0.0, 1.0), 0.9, 0.5), (Vec3::ZERO, 0.4, 1.0)]
        {
            g.targets[g.count] = Target { center, radius2: radius * radius, radiance };
            g.count += 1;
        }
        g
    }

    /// The direction density integrates to 1 over the sphere (Monte Carlo
    /// with 400000 uniform directions, within 4 standard errors), from
    /// points that see all targets and from one inside a target.
    #[test]
    fn pdf_integrates_to_one() {
        let g = guide();
        for x in [Vec3::new(0.5, 1.5, 0.2), Vec3::new(0.1, 0.1, 0.0), Vec3::new(-4.0, 2.0, 3.0)] {
            let total = g.total(x);
            assert!(total > 0.0);
            let (mean, se) = sphere_integral(&mut PixelSampler::from_key(11), 400_000, |w| g.pdf(x, total, w));
            assert!((mean - 1.0).abs() < 4.0 * se + 1e-3, "from {x}: {mean} +- {se}");
        }
    }

    /// Sampled directions follow the density: the mean of `min(pdf, cap)`
    /// over the sampler's own directions equals the integral of
    /// `pdf min(pdf, cap)` estimated with uniform directions (within 2%),
    /// which fails if a target is drawn with the wrong probability.
    #[test]
    fn sampled_directions_follow_the_density() {
        let g = guide();
        let x = Vec3::new(0.5, 1.5, 0.2);
        let total = g.total(x);
        let sample = |s: &mut PixelSampler| {
            let w = g.sample(x, total, s.next_1d(), s.next_2d()).unwrap();
            assert!((w.length() - 1.0).abs() < 1e-4);
            Some(w)
        };
        let (a, b) =
            sampled_and_integrated(&mut PixelSampler::from_key(13), 400_000, 2.0, sample, |w| g.pdf(x, total, w));
        assert!((a - b).abs() < 0.02 * b, "sampled {a} vs integrated {b}");
    }

    /// Nothing to aim at from inside every target: the total is 0 and so
    /// is the density.
    #[test]
    fn inside_every_target_the_guide_is_empty() {
        let mut g = LitSurfaces::default();
        g.targets[0] = Target { center: Vec3::ZERO, radius2: 1.0, radiance: 1.0 };
        g.count = 1;
        let x = Vec3::new(0.2, 0.1, 0.0);
        assert_eq!(g.total(x), 0.0);
        assert_eq!(g.pdf(x, 0.0, Vec3::X), 0.0);
    }
}
