use glam::Vec2;

use super::sobol::owen_scrambled_sobol_pair;

/// 64-bit finalizer of SplitMix64 (Steele, Lea, Flood 2014): a bijective
/// avalanche hash, used to derive independent streams from counters.
#[inline]
pub fn hash_u64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Which numbers [`PixelSampler::for_pixel`] gives a pixel's camera samples.
///
/// ```
/// use niebla::sampling::SamplerKind;
/// assert_eq!(SamplerKind::parse("sobol"), Some(SamplerKind::Sobol));
/// assert_eq!(SamplerKind::Sobol.name(), "sobol");
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SamplerKind {
    /// Independent uniform numbers: a hash of `(seed, x, y, s, dimension)`.
    Independent,
    /// Owen-scrambled Sobol points (Burley 2020), see [`crate::sampling::sobol`],
    /// with the integrator's fixed dimension layout where it has one
    /// ([`PixelSampler::use_slots`]: `volpath` gives every decision of a
    /// path vertex its own dimensions).
    #[default]
    Sobol,
    /// Owen-scrambled Sobol points with dimensions taken in the order the
    /// integrator draws them, ignoring its layout (the `sobol` of earlier
    /// versions; kept to measure the layout against).
    SobolSequential,
}

impl SamplerKind {
    /// Every kind, in the order of [`SamplerKind::NAMES`].
    pub const ALL: [SamplerKind; 3] = [SamplerKind::Independent, SamplerKind::Sobol, SamplerKind::SobolSequential];
    /// The names scene files and the command line use.
    pub const NAMES: [&'static str; 3] = ["independent", "sobol", "sobol_sequential"];

    /// The kind called `name`, if any.
    pub fn parse(name: &str) -> Option<SamplerKind> {
        Self::NAMES.iter().position(|n| *n == name).map(|i| Self::ALL[i])
    }

    /// The kind's name in scene files.
    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }
}

/// How a [`PixelSampler`] turns dimensions into numbers.
#[derive(Clone, Copy, Debug)]
enum Mode {
    Independent,
    /// Owen-scrambled Sobol point `index` (the low 32 bits of the sample
    /// index; the high bits are part of the key), given bit-reversed, and
    /// the last pair of dimensions computed (`pair`, `u64::MAX` for none),
    /// whose second value a 1D draw of the odd dimension takes.
    Sobol {
        index_reversed: u32,
        pair: u64,
        values: [u32; 2],
    },
}

