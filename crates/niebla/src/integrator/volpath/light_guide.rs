//! `volpath`'s guide toward point and spot lights inside media
//! ([`LightGuide`]): directions toward the cone of space a light illuminates
//! ([`LightCone`]).
//!
//! A point `y` is sampled with density proportional to `1/r^2` (r the
//! distance to the light) inside the light's cone (the whole sphere for a
//! point light) out to a radius `R`: directions from the light uniform over
//! the cone and `r` uniform on `[0, R]`. The solid-angle density of the
//! direction toward `y` seen from another point is the integral of that
//! density times `s^2` along the ray, in closed form; it grows as `1/h` for
//! directions passing at distance `h` from the light.

use crate::light::Light;
use crate::math::{Frame, Ray, Vec3};
use crate::sampling::sample_uniform_cone;

use crate::integrator::equiangular::cone_hull;

use super::lit_guide::LitSurfaces;

/// Points with density `1 / (Omega R r^2)` in the cone of half-angle
/// `acos(cos_cutoff)` (`cos_cutoff = -1`: the whole sphere) around `axis`
/// with apex at the light, `r` the distance to the apex, `r < R`, Omega the
/// cone's solid angle.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightCone {
    apex: Vec3,
    frame: Frame,
    cos_cutoff: f32,
    /// Solid angle of the cone, sr.
    solid_angle: f32,
    /// Largest distance from the apex, world units.
    radius: f32,
}

impl LightCone {
    /// The volume of `light` (a point or spot light) out to `radius`; `None`
    /// for other lights or a radius that is not positive and finite.
    pub(crate) fn new(light: &Light, radius: f32) -> Option<LightCone> {
        if !(radius > 0.0 && radius.is_finite()) {
            return None;
        }
        let (apex, frame, cos_cutoff) = match light {
            Light::Point(l) => (l.position, Frame::from_z(Vec3::Z), -1.0f32),
            Light::Spot(l) => (l.position, l.frame, l.cutoff_angle.cos()),
            _ => return None,
        };
        let solid_angle = 2.0 * std::f32::consts::PI * (1.0 - cos_cutoff);
        (solid_angle > 0.0).then_some(LightCone { apex, frame, cos_cutoff, solid_angle, radius })
    }

    /// A point of the volume from three uniform numbers.
    pub(crate) fn sample(&self, u_dir: crate::math::Vec2, u_r: f32) -> Vec3 {
        let local = sample_uniform_cone(u_dir, self.cos_cutoff);
        self.apex + self.frame.to_world(local) * (u_r * self.radius)
    }

