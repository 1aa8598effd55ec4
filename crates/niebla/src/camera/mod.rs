//! Cameras.

use crate::math::{Ray, Vec2, Vec3};
use crate::sampling::PixelSampler;

/// A camera that moves during the shutter: its eye, target and up at the
/// rendered frame (time 0) and one frame later (time 1), interpolated
/// linearly in time (frames) and extrapolated outside `[0, 1]`; the field of
/// view stays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraMotion {
    /// Eye at times 0 and 1.
    pub position: [Vec3; 2],
    /// Target at times 0 and 1.
    pub target: [Vec3; 2],
    /// Approximate up at times 0 and 1.
    pub up: [Vec3; 2],
}

/// A pinhole perspective camera looking from `position` toward a target.
///
/// Pixel `(x, y)` with row 0 at the top of the image; the camera's right is
/// increasing column. A camera sample passes through a uniformly random point
/// of its pixel and counts in that pixel alone (box filter). `fov_y` is the
/// full vertical field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerspectiveCamera {
    /// Eye position (world).
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit right vector.
    pub right: Vec3,
    /// Unit up vector, orthogonal to `forward` and `right`.
    pub up: Vec3,
    /// tan(fov_y / 2).
    pub tan_half_fov_y: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Shutter opening and closing instants, in frames relative to the
    /// rendered frame (`open <= close`); equal: no motion blur, every sample
    /// at that instant without drawing a number.
    pub shutter: [f32; 2],
    /// How the camera moves, if it does; the fields above are its pose at
    /// time 0.
    pub motion: Option<CameraMotion>,
}

impl PerspectiveCamera {
    /// A camera at `position` looking at `target` with approximate `up`, vertical
    /// field of view `fov_y_deg` in degrees. `None` if the frame is degenerate.
    pub fn look_at(
        position: Vec3,
        target: Vec3,
        up: Vec3,
        fov_y_deg: f32,
        width: u32,
        height: u32,
    ) -> Option<PerspectiveCamera> {
        let forward = (target - position).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        Some(PerspectiveCamera {
            position,
            forward,
            right,
            up,
            tan_half_fov_y: (0.5 * fov_y_deg.to_radians()).tan(),
            width,
            height,
            shutter: [0.0; 2],
            motion: None,
        })
    }

    /// The instant of a camera sample: uniform in the shutter interval (one
    /// number drawn from `sampler`), or the shutter's single instant (no
    /// number drawn, so scenes without motion blur keep their numbers).
    #[inline]
    pub fn sample_time(&self, sampler: &mut PixelSampler) -> f32 {
        let [open, close] = self.shutter;
        if open == close {
            open
        } else {
            open + (close - open) * sampler.next_1d()
        }
    }

    /// The camera sample of pixel `(x, y)`: a uniform point of the pixel
    /// (a 2D draw), then its instant ([`PerspectiveCamera::sample_time`]),
    /// which is stored in `sampler` ([`PixelSampler::time`]); the ray is
    /// shot from the camera's pose at that instant.
    #[inline]
    pub fn sample_ray(&self, x: u32, y: u32, sampler: &mut PixelSampler) -> Ray {
        let u = sampler.next_2d();
        let time = self.sample_time(sampler);
        sampler.set_time(time);
        let ray = match &self.motion {
            None => self.generate_ray(x, y, u),
            Some(m) => self.at_time(m, time).generate_ray(x, y, u),
        };
        Ray { time, ..ray }
    }

    /// The static camera posed as `motion` is at `time` (frames); the
    /// camera itself where the interpolated frame is degenerate (scene
    /// validation rejects such motions at the shutter's ends).
    pub fn at_time(&self, motion: &CameraMotion, time: f32) -> PerspectiveCamera {
        let lerp = |v: [Vec3; 2]| v[0] + (v[1] - v[0]) * time;
        let (position, target, up) = (lerp(motion.position), lerp(motion.target), lerp(motion.up));
        let Some(forward) = (target - position).try_normalize() else { return *self };
        let Some(right) = forward.cross(up).try_normalize() else { return *self };
        PerspectiveCamera { position, forward, right, up: right.cross(forward), motion: None, ..*self }
    }

    /// Ray through the point `(x + u.x, y + u.y)` of the image plane (pixel units).
    #[inline]
    pub fn generate_ray(&self, x: u32, y: u32, u: Vec2) -> Ray {
        let aspect = self.width as f32 / self.height as f32;
        let sx = (2.0 * (x as f32 + u.x) / self.width as f32 - 1.0) * self.tan_half_fov_y * aspect;
        let sy = (1.0 - 2.0 * (y as f32 + u.y) / self.height as f32) * self.tan_half_fov_y;
        let d = (self.forward + sx * self.right + sy * self.up).normalize();
        Ray::new(self.position, d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn center_pixel_looks_forward_and_row_zero_is_top() {
        let c = PerspectiveCamera::look_at(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 90.0, 100, 50).unwrap();
        let center = c.generate_ray(50, 25, Vec2::ZERO);
        assert!((center.d - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-5);
        let top_left = c.generate_ray(0, 0, Vec2::ZERO);
        assert!(top_left.d.y > 0.0 && top_left.d.x < 0.0);
        // fov 90: the top edge is at 45 degrees.
        let top = c.generate_ray(50, 0, Vec2::ZERO);
        assert!((top.d.y / -top.d.z - 1.0).abs() < 1e-5);
    }
}
