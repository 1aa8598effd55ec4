//! Shapes that move during the shutter: a pose at time 0 and one at time 1
//! (frames), interpolated linearly in time (and extrapolated outside
//! `[0, 1]`), and intersected in their pose at the ray's time.
//!
//! Spheres interpolate center and radius, boxes their two corners (both
//! exactly linear, so the shape at time `t` is again a sphere or a box).
//! Shapes placed by a `to_world` transform (rectangles, disks, mesh
//! instances) decompose each transform into translation, rotation and
//! scale (`T R S`) and interpolate translation and scale linearly and the
//! rotation by spherical linear interpolation of unit quaternions (Shoemake
//! 1985, "Animating rotation with quaternion curves"), as pbrt-v4's
//! `AnimatedTransform` and Mitsuba 3's `AnimatedTransform` do: a matrix lerp
//! would shrink a rotating object halfway through a turn (a 90 degree turn
//! lerped passes through a matrix scaled by `cos 45 = 0.71`), slerp keeps
//! its shape rigid and turns it at constant angular speed.

use glam::{Affine3A, Mat3, Quat, Vec3};

use super::{AxisAlignedBox, Disk, MeshInstance, PrimitiveHit, Rectangle, Shape, Sphere, SurfaceHit, Transform};
use crate::math::{Ray, Vec2};

/// An affine local-to-world map decomposed as translation times rotation
/// times (per-axis) scale, `x -> translation + rotation * (scale * x)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Per-axis scale (the x component carries a mirroring's sign).
    pub scale: Vec3,
    /// Unit quaternion of the rotation.
    pub rotation: Quat,
    /// Translation.
    pub translation: Vec3,
}

impl Pose {
    /// The decomposition of `a`; `None` when `a` is singular, not finite or
    /// has a shear (its recomposition differs from `a` by more than 1e-4 of
    /// its largest axis), which no translation-rotation-scale triple gives.
    pub fn from_affine(a: &Affine3A) -> Option<Pose> {
        let det = a.matrix3.determinant();
        if !det.is_finite() || det.abs() < 1e-20 || !a.translation.is_finite() {
            return None;
        }
        let (scale, rotation, translation) = a.to_scale_rotation_translation();
        if !scale.is_finite() || !rotation.is_finite() || scale.cmpeq(Vec3::ZERO).any() {
            return None;
        }
        let pose = Pose { scale, rotation: rotation.normalize(), translation };
        let back = pose.to_affine();
        let size = a.matrix3.x_axis.length().max(a.matrix3.y_axis.length()).max(a.matrix3.z_axis.length());
        let off = (back.matrix3.x_axis - a.matrix3.x_axis)
            .length()
            .max((back.matrix3.y_axis - a.matrix3.y_axis).length())
            .max((back.matrix3.z_axis - a.matrix3.z_axis).length());
        (off <= 1e-4 * size).then_some(pose)
    }

    /// The affine map `T R S`.
    #[inline]
    pub fn to_affine(&self) -> Affine3A {
        Affine3A::from_mat3_translation(
            Mat3::from_quat(self.rotation) * Mat3::from_diagonal(self.scale),
            self.translation,
        )
    }
}

/// Spherical linear interpolation of unit quaternions `a` (at 0) and `b`
/// (at 1, on `a`'s hemisphere) at `s` (any real: extrapolates at the same
/// angular speed); normalized linear interpolation where they are nearly
/// equal.
#[inline]
fn slerp(a: Quat, b: Quat, s: f32) -> Quat {
    let cos = a.dot(b).clamp(-1.0, 1.0);
    if cos > 0.9995 {
        return (a * (1.0 - s) + b * s).normalize();
    }
    let theta = cos.acos();
    let sin = theta.sin();
    let (wa, wb) = (((1.0 - s) * theta).sin() / sin, (s * theta).sin() / sin);
    (a * wa + b * wb).normalize()
}

/// Why a shape's motion cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MotionError {
    /// A pose has a shear, is singular or not finite.
    #[error(
        "the transform at time {time} cannot be split into translation, rotation and scale (it is singular, \
         not finite or sheared); a moving shape's transforms must be made of scale, rotations and translation"
    )]
    NotDecomposable {
        /// 0 (the shape's own transform) or 1 (the motion's).
        time: f32,
    },
    /// The shape collapses (a zero or sign-changing scale, a radius or box
    /// size reaching zero) at an instant the shutter is open.
    #[error("the shape is degenerate at time {time} (frames), which the shutter [{open}, {close}] covers: {what}")]
    Degenerate {
        /// The instant.
        time: f32,
        /// Shutter open.
        open: f32,
        /// Shutter close.
        close: f32,
        /// What collapses.
        what: String,
    },
}

