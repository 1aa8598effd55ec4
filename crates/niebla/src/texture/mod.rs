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

pub use bitmap::{Bitmap, TextureError, WrapMode};

use crate::color::Rgb;
use crate::math::Vec2;

/// A texture: a color per uv point, linear Rec.709 RGB.
#[derive(Clone, Debug)]
pub enum Texture {
    /// An image, filtered bilinearly, `uv` scaled by `scale` first.
    Bitmap {
        /// The image (linear RGB).
        image: std::sync::Arc<Bitmap>,
        /// uv scale (repetitions over the surface's uv range).
        scale: Vec2,
    },
    /// Two colors alternating on a grid of `scale` cells per unit of uv
    /// (Mitsuba 3's `checkerboard` has `scale` 2: four squares over `[0, 1]^2`).
    Checkerboard {
        /// Color of the cells whose integer coordinates sum to an even number.
        color0: Rgb,
        /// Color of the other cells.
        color1: Rgb,
        /// Cells per unit of uv along u and v.
        scale: Vec2,
    },
}

impl Texture {
    /// The color at `uv`.
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Rgb {
        match self {
            Texture::Bitmap { image, scale } => image.eval(uv * *scale),
            Texture::Checkerboard { color0, color1, scale } => {
                let c = (uv * *scale).floor();
                if (c.x as i64 + c.y as i64).rem_euclid(2) == 0 {
                    *color0
                } else {
                    *color1
                }
            }
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
        let t = Texture::Checkerboard { color0: Rgb::splat(0.1), color1: Rgb::splat(0.9), scale: Vec2::splat(2.0) };
        assert_eq!(t.eval(Vec2::new(0.1, 0.1)), Rgb::splat(0.1));
        assert_eq!(t.eval(Vec2::new(0.6, 0.1)), Rgb::splat(0.9));
        assert_eq!(t.eval(Vec2::new(0.6, 0.6)), Rgb::splat(0.1));
        assert_eq!(t.eval(Vec2::new(-0.1, 0.1)), Rgb::splat(0.9));
    }
}
