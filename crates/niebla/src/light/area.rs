//! Area lights: shapes that emit a uniform radiance `L` (W/(sr m^2)) from
//! their front side, sampled by solid angle as seen from a receiving point
//! (pbrt-v4 section 12.2 `DiffuseAreaLight`, section 6.2.4 sphere sampling).
//!
//! Front sides: a rectangle's local +z side (the unit square `[-1, 1]^2` of
//! the local xy plane placed by its `Transform`, see
//! [`crate::geometry::Rectangle`]), and likewise a disk's
//! ([`crate::geometry::Disk`]); a sphere's outside; a mesh's shading-normal
//! side ([`MeshLight`]: the interpolated vertex normal, else the winding's
//! geometric normal, as Mitsuba 3). A two-sided light emits `L` from both
//! sides.
//!
//! Area-to-solid-angle conversions (light sampling's density and the MIS
//! density of a ray that hits the light) take the cosine to the geometric
//! normal, also on a mesh with vertex normals: a surface element `dA`
//! subtends `|cos theta_g| dA / d^2` steradians whatever its shading normal.
//!
//! Directions follow the crate convention: `wi` points from the receiver
//! toward the light, `w_out` leaves the emitting surface (toward the
//! receiver, so `w_out = -wi`).

use std::sync::Arc;

use super::mesh_light::MeshLight;
use super::LightError;
use crate::color::Rgb;
use crate::geometry::{sphere_at, Disk, Rectangle, Sphere, SurfaceHit, TransformMotion};
use crate::math::{safe_sqrt, spherical_direction, Frame, Ray, Vec2, Vec3, PI};
use crate::sampling::sample_uniform_sphere;

/// The emitting shape of an [`AreaLight`] (world space).
#[derive(Clone, Debug)]
pub enum AreaShape {
    /// A parallelogram: the transformed square `[-1, 1]^2`, front side local +z.
    Rectangle(Rectangle),
    /// An ellipse: the transformed unit disk, front side local +z.
    Disk(Disk),
    /// A sphere, front side outside.
    Sphere(Sphere),
    /// A triangle mesh, front side that of its shading normal, solid angle
    /// by its geometric normal (shared: the mesh's triangle distribution is
    /// built once).
    Mesh(Arc<MeshLight>),
}

impl AreaShape {
    /// World-space surface area (the parallelogram's or ellipse's area; `4 pi r^2`).
    #[inline]
    pub fn area(&self) -> f32 {
        match self {
            AreaShape::Rectangle(r) => r.area(),
            AreaShape::Disk(d) => d.area(),
            AreaShape::Sphere(s) => 4.0 * PI * s.radius * s.radius,
            AreaShape::Mesh(m) => m.area(),
        }
    }

    /// Nearest intersection with `t` in `(t_min, t_max)`; the normal is the
    /// front-side normal (rectangle and disk local +z, sphere outward; a
    /// mesh's geometric normal `n`, its front-side normal is `ns`).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<SurfaceHit> {
        match self {
            AreaShape::Rectangle(r) => r.intersect(ray, t_min, t_max),
            AreaShape::Disk(d) => d.intersect(ray, t_min, t_max),
            AreaShape::Sphere(s) => s.intersect(ray, t_min, t_max),
            AreaShape::Mesh(m) => m.intersect(ray, t_min, t_max),
        }
    }

    /// The front-side normal of a hit `hit` on this shape, which decides the
    /// emitting side: the shading normal `ns` of a mesh (Mitsuba 3's
    /// emitting side), else `n`. Not the normal of the area-to-solid-angle
    /// conversion, which is always the geometric `n`.
    #[inline]
    pub fn front_normal(&self, hit: &SurfaceHit) -> Vec3 {
        match self {
            AreaShape::Mesh(_) => hit.ns,
            _ => hit.n,
        }
    }

    /// True for a mesh, which may hide parts of itself from a receiver (a
    /// shadow ray toward one of its points must test the mesh itself).
    #[inline]
    pub fn is_mesh(&self) -> bool {
        matches!(self, AreaShape::Mesh(_))
    }
}

/// How a moving [`AreaLight`] gets from its `shape` (time 0) to its pose at
/// time 1 (frames); see [`crate::geometry::MovingShape`] for the
/// interpolation.
#[derive(Clone, Copy, Debug)]
pub enum AreaMotion {
    /// A sphere's center and radius at time 1 (interpolated linearly).
    Sphere(Sphere),
    /// A rectangle's or disk's transform, from time 0 to time 1.
    Transform(TransformMotion),
}