/// The motion of a transform between two poses (time 0 and time 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TransformMotion {
    /// Pose at time 0.
    pub start: Pose,
    /// Pose at time 1 (its rotation on the start's hemisphere, so that the
    /// interpolation takes the shorter way round).
    pub end: Pose,
}

impl TransformMotion {
    /// The motion from `to_world0` (time 0) to `to_world1` (time 1).
    pub fn new(to_world0: &Affine3A, to_world1: &Affine3A) -> Result<TransformMotion, MotionError> {
        let start = Pose::from_affine(to_world0).ok_or(MotionError::NotDecomposable { time: 0.0 })?;
        let mut end = Pose::from_affine(to_world1).ok_or(MotionError::NotDecomposable { time: 1.0 })?;
        if start.rotation.dot(end.rotation) < 0.0 {
            end.rotation = -end.rotation;
        }
        Ok(TransformMotion { start, end })
    }

    /// The pose at `time` (frames).
    #[inline]
    pub fn pose_at(&self, time: f32) -> Pose {
        Pose {
            scale: self.start.scale.lerp(self.end.scale, time),
            rotation: slerp(self.start.rotation, self.end.rotation, time),
            translation: self.start.translation.lerp(self.end.translation, time),
        }
    }

    /// The transform at `time` (frames).
    #[inline]
    pub fn at(&self, time: f32) -> Transform {
        let a = self.pose_at(time).to_affine();
        Transform { to_world: a, to_local: a.inverse() }
    }

    /// An error unless every scale keeps its sign (so never reaches zero)
    /// over `shutter` (scale is linear in time: its ends decide).
    pub fn check_shutter(&self, shutter: [f32; 2]) -> Result<(), MotionError> {
        for time in shutter {
            let s = self.pose_at(time).scale;
            let flipped = (s * self.start.scale.signum()).cmple(Vec3::ZERO).any();
            if flipped || !s.is_finite() {
                return Err(MotionError::Degenerate {
                    time,
                    open: shutter[0],
                    close: shutter[1],
                    what: format!("its scale is {s} there, from {} at time 0", self.start.scale),
                });
            }
        }
        Ok(())
    }

