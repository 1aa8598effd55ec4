use glam::Vec2;

/// 64-bit finalizer of SplitMix64 (Steele, Lea, Flood 2014): a bijective
/// avalanche hash, used to derive independent streams from counters.
#[inline]
pub fn hash_u64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Counter-based sampler: the numbers of one pixel sample are a pure function
/// of `(seed, x, y, sample_index, dimension)`.
///
/// ```
/// use niebla::sampling::PixelSampler;
/// let mut a = PixelSampler::new(7, 3, 4, 10);
/// let mut b = PixelSampler::new(7, 3, 4, 10);
/// assert_eq!(a.next_1d(), b.next_1d());
/// ```
#[derive(Clone, Debug)]
pub struct PixelSampler {
    key: u64,
    dimension: u64,
    /// Sample index and pixel hash, for choices stratified across samples.
    stratum: u64,
}

impl PixelSampler {
    /// Start sample `sample_index` of pixel `(x, y)` for a render seeded with `seed`.
    pub fn new(seed: u64, x: u32, y: u32, sample_index: u64) -> PixelSampler {
        let pixel = ((y as u64) << 32) | x as u64;
        let key = hash_u64(hash_u64(hash_u64(seed) ^ pixel) ^ sample_index.wrapping_mul(0xD1B5_4A32_D192_ED03));
        let stratum = sample_index.wrapping_add(hash_u64(hash_u64(seed) ^ pixel) % 1_000_003);
        PixelSampler { key, dimension: 0, stratum }
    }

    /// A stream keyed by an arbitrary 64-bit value (photon index, test seed, ...).
    pub fn from_key(key: u64) -> PixelSampler {
        PixelSampler { key: hash_u64(key), dimension: 0, stratum: key }
    }

    /// Stratified choice of one of `n` options: consecutive sample indices of a
    /// pixel cycle through all options (starting at a pixel-dependent offset),
    /// so that every `n` samples use each option once.
    #[inline]
    pub fn stratified_choice(&self, n: u64) -> u64 {
        self.stratum % n.max(1)
    }

    /// Next uniform number in [0, 1).
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let bits = hash_u64(self.key ^ hash_u64(self.dimension));
        self.dimension += 1;
        // 24 high bits -> [0, 1) exactly representable in f32.
        (bits >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Next uniform number in [0, 1) with 53 bits, for uses that need f64 precision.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        let bits = hash_u64(self.key ^ hash_u64(self.dimension));
        self.dimension += 1;
        (bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Next pair of uniform numbers in [0, 1)^2.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let a = self.next_1d();
        Vec2::new(a, self.next_1d())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampler_is_uniform_and_decorrelated_between_pixels() {
        // Mean and variance of U[0,1) are 1/2 and 1/12; 1e5 draws give standard
        // errors of 9e-4 and 2.6e-4, so 5 SE bounds are used.
        let n = 100_000;
        let mut s = PixelSampler::new(1, 0, 0, 0);
        let v: Vec<f64> = (0..n).map(|_| s.next_1d() as f64).collect();
        let mean = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 5.0 * (1.0 / 12.0f64 / n as f64).sqrt());
        assert!((var - 1.0 / 12.0).abs() < 5.0 * 2.7e-4);
        // Neighbouring pixels and sample indices: first draws are uncorrelated.
        let mut sum_xy = 0.0;
        for i in 0..n as u32 {
            let a = PixelSampler::new(1, i, 0, 0).next_1d() as f64 - 0.5;
            let b = PixelSampler::new(1, i + 1, 0, 0).next_1d() as f64 - 0.5;
            sum_xy += a * b;
        }
        let corr = sum_xy / n as f64 * 12.0;
        assert!(corr.abs() < 5.0 / (n as f64).sqrt(), "correlation {corr}");
    }
}