/// A sampled point on an area light as seen from a receiver.
#[derive(Clone, Copy, Debug)]
pub struct AreaLightSample {
    /// Point on the light (world).
    pub p: Vec3,
    /// Unit front-side normal of the light at `p` (world), which decides
    /// the emitting side.
    pub n: Vec3,
    /// Unit geometric normal of the light at `p` (world; `n` itself except
    /// on a mesh with vertex normals), whose `|cos|` converts area to solid
    /// angle.
    pub ng: Vec3,
    /// Unit direction from the receiver toward `p` (world).
    pub wi: Vec3,
    /// Distance from the receiver to `p`.
    pub distance: f32,
    /// Radiance leaving `p` toward the receiver (non-zero), W/(sr m^2).
    pub li: Rgb,
    /// Density of `wi` per steradian at the receiver, equal to
    /// [`AreaLight::pdf_li`] of `wi`.
    pub pdf: f32,
}

/// A diffuse area emitter: uniform radiance `radiance` (W/(sr m^2), linear
/// RGB) leaving the front side of `shape`, and the back side too when
/// `two_sided`.
///
/// ```
/// use niebla::color::Rgb;
/// use niebla::geometry::Sphere;
/// use niebla::light::{AreaLight, AreaShape};
/// use niebla::math::{Vec2, Vec3};
/// let sphere = Sphere::new(Vec3::new(0.0, 0.0, 4.0), 1.0);
/// let light = AreaLight::new(AreaShape::Sphere(sphere), Rgb::splat(2.0), false).unwrap();
/// let s = light.sample_li(Vec3::ZERO, Vec2::new(0.3, 0.7)).unwrap();
/// assert_eq!(s.li, Rgb::splat(2.0));
/// assert!((light.pdf_li(Vec3::ZERO, s.wi) - s.pdf).abs() < 1e-4 * s.pdf);
/// ```
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// The emitting surface.
    pub shape: AreaShape,
    /// Emitted radiance, W/(sr m^2), each channel finite and >= 0.
    pub radiance: Rgb,
    /// Emit from the back side (rectangle local -z, sphere inside) as well.
    pub two_sided: bool,
    /// The light's motion during the shutter (`None`: still). A moving
    /// light is sampled and intersected as the still light
    /// [`AreaLight::at_time`] at the camera sample's time, so its estimates
    /// stay unbiased at every instant.
    /// Boxed: most lights do not move, and the pose pair would double the
    /// size of every [`super::Light`].
    pub motion: Option<Box<AreaMotion>>,
}

impl AreaLight {
    /// An area light, checking that the radiance is finite and non-negative
    /// and the shape is not degenerate (positive, finite radius or area).
    pub fn new(shape: AreaShape, radiance: Rgb, two_sided: bool) -> Result<AreaLight, LightError> {
        let source_name = || "area light".to_string();
        for c in 0..3 {
            let value = radiance.0[c];
            if !value.is_finite() || value < 0.0 {
                return Err(LightError::InvalidParameter { source_name: source_name(), name: "radiance", value });
            }
        }
        if let AreaShape::Sphere(s) = &shape {
            if !(s.radius > 0.0) || !s.radius.is_finite() {
                return Err(LightError::InvalidParameter {
                    source_name: source_name(),
                    name: "radius",
                    value: s.radius,
                });
            }
        }
        let area = shape.area();
        if !(area > 0.0) || !area.is_finite() {
            return Err(LightError::InvalidParameter { source_name: source_name(), name: "area", value: area });
        }
        Ok(AreaLight { shape, radiance, two_sided, motion: None })
    }

    /// The still light in its pose at `time` (frames); `None` for a light
    /// without motion (which is its own pose at every time).
    #[inline]
    pub fn at_time(&self, time: f32) -> Option<AreaLight> {
        let motion = self.motion.as_deref()?;
        let shape = match (motion, &self.shape) {
            (AreaMotion::Sphere(end), AreaShape::Sphere(start)) => AreaShape::Sphere(sphere_at(start, end, time)),
            (AreaMotion::Transform(m), AreaShape::Rectangle(_)) => AreaShape::Rectangle(Rectangle::new(m.at(time))),
            (AreaMotion::Transform(m), AreaShape::Disk(_)) => AreaShape::Disk(Disk::new(m.at(time))),
            // The scene builder pairs motions with their shapes only.
            _ => self.shape.clone(),
        };
        Some(AreaLight { shape, radiance: self.radiance, two_sided: self.two_sided, motion: None })
    }

    /// World-space area of the emitting surface.
    #[inline]
    pub fn area(&self) -> f32 {
        self.shape.area()
    }

    /// Total emitted power, W per channel: `pi L area` per emitting side.
    #[inline]
    pub fn power(&self) -> Rgb {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        self.radiance * (PI * self.area() * sides)
    }