    /// Solid-angle density (1/sr) that the direction from `x` toward a point
    /// sampled by [`LightCone::sample`] is `w` (unit): the integral of the
    /// point density times `s^2` along the ray `x + s w`.
    pub(crate) fn direction_pdf(&self, x: Vec3, w: Vec3) -> f32 {
        let ray = Ray::new(x, w);
        // The ray's part inside the cone, then within R of the apex.
        let (s_a, s_b) = if self.cos_cutoff <= -1.0 {
            (0.0, f32::INFINITY)
        } else {
            match cone_hull(&ray, self.apex, self.frame.z, self.cos_cutoff, f32::INFINITY) {
                Some(range) => range,
                None => return 0.0,
            }
        };
        let to_apex = self.apex - x;
        let s_c = f64::from(to_apex.dot(w));
        let h2 = (f64::from(to_apex.length_squared()) - s_c * s_c).max(0.0);
        let r2 = f64::from(self.radius) * f64::from(self.radius);
        if h2 >= r2 {
            return 0.0;
        }
        let half = (r2 - h2).sqrt();
        let lo = f64::from(s_a).max(s_c - half).max(0.0);
        let hi = f64::from(s_b).min(s_c + half);
        if !(hi > lo) {
            return 0.0;
        }
        let h = h2.sqrt().max(1e-9 * (1.0 + s_c.abs()));
        // Antiderivative of s^2 / (h^2 + (s - s_c)^2) in u = s - s_c.
        let f = |u: f64| u + s_c * (h * h + u * u).ln() + (s_c * s_c - h * h) / h * (u / h).atan();
        let integral = f(hi - s_c) - f(lo - s_c);
        let pdf = integral / (f64::from(self.solid_angle) * f64::from(self.radius));
        if pdf.is_finite() && pdf > 0.0 {
            pdf as f32
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::volpath::guide_checks::{mean_se, sampled_and_integrated, sphere_integral};
    use crate::light::{PointLight, SpotLight};
    use crate::sampling::PixelSampler;

    /// The direction density integrates to 1 over the sphere of directions
    /// from a point (Monte Carlo with uniform directions), for a point light
    /// and a spot light, from inside and outside the volume.
    #[test]
    fn direction_pdf_integrates_to_one() {
        let spot = Light::Spot(SpotLight {
            position: Vec3::new(0.0, 3.0, 0.0),
            frame: Frame::from_z(Vec3::new(0.2, -1.0, 0.1).normalize()),
            intensity: crate::color::Rgb::ONE,
            cutoff_angle: 0.5,
            beam_width: 0.4,
        });
        let point = Light::Point(PointLight { position: Vec3::new(0.5, 1.0, -0.5), intensity: crate::color::Rgb::ONE });
        for light in [spot, point] {
            let volume = LightCone::new(&light, 5.0).unwrap();
            for x in [Vec3::new(0.3, 1.0, 0.2), Vec3::new(4.0, -1.0, 2.0), Vec3::new(0.0, 2.5, 0.0)] {
                let mut s = PixelSampler::from_key(5);
                let (mean, se) = sphere_integral(&mut s, 400_000, |w| volume.direction_pdf(x, w));
                assert!((mean - 1.0).abs() < 4.0 * se + 2e-3, "{light:?} from {x}: {mean} +- {se}");
            }
        }
    }

    /// The root mean square distance to a box's points equals a Monte Carlo
    /// average over uniform points of the box (400000 points; the SE of
    /// the mean square is below 0.2%), from inside and outside the box.
    #[test]
    fn rms_distance_matches_uniform_points_of_the_box() {
        let (lo, hi) = (Vec3::new(-3.0, -0.5, -3.0), Vec3::new(3.0, 3.0, 5.5));
        for p in [Vec3::new(-0.2, 1.5, 0.4), Vec3::new(2.9, -0.4, 5.0), Vec3::new(10.0, 4.0, -7.0)] {
            let mut s = PixelSampler::from_key(3);
            let (mean, se) = mean_se(400_000, || {
                let u = Vec3::new(s.next_1d(), s.next_1d(), s.next_1d());
                f64::from((lo + (hi - lo) * u - p).length_squared())
            });
            let r = f64::from(rms_distance_to_box(p, lo, hi));
            assert!((r * r - mean).abs() < 4.0 * se + 1e-4 * mean, "from {p}: {} vs {mean} +- {se}", r * r);
        }
    }

    /// Directions toward sampled points follow the density: its mean over
    /// its own samples equals the integral of its square, estimated with
    /// uniform directions (a histogram-free check of shape, not only of norm).
    #[test]
    fn sampled_directions_follow_the_density() {
        let light = Light::Spot(SpotLight {
            position: Vec3::new(0.0, 2.0, 0.0),
            frame: Frame::from_z(-Vec3::Y),
            intensity: crate::color::Rgb::ONE,
            cutoff_angle: 0.6,
            beam_width: 0.5,
        });
        let volume = LightCone::new(&light, 4.0).unwrap();
        let x = Vec3::new(2.5, 0.5, 0.3);
        // E_q[min(p, c)] under the sampler vs the same integral with uniform directions.
        let sample = |s: &mut PixelSampler| Some((volume.sample(s.next_2d(), s.next_1d()) - x).normalize());
        let (a, b) = sampled_and_integrated(&mut PixelSampler::from_key(9), 400_000, 2.0, sample, |w| {
            volume.direction_pdf(x, w)
        });
        assert!((a - b).abs() < 0.02 * b, "sampled {a} vs integrated {b}");
    }

    /// On bench/scenes/fog_point.json the guide aims at its point lamp and
    /// at the three diffuse objects it lights (ball, box, floor), and its
    /// whole mixture density (lamp volume and lit objects) integrates to 1
    /// over the sphere from points in the fog, on the floor and next to
    /// the lamp (400000 uniform directions, within 4 standard errors), and
    /// the directions it samples follow it (as above, within 2%).
    #[test]
    fn fog_point_guide_density_integrates_to_one_and_is_sampled() {
        use crate::scene::{build_scene, parse_scene_str};
        let text = include_str!("../../../../../bench/scenes/fog_point.json");
        let desc = parse_scene_str(text, "fog_point").unwrap();
        let scene = build_scene(&desc, "fog_point", std::path::Path::new(".")).unwrap().scene;
        let guide = LightGuide::new(&scene);
        assert_eq!(guide.count, 1);
        assert!(guide.lit_share > 0.0 && guide.lit.is_active());
        for x in [Vec3::new(0.3, 1.2, 2.5), Vec3::new(1.5, 1e-3, 1.0), Vec3::new(-0.1, 1.4, 0.5)] {
            assert!(guide.lit_at(x).0 > 0.0, "{x}");
            let mut s = PixelSampler::from_key(17);
            let (mean, se) = sphere_integral(&mut s, 400_000, |w| guide.pdf(x, w));
            assert!((mean - 1.0).abs() < 4.0 * se + 2e-3, "from {x}: {mean} +- {se}");
            let sample = |s: &mut PixelSampler| guide.sample(x, s.next_1d(), s.next_2d(), s.next_1d());
            let (a, b) = sampled_and_integrated(&mut s, 400_000, 2.0, sample, |w| guide.pdf(x, w));
            assert!((a - b).abs() < 0.02 * b, "from {x}: sampled {a} vs integrated {b}");
        }
    }
}

/// Share of a [`LightGuide`]'s directions drawn toward diffuse objects the
/// guided point lights light ([`LitSurfaces`]), where it has some in view
/// and every guided light is a point light.
/// On bench/scenes/fog_point.json (48 px, 8 renders of 64 spp, guide
/// fraction 0.4) 0.2, 0.3 and 0.4 gave relative MSE 3.33e-3, 3.28e-3 and
/// 3.40e-3 (3.73e-3 without).
const LIT_SHARE: f32 = 0.3;

/// Most lights a [`LightGuide`] aims at.
const MAX_GUIDED_LIGHTS: usize = 4;

/// Direction guiding toward point and spot lights that lie inside a medium.
///
/// Equiangular sampling on a segment that passes at distance `h` from a
/// point light returns about `1/h` times the light's radiance scale, and
/// phase or BSDF sampling picks directions passing within `h` with a
/// probability proportional to `h^2`: the estimator's variance diverges
/// (logarithmically), and renders of a lamp inside fog show fireflies that
/// do not average out. Directions drawn toward the light's [`LightCone`]
/// have a density proportional to `1/h` near the light, which cancels the
/// singularity; `volpath` mixes them with phase/BSDF sampling (one-sample
/// MIS). Lights outside every medium need none (no segment in a medium comes
/// arbitrarily close to them), so the guide is empty there.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LightGuide {
    volumes: [Option<LightCone>; MAX_GUIDED_LIGHTS],
    count: usize,
    /// Whether every guided light is a point light.
    points_only: bool,
    /// Directions toward the diffuse objects those lights light (used only
    /// when every guided light is a point light).
    lit: LitSurfaces,
    /// Share of the guide's directions drawn toward `lit` where some of its
    /// objects is seen from outside its bounding sphere.
    lit_share: f32,
}

impl LightGuide {
    /// The guide toward the scene's point and spot lights that lie inside a
    /// medium (the first [`MAX_GUIDED_LIGHTS`] of them).
    pub(crate) fn new(scene: &crate::world::Scene) -> LightGuide {
        let mut volumes = [None; MAX_GUIDED_LIGHTS];
        let mut count = 0;
        let mut points_only = true;
        let (lo, hi) = scene.bounds;
        for light in &scene.lights {
            let Some(position) = light.point_position() else {
                continue;
            };
            if count == MAX_GUIDED_LIGHTS || scene.medium_at(position).is_none() {
                continue;
            }
            let radius = match light {
                // The root mean square distance from the light to the
                // points of the scene's bounds: about half the farthest
                // corner's, which puts twice the guided directions near the
                // lamp, where the fog glows and surfaces are lit brightest.
                // On bench/scenes/fog_point.json (48 px, 8 renders of 64
                // spp, Sobol) the relative MSE fell from 4.73e-3 (farthest
                // corner) to 3.96e-3; radii of 0.25, 0.35, 0.5 and 0.7 of
                // the farthest corner's gave 4.01e-3, 3.75e-3, 3.91e-3 and
                // 4.24e-3.
                Light::Point(_) => rms_distance_to_box(position, lo, hi),
                // Out to the farthest corner of the scene's bounds.
                _ => (position - lo).abs().max((position - hi).abs()).length(),
            };
            if let Some(v) = LightCone::new(light, radius) {
                volumes[count] = Some(v);
                count += 1;
                points_only &= matches!(light, Light::Point(_));
            }
        }
        let lit = LitSurfaces::new(&scene.objects, &scene.lights, |p| scene.medium_at(p).is_some());
        // Only where every guided light is a point light: the estimates know
        // point lights alone, and a spot's guide keeps its whole share (its
        // apex tail). On the built-in default scene (a spot and a dim point
        // lamp in haze) the lit objects took 30% of the spot's guide and the
        // image mean's standard error over 32 renders rose 1.3x.
        let lit_share = if lit.is_active() && count > 0 && points_only { LIT_SHARE } else { 0.0 };
        LightGuide { volumes, count, points_only, lit, lit_share }
    }

