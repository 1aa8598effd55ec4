//! Surface textures: colors that vary over a surface by its uv coordinates.
//!
//! uv conventions of the shapes (Mitsuba 3's): a mesh interpolates its
//! vertex uvs (without them, a hit's barycentric `(b1, b2)`); a sphere maps
//! the azimuth about +z to `u` (over 2 pi, from +x toward +y) and the polar
//! angle from +z to `v` (over pi); a rectangle maps its local square
//! `[-1, 1]^2` to `[0, 1]^2`; a disk maps its local radius to `u` and the
//! azimuth (over 2 pi, from +x toward +y) to `v`; a box maps each face's two other coordinates to
//! `[0, 1]^2` over the face. A bitmap's `v = 0` is the bottom row of the
//! image and `v = 1` the top (the convention of OBJ and PLY uvs), `u = 0`
//! its left column.

mod bitmap;
mod roughness;

pub use bitmap::{Bitmap, FilterMode, TextureError, WrapMode};
pub use roughness::{AlphaTextures, RoughnessTextures};

use crate::color::Rgb;
use crate::math::Vec2;

/// An affine map of uv coordinates, `uv' = (m[0][0] u + m[0][1] v + m[0][2],
/// m[1][0] u + m[1][1] v + m[1][2])` (Mitsuba 3's `to_uv`, rows of its 3x3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvMap {
    /// The two rows of the map.
    pub m: [[f32; 3]; 2],
}

impl UvMap {
    /// The identity map.
    pub const IDENTITY: UvMap = UvMap { m: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] };

    /// Scaling by `s` (per axis).
    pub fn scale(s: Vec2) -> UvMap {
        UvMap { m: [[s.x, 0.0, 0.0], [0.0, s.y, 0.0]] }
    }

    /// The map from the rows `m`.
    pub fn from_rows(m: [[f32; 3]; 2]) -> UvMap {
        UvMap { m }
    }

    /// `self` after `first`: `uv -> self(first(uv))`.
    pub fn after(&self, first: &UvMap) -> UvMap {
        let (a, b) = (&self.m, &first.m);
        let row = |r: usize| {
            [
                a[r][0] * b[0][0] + a[r][1] * b[1][0],
                a[r][0] * b[0][1] + a[r][1] * b[1][1],
                a[r][0] * b[0][2] + a[r][1] * b[1][2] + a[r][2],
            ]
        };
        UvMap { m: [row(0), row(1)] }
    }

    /// The mapped point.
    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let m = &self.m;
        Vec2::new(m[0][0] * uv.x + m[0][1] * uv.y + m[0][2], m[1][0] * uv.x + m[1][1] * uv.y + m[1][2])
    }
}

/// A texture: a color per uv point, linear Rec.709 RGB.
#[derive(Clone, Debug)]
pub enum Texture {
    /// An image looked up at `uv_map(uv)`.
    Bitmap {
        /// The image (linear RGB).
        image: std::sync::Arc<Bitmap>,
        /// Map applied to the surface's uv before the lookup (the JSON
        /// `scale`, after `to_uv` when given).
        uv_map: UvMap,
        /// Bilinear or nearest-texel lookup.
        filter: FilterMode,
    },
    /// Two colors alternating on a unit grid in `uv_map(uv)` (Mitsuba 3's
    /// `checkerboard` is the JSON `scale` 2: four squares over `[0, 1]^2`).
    Checkerboard {
        /// Color of the cells whose integer coordinates sum to an even number.
        color0: Rgb,
        /// Color of the other cells.
        color1: Rgb,
        /// Map from the surface's uv to cell coordinates.
        uv_map: UvMap,
    },
}

impl Texture {
    /// The color at `uv`.
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Rgb {
        match self {
            Texture::Bitmap { image, uv_map, filter } => image.eval(uv_map.apply(uv), *filter),
            Texture::Checkerboard { color0, color1, uv_map } => {
                let c = uv_map.apply(uv).floor();
                if (c.x as i64 + c.y as i64).rem_euclid(2) == 0 {
                    *color0
                } else {
                    *color1
                }
            }
        }
    }

    /// The scalar value at `uv` (for a textured roughness): a gray color's
    /// value, else its luminance, as Mitsuba 3's `Texture::eval_1` of a
    /// color texture.
    #[inline]
    pub fn scalar(&self, uv: Vec2) -> f32 {
        let c = self.eval(uv);
        if c.r() == c.g() && c.g() == c.b() {
            c.r()
        } else {
            // Mitsuba 3's `luminance` weights (Rec.709 Y, six digits).
            0.212671 * c.r() + 0.715160 * c.g() + 0.072169 * c.b()
        }
    }

    /// Mean of the three channels over the texture (over the image's pixels,
    /// or of the two checkerboard colors), as Mitsuba's `Texture::mean`.
    pub fn mean(&self) -> f32 {
        match self {
            Texture::Bitmap { image, .. } => {
                let sum: f64 = image.pixels.iter().map(|p| (p.r() + p.g() + p.b()) as f64 / 3.0).sum();
                (sum / image.pixels.len().max(1) as f64) as f32
            }
            Texture::Checkerboard { color0, color1, .. } => {
                (color0.r() + color0.g() + color0.b() + color1.r() + color1.g() + color1.b()) / 6.0
            }
        }
    }

    /// Bytes held by the texture's data.
    pub fn memory_bytes(&self) -> usize {
        match self {
            Texture::Bitmap { image, .. } => image.memory_bytes(),
            Texture::Checkerboard { .. } => 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkerboard_alternates_by_cell() {
        let t = Texture::Checkerboard {
            color0: Rgb::splat(0.1),
            color1: Rgb::splat(0.9),
            uv_map: UvMap::scale(Vec2::splat(2.0)),
        };
        assert_eq!(t.eval(Vec2::new(0.1, 0.1)), Rgb::splat(0.1));
        assert_eq!(t.eval(Vec2::new(0.6, 0.1)), Rgb::splat(0.9));
        assert_eq!(t.eval(Vec2::new(0.6, 0.6)), Rgb::splat(0.1));
        assert_eq!(t.eval(Vec2::new(-0.1, 0.1)), Rgb::splat(0.9));
    }

    #[test]
    fn uv_maps_compose_in_order() {
        // First scale by (2, 3), then translate by (0.5, -1) and swap axes.
        let first = UvMap::scale(Vec2::new(2.0, 3.0));
        let then = UvMap::from_rows([[0.0, 1.0, 0.5], [1.0, 0.0, -1.0]]);
        let both = then.after(&first);
        for uv in [Vec2::new(0.1, 0.7), Vec2::new(-2.0, 5.0)] {
            let want = then.apply(first.apply(uv));
            assert!((both.apply(uv) - want).length() < 1e-6, "{uv}");
        }
        assert_eq!(both.apply(Vec2::new(1.0, 1.0)), Vec2::new(3.5, 1.0));
    }
}