    /// Radiance leaving a point of the light with front-side normal `n` in
    /// the unit direction `w_out` (away from the surface): `radiance` on the
    /// front side (`n . w_out > 0`), on the back side only when two-sided.
    #[inline]
    pub fn le(&self, n: Vec3, w_out: Vec3) -> Rgb {
        if self.two_sided || n.dot(w_out) > 0.0 {
            self.radiance
        } else {
            Rgb::ZERO
        }
    }

    /// Sample a point on the light as seen from `p_ref` with `u` in [0, 1)^2.
    /// Sphere, `p_ref` outside: uniform over the cone of directions that see
    /// the sphere (pbrt-v4 spherical-cap sampling); inside: uniform by area.
    /// Rectangle, disk and mesh: uniform by area (a mesh's triangle chosen by
    /// area). The pdf is converted to solid angle with the cosine to the
    /// geometric normal (also on a mesh with vertex normals); the front-side
    /// normal (a mesh's shading normal) decides only whether `p` emits
    /// toward `p_ref`.
    /// `None` when the point emits nothing toward `p_ref` (its back side of a
    /// one-sided light) or the density is degenerate.
    pub fn sample_li(&self, p_ref: Vec3, u: Vec2) -> Option<AreaLightSample> {
        let (p, n, ng, pdf) = match &self.shape {
            AreaShape::Sphere(s) if (p_ref - s.center).length_squared() > s.radius * s.radius => {
                let (p, n, pdf) = sample_sphere_cone(s, p_ref, u);
                (p, n, n, pdf)
            }
            _ => {
                // Uniform by area, then to solid angle: pdf_A d^2 / |cos_g|.
                let (p, n, ng) = self.sample_area(u);
                let to = p - p_ref;
                let d2 = to.length_squared();
                let cos_light = ng.dot(to).abs() / d2.sqrt();
                (p, n, ng, d2 / (cos_light * self.area()))
            }
        };
        let to = p - p_ref;
        let distance = to.length();
        if !(distance > 0.0) || !(pdf > 0.0) || !pdf.is_finite() {
            return None;
        }
        let wi = to / distance;
        let li = self.le(n, -wi);
        if li.is_black() {
            return None;
        }
        Some(AreaLightSample { p, n, ng, wi, distance, li, pdf })
    }

    /// Density per steradian with which [`AreaLight::sample_li`] at `p_ref`
    /// generates the unit direction `wi` (whether or not that side emits), 0
    /// when the ray from `p_ref` along `wi` misses the light.
    pub fn pdf_li(&self, p_ref: Vec3, wi: Vec3) -> f32 {
        if let AreaShape::Sphere(s) = &self.shape {
            let to_center = s.center - p_ref;
            let d2 = to_center.length_squared();
            if d2 > s.radius * s.radius {
                // Uniform in the cone: test membership by sin^2 of the angle
                // to the axis (stable for small cones), with a relative slack
                // of 1e-5 for directions rounded off the silhouette.
                let sin2_theta_max = s.radius * s.radius / d2;
                let axis = to_center / d2.sqrt();
                let inside = wi.dot(axis) > 0.0 && wi.cross(axis).length_squared() <= sin2_theta_max * (1.0 + 1e-5);
                return if inside { 1.0 / (2.0 * PI * one_minus_cos_theta_max(sin2_theta_max)) } else { 0.0 };
            }
        }
        // Area sampling: intersect and convert with the geometric normal.
        let Some(hit) = self.shape.intersect(&Ray::new(p_ref, wi), 0.0, f32::INFINITY) else {
            return 0.0;
        };
        let cos_light = hit.n.dot(wi).abs();
        if cos_light == 0.0 {
            return 0.0;
        }
        hit.t * hit.t / (cos_light * self.area())
    }

    /// A point uniformly distributed by area, its unit front-side normal
    /// (which decides the emitting side) and its unit geometric normal
    /// (the same vector except on a mesh with vertex normals).
    #[inline]
    pub fn sample_area(&self, u: Vec2) -> (Vec3, Vec3, Vec3) {
        match &self.shape {
            AreaShape::Rectangle(r) => {
                // An affine map takes uniform points of the square to uniform points.
                let local = Vec3::new(2.0 * u.x - 1.0, 2.0 * u.y - 1.0, 0.0);
                (r.transform.point_to_world(local), r.normal, r.normal)
            }
            AreaShape::Disk(d) => (d.sample_point(u), d.normal, d.normal),
            AreaShape::Sphere(s) => {
                let n = sample_uniform_sphere(u);
                (s.center + s.radius * n, n, n)
            }
            AreaShape::Mesh(m) => m.sample_area(u),
        }
    }
}

/// `1 - cos(theta_max)` from `sin^2(theta_max)`, computed as
/// `sin^2 / (1 + cos)`, which has no cancellation for small cones.
#[inline]
fn one_minus_cos_theta_max(sin2_theta_max: f32) -> f32 {
    sin2_theta_max / (1.0 + safe_sqrt(1.0 - sin2_theta_max))
}