/// Counter-based sampler: the numbers of one pixel sample are a pure function
/// of `(seed, x, y, sample_index, dimension)`.
///
/// Two kinds ([`SamplerKind`]): independent numbers, a hash of all five, or
/// Owen-scrambled Sobol points (Burley 2020) in which sample `s` is point
/// `s` of a sequence scrambled per `(seed, pixel)`, so that a pixel's first
/// `2^k` samples are stratified in every pair of dimensions `(2j, 2j+1)`.
///
/// **Dimension layout.** Without a layout, dimensions are drawn in the
/// order the integrator asks for them (independent samplers always, and
/// [`SamplerKind::SobolSequential`]): the render loop draws the pixel
/// position first (dimensions 0 and 1), and [`PixelSampler::next_2d`] of a
/// Sobol sampler first skips to an even dimension, so every 2D decision gets
/// a stratified pair; since the number of dimensions a path uses depends on
/// its events, the dimension of a given decision then varies between
/// samples (each dimension is uniform all the same, so estimates stay
/// unbiased). An integrator with a fixed layout (`volpath`) calls
/// [`PixelSampler::use_slots`] before each decision: a [`SamplerKind::Sobol`]
/// sampler then takes that decision's numbers from fixed dimensions (its
/// slot), the same in every sample of the pixel, so that the decision is
/// stratified over the pixel's samples; draws beyond the slot (a decision
/// repeated an unbounded number of times, such as the null collisions of
/// delta tracking) are independent numbers keyed by the slot and a counter.
/// Independent and sequential samplers ignore slots.
/// [`PixelSampler::stratified_choice`] does not use a dimension.
///
/// Streams that are not per-pixel camera samples (photons, tests:
/// [`PixelSampler::from_key`]) are always independent.
///
/// ```
/// use niebla::sampling::{PixelSampler, SamplerKind};
/// let mut a = PixelSampler::new(7, 3, 4, 10);
/// let mut b = PixelSampler::new(7, 3, 4, 10);
/// assert_eq!(a.next_1d(), b.next_1d());
/// let mut c = PixelSampler::for_pixel(SamplerKind::Sobol, 7, 3, 4, 10);
/// assert!((0.0..1.0).contains(&c.next_1d()));
/// ```
#[derive(Clone, Debug)]
pub struct PixelSampler {
    key: u64,
    dimension: u64,
    /// The dimensions of the current slot end here: draws from here on are
    /// independent numbers keyed by `slot_key` (`u64::MAX`: no slot, the
    /// dimensions in draw order).
    slot_end: u64,
    /// Key of the current slot's independent numbers.
    slot_key: u64,
    /// Whether [`PixelSampler::use_slots`] acts (Sobol with layout).
    laid_out: bool,
    /// Block of the integrator's fixed layout the next decisions belong to
    /// ([`PixelSampler::set_layout_block`]; `u32::MAX`: none).
    layout_block: u32,
    /// Sample index and pixel hash, for choices stratified across samples.
    stratum: u64,
    mode: Mode,
    /// Instant of the camera sample (frames relative to the rendered frame,
    /// see [`PixelSampler::time`]).
    time: f32,
}

impl PixelSampler {
    /// Start sample `sample_index` of pixel `(x, y)` for a render seeded with
    /// `seed`, with independent numbers.
    pub fn new(seed: u64, x: u32, y: u32, sample_index: u64) -> PixelSampler {
        let pixel = ((y as u64) << 32) | x as u64;
        let key = hash_u64(hash_u64(hash_u64(seed) ^ pixel) ^ sample_index.wrapping_mul(0xD1B5_4A32_D192_ED03));
        let stratum = sample_index.wrapping_add(hash_u64(hash_u64(seed) ^ pixel) % 1_000_003);
        PixelSampler::with(key, stratum, Mode::Independent, false)
    }

    /// A sampler at dimension 0, without a slot.
    #[inline]
    fn with(key: u64, stratum: u64, mode: Mode, laid_out: bool) -> PixelSampler {
        PixelSampler {
            key,
            dimension: 0,
            slot_end: u64::MAX,
            slot_key: 0,
            laid_out,
            layout_block: u32::MAX,
            stratum,
            mode,
            time: 0.0,
        }
    }

    /// Start sample `sample_index` of pixel `(x, y)` for a render seeded with
    /// `seed`, with the numbers of `kind`. Independent samplers are those of
    /// [`PixelSampler::new`]; Sobol samplers key their scrambles by
    /// `(seed, x, y)` and the sample index's bits above 32 (each block of
    /// `2^32` samples is a fresh scramble) and take point `sample_index mod
    /// 2^32`.
    #[inline]
    pub fn for_pixel(kind: SamplerKind, seed: u64, x: u32, y: u32, sample_index: u64) -> PixelSampler {
        match kind {
            SamplerKind::Independent => PixelSampler::new(seed, x, y, sample_index),
            SamplerKind::Sobol | SamplerKind::SobolSequential => {
                let pixel = ((y as u64) << 32) | x as u64;
                let pixel_hash = hash_u64(hash_u64(seed) ^ pixel);
                let key = hash_u64(pixel_hash ^ hash_u64(0x5EED_50B0 ^ (sample_index >> 32)));
                let stratum = sample_index.wrapping_add(pixel_hash % 1_000_003);
                let mode = Mode::Sobol {
                    index_reversed: (sample_index as u32).reverse_bits(),
                    pair: u64::MAX,
                    values: [0; 2],
                };
                PixelSampler::with(key, stratum, mode, kind == SamplerKind::Sobol)
            }
        }
    }

