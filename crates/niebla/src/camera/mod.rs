//! Cameras.

use crate::math::{Ray, Vec2, Vec3};

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
        })
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
