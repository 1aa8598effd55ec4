use glam::{Affine3A, Mat3, Vec3};

use crate::math::Ray;

/// An affine map from an object's local space to world space, with its inverse.
#[derive(Clone, Copy, Debug)]
pub struct Transform {
    /// Local to world.
    pub to_world: Affine3A,
    /// World to local.
    pub to_local: Affine3A,
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Transform = Transform { to_world: Affine3A::IDENTITY, to_local: Affine3A::IDENTITY };

    /// A transform from its local-to-world map; `None` when it is singular.
    pub fn new(to_world: Affine3A) -> Option<Transform> {
        let det = to_world.matrix3.determinant();
        if !det.is_finite() || det.abs() < 1e-20 {
            return None;
        }
        Some(Transform { to_world, to_local: to_world.inverse() })
    }

    /// Scale, then rotate about x, y, z (degrees, right-handed), then translate.
    pub fn from_components(scale: Vec3, rotate_deg: Vec3, translate: Vec3) -> Option<Transform> {
        let rot = Mat3::from_rotation_z(rotate_deg.z.to_radians())
            * Mat3::from_rotation_y(rotate_deg.y.to_radians())
            * Mat3::from_rotation_x(rotate_deg.x.to_radians());
        let m = rot * Mat3::from_diagonal(scale);
        Transform::new(Affine3A::from_mat3_translation(m, translate))
    }

    /// A point from local to world.
    #[inline]
    pub fn point_to_world(&self, p: Vec3) -> Vec3 {
        self.to_world.transform_point3(p)
    }

    /// A vector (not normalized) from local to world.
    #[inline]
    pub fn vector_to_world(&self, v: Vec3) -> Vec3 {
        self.to_world.transform_vector3(v)
    }

    /// A normal from local to world (inverse transpose), normalized.
    #[inline]
    pub fn normal_to_world(&self, n: Vec3) -> Vec3 {
        Mat3::from(self.to_local.matrix3).transpose().mul_vec3(n).normalize()
    }

    /// Where `ray` (world space) crosses the local plane `z = 0` with its
    /// parameter in `(t_min, t_max)`: the parameter `t` (an affine map keeps
    /// it: `o + t d` maps to `o' + t d'`) and the local crossing point.
    /// `None` for a ray parallel to the plane. Planar shapes test the point
    /// against their outline.
    #[inline]
    pub fn local_plane_crossing(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<(f32, Vec3)> {
        let o = self.to_local.transform_point3(ray.o);
        let d = self.to_local.transform_vector3(ray.d);
        if d.z == 0.0 {
            return None;
        }
        let t = -o.z / d.z;
        if !(t > t_min && t < t_max) {
            return None;
        }
        Some((t, o + d * t))
    }
}