    /// A stream keyed by an arbitrary 64-bit value (photon index, test seed, ...).
    pub fn from_key(key: u64) -> PixelSampler {
        PixelSampler::with(hash_u64(key), key, Mode::Independent, false)
    }

    /// Stratified choice of one of `n` options: consecutive sample indices of a
    /// pixel cycle through all options (starting at a pixel-dependent offset),
    /// so that every `n` samples use each option once.
    #[inline]
    pub fn stratified_choice(&self, n: u64) -> u64 {
        self.stratum % n.max(1)
    }

    /// The next dimension's 32 random bits (independent: the high half of a
    /// 64-bit hash; Sobol: the scrambled fixed-point value).
    #[inline]
    fn next_u32(&mut self) -> u32 {
        let beyond_slot = self.dimension >= self.slot_end;
        let bits = match &mut self.mode {
            Mode::Independent => (hash_u64(self.key ^ hash_u64(self.dimension)) >> 32) as u32,
            // The key is the pixel's: the sample index makes the numbers
            // independent between samples.
            Mode::Sobol { index_reversed, .. } if beyond_slot => {
                let sample = hash_u64(((*index_reversed as u64) << 32) | 0x5A4D);
                (hash_u64(self.key ^ hash_u64(self.slot_key ^ sample ^ hash_u64(self.dimension))) >> 32) as u32
            }
            Mode::Sobol { index_reversed, pair, values } => {
                if *pair != self.dimension >> 1 {
                    *pair = self.dimension >> 1;
                    *values = owen_scrambled_sobol_pair(self.key, *index_reversed, *pair);
                }
                values[(self.dimension & 1) as usize]
            }
        };
        self.dimension += 1;
        bits
    }

