//! Images and their files: linear float RGB in memory; EXR (linear float32,
//! unclamped) and PNG (exposure, sRGB curve, 8-bit) on disk. Files are written
//! to a temporary file in the target folder and renamed into place, so a
//! failed or killed run never leaves a half-written image. A checkpoint is
//! an EXR whose header also records how it was rendered (samples per pixel
//! so far, seed, scene hash, integrator), so that a killed progressive
//! render can be continued exactly (`checkpoint.rs`). Renders accumulate
//! exact fixed-point sums per pixel (`sums.rs`), so that sample ranges
//! rendered apart add up to the image of one render, bit for bit. A
//! reference of two independent renders measures errors with its own noise
//! removed (`split_reference.rs`).

mod checkpoint;
mod exr_read;
mod output;
mod split_reference;
mod sums;

pub(crate) use checkpoint::write_checkpoint_with;
pub use checkpoint::{
    read_checkpoint, read_checkpoint_full, scene_hash, write_checkpoint, Checkpoint, CheckpointError, CheckpointInfo,
};
pub use exr_read::{read_exr, ExrImage, ExrReadError};
pub(crate) use output::write_srgb8_png;
pub use output::{write_atomically, write_exr, write_exr_with_attributes, write_image, write_png, OutputError};
pub use split_reference::SplitReference;
pub use sums::{mean_of_sum, quantize_sample, SampleSums, FRACTION_BITS, SAMPLE_LIMIT};

use crate::color::Rgb;

/// Bytes per pixel a progressive render holds at once: the accumulated
/// exact sums, the pass's sums and its tiles (`SampleSums`, 48 bytes
/// each), the mean image (12), the checkpoint EXR's uncompressed and
/// compressed buffers (mean and sums, 60 each) and the PNG's (6), rounded up.
pub const RENDER_BYTES_PER_PIXEL: u64 = 288;

/// Memory a progressive render of a `width` x `height` image needs for its
/// images and output buffers ([`RENDER_BYTES_PER_PIXEL`] per pixel).
///
/// ```
/// assert_eq!(niebla::film::render_memory(1920, 1080), 1920 * 1080 * 288);
/// ```
pub fn render_memory(width: u32, height: u32) -> u64 {
    u64::from(width) * u64::from(height) * RENDER_BYTES_PER_PIXEL
}

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