    /// A world box holding every point `T(t) + R(t) S(t) q` for `q` in the
    /// local box `local` and `t` in `shutter`. Without a turn (equal
    /// rotations) each point moves on a segment, so the boxes of the poses
    /// at the shutter's ends bound it exactly; with a turn, a point stays
    /// within `rho = max |S(t) q|` of the moving origin `T(t)` (`rho` is
    /// taken at the shutter's ends and the local box's corners, where the
    /// convex `|S(t) q|` is largest), a conservative box.
    pub fn swept_bounds(&self, local: &AxisAlignedBox, shutter: [f32; 2]) -> (Vec3, Vec3) {
        let corners = (0..8).map(|i| {
            Vec3::new(
                if i & 1 == 0 { local.min.x } else { local.max.x },
                if i & 2 == 0 { local.min.y } else { local.max.y },
                if i & 4 == 0 { local.min.z } else { local.max.z },
            )
        });
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        if self.start.rotation == self.end.rotation {
            for time in shutter {
                let a = self.pose_at(time).to_affine();
                for q in corners.clone() {
                    let p = a.transform_point3(q);
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
            }
        } else {
            let mut rho = 0.0f32;
            for time in shutter {
                let s = self.pose_at(time).scale;
                for q in corners.clone() {
                    rho = rho.max((s * q).length());
                }
            }
            for time in shutter {
                let t = self.pose_at(time).translation;
                lo = lo.min(t - Vec3::splat(rho));
                hi = hi.max(t + Vec3::splat(rho));
            }
        }
        pad(lo, hi)
    }
}

/// A box grown by a relative `1e-5` of its coordinates' magnitude, so
/// rounding in the poses computed per ray stays inside it.
fn pad(lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let e = Vec3::splat(1e-5 * lo.abs().max(hi.abs()).max_element().max(1.0));
    (lo - e, hi + e)
}

/// The sphere at `time` between `start` (time 0) and `end` (time 1); its
/// uv frame stays `start`'s ([`Sphere::rotation`]).
#[inline]
pub fn sphere_at(start: &Sphere, end: &Sphere, time: f32) -> Sphere {
    Sphere::new(start.center.lerp(end.center, time), start.radius + (end.radius - start.radius) * time)
        .with_rotation(start.rotation)
}

/// The box at `time` between `start` (time 0) and `end` (time 1).
#[inline]
pub fn box_at(start: &AxisAlignedBox, end: &AxisAlignedBox, time: f32) -> AxisAlignedBox {
    AxisAlignedBox { min: start.min.lerp(end.min, time), max: start.max.lerp(end.max, time) }
}

/// How a [`MovingShape`] moves: its poses at time 0 and time 1.
#[derive(Clone, Debug)]
pub enum Motion {
    /// Center and radius interpolated linearly.
    Sphere {
        /// At time 0.
        start: Sphere,
        /// At time 1.
        end: Sphere,
    },
    /// Corners interpolated linearly.
    Box {
        /// At time 0.
        start: AxisAlignedBox,
        /// At time 1.
        end: AxisAlignedBox,
    },
    /// A rectangle placed by the moving transform.
    Rectangle(TransformMotion),
    /// A disk placed by the moving transform.
    Disk(TransformMotion),
    /// A mesh instance (its own transform is the pose at time 0) placed by
    /// the moving transform.
    Mesh(MeshInstance, TransformMotion),
}

/// A shape that moves during the shutter (see the module documentation),
/// with its box over the whole shutter.
#[derive(Clone, Debug)]
pub struct MovingShape {
    /// The poses.
    pub motion: Motion,
    /// The still shape at time 0 (for what is asked without a time: inside
    /// tests, volume, closedness).
    pub at_zero: Shape,
    /// World box of everything the shape sweeps over `shutter`.
    bounds: (Vec3, Vec3),
}

impl MovingShape {
    /// A moving shape seen through the shutter `[open, close]` (frames):
    /// an error when it is degenerate at an instant the shutter covers.
    pub fn new(motion: Motion, shutter: [f32; 2]) -> Result<MovingShape, MotionError> {
        let degenerate =
            |time: f32, what: String| MotionError::Degenerate { time, open: shutter[0], close: shutter[1], what };
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let mut grow = |(a, b): (Vec3, Vec3)| {
            lo = lo.min(a);
            hi = hi.max(b);
        };
        let at_zero = match &motion {
            Motion::Sphere { start, end } => {
                for time in shutter {
                    let s = sphere_at(start, end, time);
                    if !(s.radius > 0.0) || !s.radius.is_finite() || !s.center.is_finite() {
                        return Err(degenerate(time, format!("its radius is {} there", s.radius)));
                    }
                    grow(Shape::Sphere(s).bounds());
                }
                Shape::Sphere(*start)
            }
            Motion::Box { start, end } => {
                for time in shutter {
                    let b = box_at(start, end, time);
                    if !b.max.cmpgt(b.min).all() || !b.min.is_finite() || !b.max.is_finite() {
                        return Err(degenerate(time, format!("its corners are min {} and max {} there", b.min, b.max)));
                    }
                    grow((b.min, b.max));
                }
                Shape::Box(*start)
            }
            Motion::Rectangle(m) | Motion::Disk(m) => {
                m.check_shutter(shutter)?;
                let square = AxisAlignedBox { min: Vec3::new(-1.0, -1.0, 0.0), max: Vec3::new(1.0, 1.0, 0.0) };
                grow(m.swept_bounds(&square, shutter));
                match motion {
                    Motion::Rectangle(_) => Shape::Rectangle(Rectangle::new(m.at(0.0))),
                    _ => Shape::Disk(Disk::new(m.at(0.0))),
                }
            }
            Motion::Mesh(instance, m) => {
                m.check_shutter(shutter)?;
                if let Some(local) = instance.mesh.bounds() {
                    grow(m.swept_bounds(&local, shutter));
                }
                Shape::Mesh(instance.clone())
            }
        };
        if !lo.cmple(hi).all() {
            (lo, hi) = (Vec3::ZERO, Vec3::ZERO);
        }
        Ok(MovingShape { motion, at_zero, bounds: (lo, hi) })
    }

    /// The shape at `time` (frames), for all but meshes (`None`), whose
    /// instances are placed by `MovingShape::mesh_pose` instead.
    #[inline]
    pub fn still_at(&self, time: f32) -> Option<Shape> {
        Some(match &self.motion {
            Motion::Sphere { start, end } => Shape::Sphere(sphere_at(start, end, time)),
            Motion::Box { start, end } => Shape::Box(box_at(start, end, time)),
            Motion::Rectangle(m) => Shape::Rectangle(Rectangle::new(m.at(time))),
            Motion::Disk(m) => Shape::Disk(Disk::new(m.at(time))),
            Motion::Mesh(..) => return None,
        })
    }

