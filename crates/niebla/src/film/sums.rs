//! Exact per-pixel sums of samples, so that a render split into sample
//! ranges (passes, checkpoints, machines) adds up to the same image as one
//! render of all the samples, bit for bit.
//!
//! Floating-point addition is not associative: the f64 sum of samples
//! `0..8` in index order differs in its last bits from the sum of the sums
//! of `0..3` and `3..8`. So each sample's radiance (an f32 per channel) is
//! turned into a fixed-point integer, `round(v * 2^FRACTION_BITS)` as an
//! `i128`, and a pixel holds the integer sum of its samples. Integer sums
//! are exact and associative, so the sum of any sample range is the sum of
//! the sums of its parts in any grouping or order. The pixel's value is the
//! one function [`mean_of_sum`] of (sum, sample count): `sum * 2^-60 / n`
//! in f64, rounded to f32.
//!
//! Range: a sample contributes exactly to within `2^-61` (about 4.3e-19)
//! in absolute value; samples smaller than that count as zero. A sample of
//! magnitude [`SAMPLE_LIMIT`] (2^32, about 4.3e9) or more is dropped like a
//! non-finite one (counted as zero), so that the sum of up to 2^35 samples
//! per pixel cannot overflow the `i128`.

use crate::color::Rgb;

use super::Image;

/// Bits after the binary point of the fixed-point sums.
pub const FRACTION_BITS: i32 = 60;

/// Samples of this magnitude or more (per channel) are dropped.
pub const SAMPLE_LIMIT: f32 = 4_294_967_296.0;

/// The fixed-point value of one sample channel: `round(v * 2^60)`, or 0
/// when `v` is not finite or `|v| >= SAMPLE_LIMIT`.
///
/// ```
/// use niebla::film::{quantize_sample, mean_of_sum};
/// assert_eq!(quantize_sample(1.0), 1i128 << 60);
/// assert_eq!(quantize_sample(f32::NAN), 0);
/// assert_eq!(mean_of_sum(quantize_sample(0.25) * 4, 4), 0.25);
/// ```
#[inline]
pub fn quantize_sample(v: f32) -> i128 {
    if !v.is_finite() || v.abs() >= SAMPLE_LIMIT {
        return 0;
    }
    // Exact: scaling an f32 by a power of two in f64 loses nothing, and the
    // rounded value is below 2^92 in magnitude.
    (v as f64 * (2f64).powi(FRACTION_BITS)).round() as i128
}

/// Mean radiance of `n` samples whose fixed-point sum is `sum`:
/// `sum * 2^-60 / n` in f64, rounded to f32 (0 when `n == 0`).
#[inline]
pub fn mean_of_sum(sum: i128, n: u64) -> f32 {
    if n == 0 {
        return 0.0;
    }
    ((sum as f64) * (2f64).powi(-FRACTION_BITS) / n as f64) as f32
}

/// Per-pixel fixed-point sums of the samples of a sample range (see the
/// module documentation), `sums[y * width + x]` per RGB channel.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SampleSums {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Fixed-point sums (units of 2^-60 W/(sr m^2)) per pixel and channel.
    pub sums: Vec<[i128; 3]>,
}

impl SampleSums {
    /// All sums zero (no samples).
    pub fn new(width: u32, height: u32) -> SampleSums {
        SampleSums { width, height, sums: vec![[0; 3]; width as usize * height as usize] }
    }

    /// Adds the sums of another sample range of the same image size
    /// (exact; the order of additions does not matter).
    ///
    /// # Panics
    /// If the sizes differ.
    pub fn add(&mut self, other: &SampleSums) {
        assert_eq!((self.width, self.height), (other.width, other.height), "sums of images of different sizes");
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            for c in 0..3 {
                a[c] += b[c];
            }
        }
    }

    /// The mean image of `n` samples per pixel ([`mean_of_sum`] per channel).
    pub fn mean(&self, n: u64) -> Image {
        let pixels = self
            .sums
            .iter()
            .map(|s| Rgb::new(mean_of_sum(s[0], n), mean_of_sum(s[1], n), mean_of_sum(s[2], n)))
            .collect();
        Image { width: self.width, height: self.height, pixels }
    }

    /// Sums that reproduce a mean image of `n` samples per pixel as closely
    /// as fixed point allows: `round(mean * n * 2^60)`. For images that
    /// carry no sums (checkpoints of niebla before sums were stored); the
    /// mean of the result may differ from `mean` in the last bit.
    pub fn from_mean(mean: &Image, n: u64) -> SampleSums {
        let scale = (2f64).powi(FRACTION_BITS) * n as f64;
        let sums = mean
            .pixels
            .iter()
            .map(|p| p.0.map(|v| if v.is_finite() { (v as f64 * scale).round() as i128 } else { 0 }))
            .collect();
        SampleSums { width: mean.width, height: mean.height, sums }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_sums_add_up_exactly_in_any_grouping() {
        // Values of very different magnitudes, whose f64 sums depend on order.
        let values: Vec<f32> = (0..40).map(|i| ((i * 7919 % 97) as f32 - 30.0) * 10f32.powi(i % 9 - 4)).collect();
        let total: i128 = values.iter().map(|&v| quantize_sample(v)).sum();
        for split in 1..values.len() {
            let (a, b) = values.split_at(split);
            let sum = |part: &[f32]| part.iter().rev().map(|&v| quantize_sample(v)).sum::<i128>();
            assert_eq!(sum(b) + sum(a), total);
        }
        // The mean agrees with the f64 mean to f32 precision.
        let f64_mean = values.iter().map(|&v| v as f64).sum::<f64>() / values.len() as f64;
        let mean = mean_of_sum(total, values.len() as u64) as f64;
        assert!((mean - f64_mean).abs() <= 1e-7 * f64_mean.abs(), "{mean} vs {f64_mean}");
    }

    #[test]
    fn out_of_range_samples_count_as_zero_and_small_ones_round() {
        assert_eq!(quantize_sample(f32::INFINITY), 0);
        assert_eq!(quantize_sample(-SAMPLE_LIMIT), 0);
        assert_eq!(quantize_sample(SAMPLE_LIMIT * 0.5), 1i128 << 91);
        assert_eq!(quantize_sample(1e-20), 0);
        assert_eq!(quantize_sample(-3.0), -3i128 << 60);
        // 2^35 samples at the limit stay below i128::MAX.
        assert!(((1i128 << 92) - 1).checked_mul(1 << 35).is_some());
    }

    #[test]
    fn from_mean_round_trips_ordinary_values() {
        let mut image = Image::new(2, 1);
        image.pixels[0] = Rgb::new(0.1, 2.5, 1e-6);
        image.pixels[1] = Rgb::new(f32::NAN, 0.0, 7.0);
        let sums = SampleSums::from_mean(&image, 3);
        let back = sums.mean(3);
        assert_eq!(back.pixels[0], image.pixels[0]);
        assert_eq!(back.pixels[1], Rgb::new(0.0, 0.0, 7.0));
    }
}
