//! The stored photon and the packing of surface normals into its tag.

use crate::color::Rgb;
use crate::math::{Vec2, Vec3};

/// A photon stored at a scattering event (volume) or on a diffuse surface.
///
/// ```
/// use niebla::color::Rgb;
/// use niebla::integrator::photon::Photon;
/// use niebla::math::Vec3;
/// let n = Vec3::new(0.0, 0.6, 0.8);
/// let photon = Photon::on_surface(Vec3::ZERO, Vec3::Y, Rgb::ONE, n);
/// assert!((photon.normal() - n).length() < 1e-4);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Position (world).
    pub p: Vec3,
    /// Unit direction toward where the photon came from (the `wi` of the
    /// scattering convention: minus its direction of travel).
    pub wi: Vec3,
    /// Flux the photon carries, W per channel (already divided by the
    /// number of photons emitted).
    pub power: Rgb,
    /// Volume photons: the index of the medium ([`crate::medium::MediumId`]).
    /// Surface photons: the surface normal on the side the photon arrived
    /// from, octahedron-packed into 2 x 16 bits.
    pub tag: u32,
}

impl Photon {
    /// A photon stored in medium `medium` (its index).
    #[inline]
    pub fn in_medium(p: Vec3, wi: Vec3, power: Rgb, medium: u32) -> Photon {
        Photon { p, wi, power, tag: medium }
    }

    /// A photon stored on a surface whose unit normal on the photon's side is `n`.
    #[inline]
    pub fn on_surface(p: Vec3, wi: Vec3, power: Rgb, n: Vec3) -> Photon {
        Photon { p, wi, power, tag: pack_normal(n) }
    }

    /// The unit normal of a surface photon.
    #[inline]
    pub fn normal(&self) -> Vec3 {
        unpack_normal(self.tag)
    }
}

/// Octahedral encoding of a unit vector in 32 bits (Cigolle et al. 2014),
/// error below 1e-4.
#[inline]
pub fn pack_normal(n: Vec3) -> u32 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    let mut v = Vec2::new(n.x, n.y) / l1.max(f32::MIN_POSITIVE);
    if n.z < 0.0 {
        v = Vec2::new((1.0 - v.y.abs()) * v.x.signum(), (1.0 - v.x.abs()) * v.y.signum());
    }
    let q = |x: f32| (((x.clamp(-1.0, 1.0) * 0.5 + 0.5) * 65535.0).round() as u32) & 0xffff;
    q(v.x) | (q(v.y) << 16)
}

/// Inverse of [`pack_normal`].
#[inline]
pub fn unpack_normal(bits: u32) -> Vec3 {
    let d = |b: u32| (b & 0xffff) as f32 / 65535.0 * 2.0 - 1.0;
    let (x, y) = (d(bits), d(bits >> 16));
    let z = 1.0 - x.abs() - y.abs();
    let t = (-z).max(0.0);
    let v = Vec3::new(x - t * x.signum(), y - t * y.signum(), z);
    v.normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{sample_uniform_sphere, PixelSampler};

    #[test]
    fn packed_normals_round_trip_within_1e_4() {
        let mut rng = PixelSampler::from_key(3);
        for _ in 0..100_000 {
            let n = sample_uniform_sphere(rng.next_2d());
            let m = unpack_normal(pack_normal(n));
            assert!((n - m).length() < 1e-4, "{n:?} -> {m:?}");
        }
        for n in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
            assert!((unpack_normal(pack_normal(n)) - n).length() < 1e-4);
        }
    }
}