    /// A moving mesh's instance and its transform at `time`.
    #[inline]
    fn mesh_pose(&self, time: f32) -> Option<(&MeshInstance, Transform)> {
        match &self.motion {
            Motion::Mesh(instance, m) => Some((instance, m.at(time))),
            _ => None,
        }
    }

    /// [`Shape::hit_t`] in the pose at the ray's time.
    #[inline]
    pub fn hit_t(&self, ray: &Ray, inv: Vec3, t_min: f32, t_max: f32) -> Option<PrimitiveHit> {
        match self.still_at(ray.time) {
            Some(shape) => shape.hit_t(ray, inv, t_min, t_max),
            None => {
                let (instance, pose) = self.mesh_pose(ray.time)?;
                instance.hit_posed(&pose, ray, t_min, t_max)
            }
        }
    }

    /// [`Shape::occludes`] in the pose at the ray's time.
    #[inline]
    pub fn occludes(&self, ray: &Ray, inv: Vec3, t_min: f32, t_max: f32) -> bool {
        match self.still_at(ray.time) {
            Some(shape) => shape.occludes(ray, inv, t_min, t_max),
            None => self.mesh_pose(ray.time).is_some_and(|(m, pose)| m.occluded_posed(&pose, ray, t_min, t_max)),
        }
    }

    /// [`Shape::surface_at`] in the pose at the ray's time.
    #[inline]
    pub fn surface_at(&self, ray: &Ray, hit: &PrimitiveHit) -> SurfaceHit {
        match self.still_at(ray.time) {
            Some(shape) => shape.surface_at(ray, hit),
            None => {
                let (instance, pose) = self.mesh_pose(ray.time).expect("a moving shape is a mesh when not still");
                instance.surface_at_posed(&pose, ray, hit)
            }
        }
    }

    /// [`Shape::uv`] of a hit found at `time`.
    pub fn uv(&self, surface: &SurfaceHit, local: &PrimitiveHit, time: f32) -> Vec2 {
        match self.still_at(time) {
            Some(shape) => shape.uv(surface, local, time),
            None => self.at_zero.uv(surface, local, time),
        }
    }

    /// [`Shape::dpdu`] of a hit found at `time`, in the pose at `time`.
    pub fn dpdu(&self, surface: &SurfaceHit, local: &PrimitiveHit, time: f32) -> Vec3 {
        match self.still_at(time) {
            Some(shape) => shape.dpdu(surface, local, time),
            None => match self.mesh_pose(time) {
                Some((instance, pose)) => instance.dpdu_by(&pose, local, surface.n),
                None => crate::math::Frame::from_z(surface.n).x,
            },
        }
    }

    /// World box of everything the shape sweeps while the shutter is open.
    #[inline]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poses_round_trip_and_shear_is_refused() {
        let t = Transform::from_components(Vec3::new(2.0, -0.5, 3.0), Vec3::new(10.0, 20.0, 30.0), Vec3::X).unwrap();
        let p = Pose::from_affine(&t.to_world).unwrap();
        let back = p.to_affine();
        assert!((back.matrix3.x_axis - t.to_world.matrix3.x_axis).length() < 1e-5);
        assert!((back.translation - t.to_world.translation).length() < 1e-6);
        let shear = Affine3A::from_mat3(Mat3::from_cols(Vec3::X, Vec3::new(0.5, 1.0, 0.0), Vec3::Z));
        assert!(Pose::from_affine(&shear).is_none());
    }

    /// Slerp turns at constant speed: a 90 degree turn about z is at 45
    /// degrees halfway, at 135 degrees at time 1.5, and keeps unit scale
    /// (a matrix lerp would give 0.707 at the middle).
    #[test]
    fn rotation_is_interpolated_rigidly_at_constant_speed() {
        let a = Transform::from_components(Vec3::ONE, Vec3::ZERO, Vec3::ZERO).unwrap();
        let b = Transform::from_components(Vec3::ONE, Vec3::new(0.0, 0.0, 90.0), Vec3::new(2.0, 0.0, 0.0)).unwrap();
        let m = TransformMotion::new(&a.to_world, &b.to_world).unwrap();
        for (time, deg) in [(0.5f32, 45.0f32), (1.5, 135.0), (-0.5, -45.0)] {
            let x = m.at(time).vector_to_world(Vec3::X);
            let want = Vec3::new(deg.to_radians().cos(), deg.to_radians().sin(), 0.0);
            assert!((x - want).length() < 1e-5, "t {time}: {x} vs {want}");
            assert!((m.at(time).point_to_world(Vec3::ZERO) - Vec3::new(2.0 * time, 0.0, 0.0)).length() < 1e-5);
        }
    }

