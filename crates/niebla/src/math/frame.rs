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
}
