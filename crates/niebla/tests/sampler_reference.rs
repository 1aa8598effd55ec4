//! The sampler's numbers against a reference implementation: a verbatim copy
//! of the straightforward `PixelSampler` and Owen-scrambled Sobol code of
//! niebla 0.1 (before the sampler was optimized), kept here so that any
//! change that is meant to be a pure speed-up is checked to draw exactly the
//! same bits. Images rendered before and after then agree to the last bit.
//!
//! The drivers replay pseudo-random sequences of every sampler operation
//! (1D, 2D and f64 draws, slots, repeats, rewinds, stratified choices) over
//! many `(kind, seed, pixel, sample index)` tuples and compare each number's
//! bit pattern.

use niebla::sampling::{
    hash_u64, owen_scrambled_sobol_1d, owen_scrambled_sobol_pair, sobol_2d, PixelSampler, SamplerKind,
};

mod reference {
    use niebla::sampling::hash_u64;

    pub fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
        x = x.wrapping_add(seed);
        x ^= x.wrapping_mul(0x6c50_b47c);
        x ^= x.wrapping_mul(0xb82f_1e52);
        x ^= x.wrapping_mul(0xc7af_e638);
        x ^= x.wrapping_mul(0x8d22_f6e6);
        x
    }

    pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
        laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
    }

    /// Sobol dimensions 0 and 1 bit by bit from the direction numbers of
    /// `x + 1` (`v_0 = 2^31`, `v_k = v_{k-1} ^ (v_{k-1} >> 1)`).
    pub fn sobol_2d(index: u32) -> [u32; 2] {
        let mut v = 1u32 << 31;
        let mut y = 0;
        for bit in 0..32 {
            if (index >> bit) & 1 == 1 {
                y ^= v;
            }
            v ^= v >> 1;
        }
        [index.reverse_bits(), y]
    }

    pub fn owen_scrambled_sobol_pair(key: u64, index: u32, pair: u64) -> [u32; 2] {
        let h = hash_u64(key ^ pair.wrapping_mul(0xD6E8_FEB8_6659_FD93));
        let point = sobol_2d(nested_uniform_scramble(index, h as u32));
        let seeds = hash_u64(h);
        [nested_uniform_scramble(point[0], seeds as u32), nested_uniform_scramble(point[1], (seeds >> 32) as u32)]
    }

    #[derive(Clone, Copy)]
    enum Mode {
        Independent,
        Sobol { index_reversed: u32, pair: u64, values: [u32; 2] },
    }

    /// The `PixelSampler` of niebla 0.1 (slots, rewinds and all).
    pub struct Sampler {
        key: u64,
        dimension: u64,
        slot_end: u64,
        slot_key: u64,
        laid_out: bool,
        stratum: u64,
        mode: Mode,
    }

    impl Sampler {
        pub fn new(seed: u64, x: u32, y: u32, sample_index: u64) -> Sampler {
            let pixel = ((y as u64) << 32) | x as u64;
            let key = hash_u64(hash_u64(hash_u64(seed) ^ pixel) ^ sample_index.wrapping_mul(0xD1B5_4A32_D192_ED03));
            let stratum = sample_index.wrapping_add(hash_u64(hash_u64(seed) ^ pixel) % 1_000_003);
            Sampler {
                key,
                dimension: 0,
                slot_end: u64::MAX,
                slot_key: 0,
                laid_out: false,
                stratum,
                mode: Mode::Independent,
            }
        }

        pub fn for_pixel(sobol: bool, laid_out: bool, seed: u64, x: u32, y: u32, sample_index: u64) -> Sampler {
            if !sobol {
                return Sampler::new(seed, x, y, sample_index);
            }
            let pixel = ((y as u64) << 32) | x as u64;
            let pixel_hash = hash_u64(hash_u64(seed) ^ pixel);
            let key = hash_u64(pixel_hash ^ hash_u64(0x5EED_50B0 ^ (sample_index >> 32)));
            let stratum = sample_index.wrapping_add(pixel_hash % 1_000_003);
            let mode =
                Mode::Sobol { index_reversed: (sample_index as u32).reverse_bits(), pair: u64::MAX, values: [0; 2] };
            Sampler { key, dimension: 0, slot_end: u64::MAX, slot_key: 0, laid_out, stratum, mode }
        }

        pub fn from_key(key: u64) -> Sampler {
            Sampler {
                key: hash_u64(key),
                dimension: 0,
                slot_end: u64::MAX,
                slot_key: 0,
                laid_out: false,
                stratum: key,
                mode: Mode::Independent,
            }
        }

        pub fn stratified_choice(&self, n: u64) -> u64 {
            self.stratum % n.max(1)
        }

        fn next_u32(&mut self) -> u32 {
            let beyond_slot = self.dimension >= self.slot_end;
            let bits = match &mut self.mode {
                Mode::Independent => (hash_u64(self.key ^ hash_u64(self.dimension)) >> 32) as u32,
                Mode::Sobol { index_reversed, .. } if beyond_slot => {
                    let sample = hash_u64(((*index_reversed as u64) << 32) | 0x5A4D);
                    (hash_u64(self.key ^ hash_u64(self.slot_key ^ sample ^ hash_u64(self.dimension))) >> 32) as u32
                }
                Mode::Sobol { index_reversed, pair, values } => {
                    if *pair != self.dimension >> 1 {
                        *pair = self.dimension >> 1;
                        *values = owen_scrambled_sobol_pair(self.key, index_reversed.reverse_bits(), *pair);
                    }
                    values[(self.dimension & 1) as usize]
                }
            };
            self.dimension += 1;
            bits
        }

        pub fn next_1d(&mut self) -> f32 {
            (self.next_u32() >> 8) as f32 * (1.0 / (1u64 << 24) as f32)
        }

        pub fn next_f64(&mut self) -> f64 {
            let bits = match self.mode {
                Mode::Independent => {
                    let bits = hash_u64(self.key ^ hash_u64(self.dimension)) >> 11;
                    self.dimension += 1;
                    bits
                }
                Mode::Sobol { .. } => {
                    let low = hash_u64(self.key ^ hash_u64(!self.dimension) ^ hash_u64(self.stratum)) >> 43;
                    ((self.next_u32() as u64) << 21) | low
                }
            };
            bits as f64 * (1.0 / (1u64 << 53) as f64)
        }

        pub fn next_2d(&mut self) -> [f32; 2] {
            match self.mode {
                Mode::Independent => {
                    let a = self.next_1d();
                    [a, self.next_1d()]
                }
                Mode::Sobol { .. } if self.slot_end != u64::MAX => {
                    self.dimension += self.dimension & 1;
                    if self.dimension + 1 < self.slot_end {
                        if let Mode::Sobol { index_reversed, .. } = self.mode {
                            let [a, b] =
                                owen_scrambled_sobol_pair(self.key, index_reversed.reverse_bits(), self.dimension >> 1);
                            self.dimension += 2;
                            let scale = 1.0 / (1u64 << 24) as f32;
                            return [(a >> 8) as f32 * scale, (b >> 8) as f32 * scale];
                        }
                    }
                    let a = self.next_1d();
                    [a, self.next_1d()]
                }
                Mode::Sobol { index_reversed, .. } => {
                    let pair = self.dimension.div_ceil(2);
                    self.dimension = 2 * pair + 2;
                    let [a, b] = owen_scrambled_sobol_pair(self.key, index_reversed.reverse_bits(), pair);
                    let scale = 1.0 / (1u64 << 24) as f32;
                    [(a >> 8) as f32 * scale, (b >> 8) as f32 * scale]
                }
            }
        }

        pub fn dimension(&self) -> u64 {
            self.dimension
        }

        pub fn use_slots(&mut self, start: u64, len: u64, repeat: u32) {
            if self.laid_out {
                self.dimension = start;
                self.slot_end = if repeat == 0 { start + len } else { start };
                self.slot_key = hash_u64(0x510B_5EED ^ start ^ ((repeat as u64) << 40));
            }
        }

        pub fn rewind_for_another_estimate(&mut self, dimension: u64) {
            if let Mode::Sobol { .. } = self.mode {
                self.dimension = dimension;
                self.slot_end = u64::MAX;
            }
        }
    }
}