    /// The share of directions toward lit objects at `x` and the lit
    /// guide's normalization there (both 0 where it has nothing to aim at).
    #[inline]
    fn lit_at(&self, x: Vec3) -> (f32, f32) {
        if self.lit_share > 0.0 {
            let total = self.lit.total(x);
            if total > 0.0 {
                return (self.lit_share, total);
            }
        }
        (0.0, 0.0)
    }

    /// Whether every guided light is a point light (true when none is guided).
    #[inline]
    pub(crate) fn points_only(&self) -> bool {
        self.points_only
    }

    /// Whether some light is guided toward.
    #[inline]
    pub(crate) fn is_active(&self) -> bool {
        self.count > 0
    }

    /// A unit direction from `x` toward a point of one guided light's volume
    /// (chosen uniformly with `u_light`); `None` when that point is `x`.
    pub(crate) fn sample(&self, x: Vec3, u_light: f32, u_dir: crate::math::Vec2, u_r: f32) -> Option<Vec3> {
        let (share, total) = self.lit_at(x);
        if u_light < share {
            return self.lit.sample(x, total, u_light / share, u_dir);
        }
        let u_light = (u_light - share) / (1.0 - share);
        let k = ((u_light * self.count as f32) as usize).min(self.count.saturating_sub(1));
        let to = self.volumes[k]?.sample(u_dir, u_r) - x;
        let length = to.length();
        (length > 1e-6 * (1.0 + x.abs().max_element())).then(|| to / length)
    }

    /// Solid-angle density (1/sr) of [`LightGuide::sample`] from `x` at `w`.
    pub(crate) fn pdf(&self, x: Vec3, w: Vec3) -> f32 {
        let sum: f32 = self.volumes[..self.count].iter().flatten().map(|v| v.direction_pdf(x, w)).sum();
        let lamps = sum / self.count.max(1) as f32;
        if self.lit_share > 0.0 {
            let (total, inside) = self.lit.density(x, w);
            if total > 0.0 {
                return (1.0 - self.lit_share) * lamps + self.lit_share * inside / total;
            }
        }
        lamps
    }
}

/// Root mean square distance from `p` to the points of the box `[lo, hi]`
/// (uniformly distributed): `sqrt(|p - c|^2 + sum_i size_i^2 / 12)`, `c`
/// the box's center.
fn rms_distance_to_box(p: Vec3, lo: Vec3, hi: Vec3) -> f32 {
    let size = hi - lo;
    ((p - 0.5 * (lo + hi)).length_squared() + size.length_squared() / 12.0).sqrt()
}