    /// Next uniform number in [0, 1).
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        // 24 high bits -> [0, 1) exactly representable in f32.
        (self.next_u32() >> 8) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Next uniform number in [0, 1) with 53 bits, for uses that need f64
    /// precision (a Sobol value's 32 bits are completed by 21 hashed bits).
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        let bits = match self.mode {
            Mode::Independent => {
                let bits = hash_u64(self.key ^ hash_u64(self.dimension)) >> 11;
                self.dimension += 1;
                bits
            }
            Mode::Sobol { .. } => {
                // The key is per pixel in Sobol mode: the sample's stratum makes the
                // low bits differ between samples too.
                let low = hash_u64(self.key ^ hash_u64(!self.dimension) ^ hash_u64(self.stratum)) >> 43;
                ((self.next_u32() as u64) << 21) | low
            }
        };
        bits as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Next pair of uniform numbers in [0, 1)^2. A Sobol sampler first skips
    /// to an even dimension, so that the pair is one of its stratified pairs.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        match self.mode {
            Mode::Independent => {
                let a = self.next_1d();
                Vec2::new(a, self.next_1d())
            }
            Mode::Sobol { .. } if self.slot_end != u64::MAX => {
                // A slot's pairs start at even dimensions.
                self.dimension += self.dimension & 1;
                if self.dimension + 1 < self.slot_end {
                    if let Mode::Sobol { index_reversed, .. } = self.mode {
                        let [a, b] = owen_scrambled_sobol_pair(self.key, index_reversed, self.dimension >> 1);
                        self.dimension += 2;
                        let scale = 1.0 / (1u64 << 24) as f32;
                        return Vec2::new((a >> 8) as f32 * scale, (b >> 8) as f32 * scale);
                    }
                }
                let a = self.next_1d();
                Vec2::new(a, self.next_1d())
            }
            Mode::Sobol { index_reversed, .. } => {
                let pair = self.dimension.div_ceil(2);
                self.dimension = 2 * pair + 2;
                let [a, b] = owen_scrambled_sobol_pair(self.key, index_reversed, pair);
                let scale = 1.0 / (1u64 << 24) as f32;
                Vec2::new((a >> 8) as f32 * scale, (b >> 8) as f32 * scale)
            }
        }
    }

    /// The instant of this camera sample, in frames relative to the rendered
    /// frame (0 unless the camera's shutter is open over an interval): set
    /// once when the camera ray is generated
    /// ([`crate::camera::PerspectiveCamera::sample_ray`]) and read by every
    /// lookup of a moving medium along the sample's path, its shadow rays
    /// included. All rays of one camera sample share the instant, and every
    /// estimator already receives the sampler with its ray, so no ray built
    /// on the way can lose it. Streams from [`PixelSampler::from_key`]
    /// (photons) are at time 0.
    #[inline]
    pub fn time(&self) -> f32 {
        self.time
    }

    /// Set the instant of this camera sample ([`PixelSampler::time`]).
    #[inline]
    pub fn set_time(&mut self, time: f32) {
        self.time = time;
    }

    /// The dimension the next draw uses (how many were drawn so far, plus
    /// those a Sobol sampler's [`PixelSampler::next_2d`] skipped).
    #[inline]
    pub fn dimension(&self) -> u64 {
        self.dimension
    }

    /// Take the next numbers from the slot of dimensions `start .. start +
    /// len` (a [`SamplerKind::Sobol`] sampler; others ignore it): the draws
    /// that follow use those dimensions in order ([`PixelSampler::next_2d`]
    /// first skips to an even one), and any beyond them are independent
    /// numbers keyed by `(start, repeat)` and their count. `repeat` counts
    /// earlier uses of the same slot by the same estimate: 0 for the first,
    /// which gets the slot's dimensions; every later one gets independent
    /// numbers only, since two decisions of one path must not share a
    /// number. Slots of one estimate must not overlap.
    #[inline]
    pub fn use_slots(&mut self, start: u64, len: u64, repeat: u32) {
        if self.laid_out {
            self.dimension = start;
            self.slot_end = if repeat == 0 { start + len } else { start };
            self.slot_key = hash_u64(0x510B_5EED ^ start ^ ((repeat as u64) << 40));
        }
    }

    /// Record which block of its fixed dimension layout an integrator's next
    /// decisions belong to (the camera-ray walk of `single`, `emission` and
    /// `analytic` sets the index of its step along the ray, so that shared
    /// lighting code can find its slots without being told), or `None` when
    /// the estimate has no layout. Only bookkeeping: the numbers change only
    /// when a slot is then entered ([`PixelSampler::use_slots`]).
    #[inline]
    pub fn set_layout_block(&mut self, block: Option<u32>) {
        self.layout_block = block.unwrap_or(u32::MAX);
    }

    /// The block set by [`PixelSampler::set_layout_block`], if any.
    #[inline]
    pub fn layout_block(&self) -> Option<u32> {
        (self.layout_block != u32::MAX).then_some(self.layout_block)
    }

    /// Whether [`PixelSampler::use_slots`] changes this sampler's numbers
    /// (a [`SamplerKind::Sobol`] camera sample).
    #[inline]
    pub fn is_laid_out(&self) -> bool {
        self.laid_out
    }

    /// Draw again from `dimension` on (an earlier [`PixelSampler::dimension`]),
    /// for estimates that may share their numbers because each is unbiased
    /// alone and they add up different things (the paths of `volpath`'s
    /// channel groups, each giving only its own channels): each then gets the
    /// stratified low dimensions of a Sobol sampler instead of those left
    /// after the previous one. Independent samplers ignore it, so that their
    /// numbers stay those of a plain sequence of draws.
    #[inline]
    pub fn rewind_for_another_estimate(&mut self, dimension: u64) {
        if let Mode::Sobol { .. } = self.mode {
            self.dimension = dimension;
            self.slot_end = u64::MAX;
        }
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