/// Replays `ops` pseudo-random operations (chosen by a hash of `script`) on
/// both samplers and asserts equal bits; returns how many numbers matched.
fn replay(mut a: PixelSampler, mut b: reference::Sampler, script: u64, ops: u32, what: &str) -> u32 {
    let mut compared = 0;
    for op in 0..ops {
        let r = hash_u64(script ^ ((op as u64) << 20));
        let at = || format!("{what}, script {script:#x}, op {op}");
        match r % 9 {
            0 | 1 => {
                assert_eq!(a.next_1d().to_bits(), b.next_1d().to_bits(), "next_1d: {}", at());
                compared += 1;
            }
            2 | 3 => {
                let (u, v) = (a.next_2d(), b.next_2d());
                assert_eq!([u.x.to_bits(), u.y.to_bits()], [v[0].to_bits(), v[1].to_bits()], "next_2d: {}", at());
                compared += 2;
            }
            4 => {
                assert_eq!(a.next_f64().to_bits(), b.next_f64().to_bits(), "next_f64: {}", at());
                compared += 1;
            }
            5 | 6 => {
                // Slots of a volpath-like layout: starts anywhere in the
                // first few hundred dimensions, short lengths, a few repeats.
                let start = (r >> 8) % 300;
                let len = 1 + (r >> 20) % 6;
                let repeat = if (r >> 32).is_multiple_of(4) { ((r >> 36) % 3) as u32 } else { 0 };
                a.use_slots(start, len, repeat);
                b.use_slots(start, len, repeat);
            }
            7 => {
                let d = (r >> 8) % 40;
                a.rewind_for_another_estimate(d);
                b.rewind_for_another_estimate(d);
            }
            _ => {
                let n = 1 + (r >> 8) % 7;
                assert_eq!(a.stratified_choice(n), b.stratified_choice(n), "stratified_choice: {}", at());
            }
        }
        assert_eq!(a.dimension(), b.dimension(), "dimension: {}", at());
    }
    compared
}