/// Uniform direction in the cone from `p_ref` (outside) that sees sphere `s`,
/// returned as the first point the direction hits, its outward normal and
/// the cone's density `1 / (2 pi (1 - cos(theta_max)))` (pbrt-v4
/// `Sphere::Sample(ctx, u)`: sample `theta` in the cone, then find the angle
/// `alpha` at the center so that the point lies on the visible cap).
///
/// pbrt-v4 switches below 1.5 degrees to `sin^2(theta) = u sin^2(theta_max)`,
/// whose density differs from the pdf it reports by up to
/// `sin^2(theta_max) / 2`; here `1 - cos(theta) = u (1 - cos(theta_max))` and
/// `sin^2(theta) = t (2 - t)` with `t = 1 - cos(theta)` are exact and free of
/// cancellation at any size.
fn sample_sphere_cone(s: &Sphere, p_ref: Vec3, u: Vec2) -> (Vec3, Vec3, f32) {
    let to_center = s.center - p_ref;
    let dc = to_center.length();
    let sin_theta_max = s.radius / dc;
    let sin2_theta_max = sin_theta_max * sin_theta_max;
    let one_minus_cos_max = one_minus_cos_theta_max(sin2_theta_max);
    let t = u.x * one_minus_cos_max;
    let (cos_theta, sin2_theta) = (1.0 - t, t * (2.0 - t));
    // Angle at the center between the axis (center -> p_ref) and the point.
    let cos_alpha =
        sin2_theta / sin_theta_max + cos_theta * safe_sqrt(1.0 - sin2_theta / (sin_theta_max * sin_theta_max));
    let sin_alpha = safe_sqrt(1.0 - cos_alpha * cos_alpha);
    let w = spherical_direction(sin_alpha, cos_alpha, 2.0 * PI * u.y);
    let frame = Frame::from_z(to_center / dc);
    let n = frame.to_world(-w).normalize();
    let p = s.center + s.radius * n;
    (p, n, 1.0 / (2.0 * PI * one_minus_cos_max))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Transform;
    use crate::sampling::PixelSampler;

    #[test]
    fn cone_samples_lie_on_the_visible_cap() {
        // Every sampled point faces p_ref (n . (p_ref - p) >= 0, to rounding)
        // and lies on the sphere, for a near and a far (small-cone) sphere.
        for dc in [1.5f32, 60.0] {
            let s = Sphere::new(Vec3::new(0.0, dc, 0.0), 1.0);
            let mut rng = PixelSampler::from_key(7);
            for _ in 0..10_000 {
                let (p, n, _) = sample_sphere_cone(&s, Vec3::ZERO, rng.next_2d());
                assert!(((p - s.center).length() - 1.0).abs() < 1e-4);
                assert!(n.dot(-p) >= -1e-3 * dc, "back-facing point at d = {dc}");
            }
        }
    }

    #[test]
    fn power_is_pi_l_area_per_side() {
        let t = Transform::from_components(Vec3::new(2.0, 3.0, 1.0), Vec3::ZERO, Vec3::ZERO).unwrap();
        let one = AreaLight::new(AreaShape::Rectangle(Rectangle::new(t)), Rgb::splat(1.5), false).unwrap();
        assert!((one.area() - 24.0).abs() < 1e-4);
        assert!((one.power().g() - PI * 1.5 * 24.0).abs() < 1e-3);
        let two = AreaLight { two_sided: true, ..one.clone() };
        assert!((two.power().g() - 2.0 * PI * 1.5 * 24.0).abs() < 1e-3);
        assert!(AreaLight::new(one.shape, Rgb::new(1.0, -1.0, 0.0), false).is_err());
        let bad = AreaShape::Sphere(Sphere::new(Vec3::ZERO, 0.0));
        assert!(AreaLight::new(bad, Rgb::ONE, false).is_err());
    }

    #[test]
    fn le_is_zero_behind_a_one_sided_light() {
        let l = AreaLight {
            shape: AreaShape::Sphere(Sphere::new(Vec3::ZERO, 1.0)),
            radiance: Rgb::ONE,
            two_sided: false,
            motion: None,
        };
        assert_eq!(l.le(Vec3::Z, Vec3::new(0.0, 0.6, 0.8)), Rgb::ONE);
        assert_eq!(l.le(Vec3::Z, -Vec3::Z), Rgb::ZERO);
        assert_eq!(AreaLight { two_sided: true, ..l.clone() }.le(Vec3::Z, -Vec3::Z), Rgb::ONE);
        // From inside a one-sided sphere nothing is visible.
        assert!(l.sample_li(Vec3::new(0.1, 0.2, 0.0), Vec2::new(0.3, 0.4)).is_none());
    }
}