    /// The swept box holds the shape at 1001 instants of the shutter, for a
    /// turning and a sliding rectangle.
    #[test]
    fn swept_bounds_hold_every_pose() {
        let a = Transform::from_components(Vec3::new(1.0, 2.0, 1.0), Vec3::ZERO, Vec3::new(0.0, 0.0, 3.0)).unwrap();
        for rot in [Vec3::ZERO, Vec3::new(30.0, 0.0, 120.0)] {
            let b = Transform::from_components(Vec3::new(2.0, 1.0, 1.0), rot, Vec3::new(1.0, -1.0, 3.0)).unwrap();
            let m = TransformMotion::new(&a.to_world, &b.to_world).unwrap();
            let shape = MovingShape::new(Motion::Rectangle(m), [-0.25, 1.0]).unwrap();
            let (lo, hi) = shape.bounds();
            for i in 0..=1000 {
                let time = -0.25 + 1.25 * i as f32 / 1000.0;
                let (a, b) = shape.still_at(time).unwrap().bounds();
                assert!(a.cmpge(lo).all() && b.cmple(hi).all(), "t {time}: {a} {b} outside {lo} {hi}");
            }
        }
    }

    #[test]
    fn degenerate_motions_are_errors() {
        let s0 = Sphere::new(Vec3::ZERO, 1.0);
        let s1 = Sphere::new(Vec3::X, 0.0);
        assert!(MovingShape::new(Motion::Sphere { start: s0, end: s1 }, [0.0, 0.5]).is_ok());
        assert!(matches!(
            MovingShape::new(Motion::Sphere { start: s0, end: s1 }, [0.0, 1.0]),
            Err(MotionError::Degenerate { time, .. }) if time == 1.0
        ));
        let a = Transform::from_components(Vec3::ONE, Vec3::ZERO, Vec3::ZERO).unwrap();
        let b = Transform::from_components(Vec3::new(-1.0, 1.0, 1.0), Vec3::ZERO, Vec3::ZERO).unwrap();
        let m = TransformMotion::new(&a.to_world, &b.to_world).unwrap();
        assert!(MovingShape::new(Motion::Disk(m), [0.0, 1.0]).is_err());
    }

    /// A sliding sphere is hit where the still sphere at the ray's time is.
    #[test]
    fn rays_hit_the_pose_at_their_time() {
        let start = Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0);
        let end = Sphere::new(Vec3::new(2.0, 0.0, 5.0), 1.0);
        let shape = Shape::Moving(Box::new(MovingShape::new(Motion::Sphere { start, end }, [0.0, 1.0]).unwrap()));
        let ray = |time| Ray::at_time(Vec3::new(1.0, 0.0, 0.0), Vec3::Z, time);
        let inv = Vec3::Z.recip();
        // At time 0.5 the center is at x = 1: a head-on hit at t = 4.
        let h = shape.hit_t(&ray(0.5), inv, 0.0, f32::INFINITY).unwrap();
        assert!((h.t - 4.0).abs() < 1e-5);
        assert!((shape.surface_at(&ray(0.5), &h).n + Vec3::Z).length() < 1e-5);
        // Texture coordinates come from the pose at the hit's time: off the
        // axis by 0.6 in y at time 0.5 the normal is (0, 0.6, -0.8), azimuth
        // u = 1/4 (the center at time 0 would give atan2(0.6, 1) / 2 pi).
        let off = Ray::at_time(Vec3::new(1.0, 0.6, 0.0), Vec3::Z, 0.5);
        let h = shape.hit_t(&off, inv, 0.0, f32::INFINITY).unwrap();
        let uv = shape.uv(&shape.surface_at(&off, &h), &h, 0.5);
        assert!((uv.x - 0.25).abs() < 1e-5 && (uv.y - (-0.8f32).acos() / crate::math::PI).abs() < 1e-5, "{uv}");
        // At time 0 the ray grazes x = 1: it hits at t = 5 only to rounding.
        assert!(shape.hit_t(&Ray::at_time(Vec3::new(1.2, 0.0, 0.0), Vec3::Z, 0.0), inv, 0.0, 1e9).is_none());
        assert!(shape.hit_t(&Ray::at_time(Vec3::new(1.2, 0.0, 0.0), Vec3::Z, 0.9), inv, 0.0, 1e9).is_some());
    }
}