#[test]
fn pixel_samplers_draw_the_reference_bits() {
    let mut compared = 0u64;
    let seeds = [0u64, 1, 7, 0xDEAD_BEEF, u64::MAX];
    let pixels = [(0u32, 0u32), (1, 0), (0, 1), (37, 211), (4095, 2047), (u32::MAX, u32::MAX)];
    // Sample indices across the 2^32 boundary (a fresh scramble there).
    let samples = [0u64, 1, 2, 3, 15, 16, 255, 1000, (1 << 32) - 1, 1 << 32, (1 << 32) + 5, u64::MAX];
    for kind in SamplerKind::ALL {
        let sobol = kind != SamplerKind::Independent;
        let laid_out = kind == SamplerKind::Sobol;
        for &seed in &seeds {
            for &(x, y) in &pixels {
                for &s in &samples {
                    let script = hash_u64(seed ^ ((x as u64) << 7) ^ ((y as u64) << 29) ^ s.rotate_left(17));
                    let what = format!("{} seed {seed} pixel ({x}, {y}) sample {s}", kind.name());
                    compared += replay(
                        PixelSampler::for_pixel(kind, seed, x, y, s),
                        reference::Sampler::for_pixel(sobol, laid_out, seed, x, y, s),
                        script,
                        200,
                        &what,
                    ) as u64;
                }
            }
        }
    }
    // Consecutive samples of a few pixels, as the render loop draws them.
    for kind in SamplerKind::ALL {
        for s in 0..256u64 {
            let what = format!("{} consecutive sample {s}", kind.name());
            let (sobol, laid_out) = (kind != SamplerKind::Independent, kind == SamplerKind::Sobol);
            compared += replay(
                PixelSampler::for_pixel(kind, 3, 5, 9, s),
                reference::Sampler::for_pixel(sobol, laid_out, 3, 5, 9, s),
                0x5EED ^ s,
                120,
                &what,
            ) as u64;
        }
    }
    // Keyed streams (photons, tests).
    for key in [0u64, 1, 42, u64::MAX] {
        compared += replay(PixelSampler::from_key(key), reference::Sampler::from_key(key), key, 300, "from_key") as u64;
    }
    // Every kind drew many numbers of each operation.
    assert!(compared > 100_000, "compared {compared}");
}

#[test]
fn sobol_pairs_match_the_reference() {
    for i in 0..20_000u64 {
        let r = hash_u64(i);
        let key = hash_u64(r ^ 0x1234);
        let index = match i % 4 {
            0 => (i / 4) as u32,
            1 => u32::MAX - (i / 4) as u32,
            _ => (r >> 32) as u32,
        };
        let pair = if i % 3 == 0 { r % 512 } else { (r >> 7) % (1 << 40) };
        let expected = reference::owen_scrambled_sobol_pair(key, index, pair);
        assert_eq!(
            owen_scrambled_sobol_pair(key, index.reverse_bits(), pair),
            expected,
            "key {key} index {index} pair {pair}"
        );
        assert_eq!(owen_scrambled_sobol_1d(key, index, 2 * pair + (i & 1)), expected[(i & 1) as usize]);
        assert_eq!(sobol_2d(index), reference::sobol_2d(index), "index {index}");
    }
}
