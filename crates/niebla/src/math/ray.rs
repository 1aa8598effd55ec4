use glam::Vec3;

/// A ray `o + t d` in world space at an instant; `d` is a unit vector so `t`
/// is a distance.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    /// Origin (world space).
    pub o: Vec3,
    /// Unit direction (world space).
    pub d: Vec3,
    /// The instant the ray exists at, in frames relative to the rendered
    /// frame (see the camera's shutter): moving shapes are intersected in
    /// their pose at this time. 0 for rays of a still scene.
    pub time: f32,
}

impl Ray {
    /// A ray from `o` along unit direction `d` at time 0.
    #[inline]
    pub fn new(o: Vec3, d: Vec3) -> Ray {
        Ray { o, d, time: 0.0 }
    }

    /// A ray from `o` along unit direction `d` at `time` (frames).
    #[inline]
    pub fn at_time(o: Vec3, d: Vec3, time: f32) -> Ray {
        Ray { o, d, time }
    }

    /// The point at distance `t` along the ray.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}
