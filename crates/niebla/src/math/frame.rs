use glam::Vec3;

/// An orthonormal frame (x, y, z) built around a unit vector z, used to turn
/// directions sampled around +z into world directions.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    /// First tangent.
    pub x: Vec3,
    /// Second tangent.
    pub y: Vec3,
    /// The axis the frame was built around.
    pub z: Vec3,
}

impl Frame {
    /// Frame whose z axis is the unit vector `z` (Duff et al. 2017 branchless basis).
    pub fn from_z(z: Vec3) -> Frame {
        let sign = 1.0f32.copysign(z.z);
        let a = -1.0 / (sign + z.z);
        let b = z.x * z.y * a;
        let x = Vec3::new(1.0 + sign * z.x * z.x * a, sign * b, -sign * z.x);
        let y = Vec3::new(b, sign + z.y * z.y * a, -z.y);
        Frame { x, y, z }
    }

    /// Frame whose z axis is the unit normal `n` and whose x axis is the
    /// tangent `t` made orthogonal to `n` (Gram-Schmidt, Mitsuba 3's
    /// `SurfaceInteraction::initialize_sh_frame`: `x = normalize(t - n (n . t))`,
    /// `y = n x x`). `t` need not be unit; where it is zero or along `n`,
    /// `x` is [`Frame::from_z`]'s (Mitsuba's `coordinate_system(n)` fallback).
    pub fn from_normal_tangent(n: Vec3, t: Vec3) -> Frame {
        let s = t - n * n.dot(t);
        let len2 = s.length_squared();
        if !(len2 > 1e-12 * t.length_squared()) || !len2.is_finite() {
            return Frame::from_z(n);
        }
        let x = s / len2.sqrt();
        Frame { x, y: n.cross(x), z: n }
    }

    /// Local (frame) coordinates to world coordinates.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }

    /// World coordinates to local (frame) coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_any_axis() {
        for z in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
            Vec3::new(-1e-7, 0.0, -1.0).normalize(),
        ] {
            let f = Frame::from_z(z);
            assert!((f.x.length() - 1.0).abs() < 1e-5);
            assert!((f.y.length() - 1.0).abs() < 1e-5);
            assert!(f.x.dot(f.y).abs() < 1e-5);
            assert!(f.x.dot(f.z).abs() < 1e-5);
            assert!((f.x.cross(f.y) - f.z).length() < 1e-5);
            let v = Vec3::new(0.2, -0.5, 0.7);
            assert!((f.to_local(f.to_world(v)) - v).length() < 1e-5);
        }
    }

    #[test]
    fn tangent_frame_is_gram_schmidt_with_from_z_fallback() {
        let n = Vec3::new(0.3, -0.4, 0.866_025_4).normalize();
        let t = Vec3::new(2.0, 1.0, 0.5);
        let f = Frame::from_normal_tangent(n, t);
        // x lies in the plane of n and t, orthogonal to n, on t's side.
        assert!(f.x.dot(n).abs() < 1e-6 && f.x.dot(t) > 0.0);
        assert!(n.cross(t).dot(f.x).abs() < 1e-5);
        assert!((f.x.length() - 1.0).abs() < 1e-6 && (f.x.cross(f.y) - f.z).length() < 1e-5);
        // A zero (or normal-parallel) tangent gives the normal-only frame.
        for t in [Vec3::ZERO, n * 3.0] {
            let g = Frame::from_normal_tangent(n, t);
            assert_eq!((g.x, g.y), (Frame::from_z(n).x, Frame::from_z(n).y));
        }
    }
}
