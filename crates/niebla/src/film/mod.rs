//! Images and their files: linear float RGB in memory; EXR (linear float32,
//! unclamped) and PNG (exposure, sRGB curve, 8-bit) on disk. Files are written
//! to a temporary file in the target folder and renamed into place, so a
//! failed or killed run never leaves a half-written image.

mod output;

pub use output::{write_atomically, write_exr, write_image, write_png, OutputError};

use crate::color::Rgb;

/// A linear RGB image, row 0 at the top, `pixels[y * width + x]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear radiance per pixel, W/(sr m^2).
    pub pixels: Vec<Rgb>,
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Image {
        Image { width, height, pixels: vec![Rgb::ZERO; width as usize * height as usize] }
    }

    /// Pixel at column `x`, row `y`.
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// Mean of all pixels.
    pub fn mean(&self) -> Rgb {
        let mut sum = [0f64; 3];
        for p in &self.pixels {
            for c in 0..3 {
                sum[c] += p[c] as f64;
            }
        }
        let n = self.pixels.len().max(1) as f64;
        Rgb::new((sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32)
    }

    /// Relative mean squared error against `reference`: the mean over pixels
    /// and channels of `(x - r)^2 / (r^2 + eps)`, with `eps = (0.01 * mean(r))^2`
    /// so that black reference pixels do not dominate while the measure stays
    /// independent of the image's overall brightness.
    pub fn relative_mse(&self, reference: &Image) -> f64 {
        let mean = reference.mean().average() as f64;
        let eps = (0.01 * mean).powi(2).max(f64::MIN_POSITIVE);
        let mut sum = 0.0f64;
        for (a, b) in self.pixels.iter().zip(&reference.pixels) {
            for c in 0..3 {
                let (x, r) = (a[c] as f64, b[c] as f64);
                sum += (x - r).powi(2) / (r * r + eps);
            }
        }
        sum / (3.0 * self.pixels.len().max(1) as f64)
    }
}
