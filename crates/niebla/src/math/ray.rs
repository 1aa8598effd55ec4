use glam::Vec3;

/// A ray `o + t d` in world space; `d` is a unit vector so `t` is a distance.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin (world space).
    pub o: Vec3,
    /// Unit direction (world space).
    pub d: Vec3,
}

impl Ray {
    /// A ray from `o` along unit direction `d`.
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Ray {
        Ray { o, d }
    }

    /// The point at distance `t` along the ray.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}
