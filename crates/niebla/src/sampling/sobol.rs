//! Owen-scrambled Sobol points with hash-based scrambling (Burley 2020,
//! "Practical Hash-based Owen Scrambling", JCGT 9(4)).
//!
//! **Points.** The first two dimensions of the Sobol sequence (Sobol 1967;
//! direction numbers of Joe and Kuo 2008): dimension 0 is the van der Corput
//! sequence, dimension 1 the one of primitive polynomial `x + 1` (its
//! generator matrix is Pascal's triangle mod 2). Together they form a
//! (0, 2)-sequence in base 2: every aligned block of `2^k` consecutive
//! indices is a (0, k, 2)-net, i.e. each elementary interval of area `2^-k`
//! (shapes `2^-a x 2^-b`, `a + b = k`) holds exactly one point.
//!
//! **Padding.** Higher dimensions are not taken from higher Sobol
//! dimensions: the 2D projections of Sobol dimensions 2 and 3 (polynomials
//! `x^2 + x + 1`, `x^3 + x + 1`) have a t-value of 1 or 2 for `2^k` points,
//! `k = 2, 3, 5 .. 10` (0 only for 2, 16 points), so they are not (0, k,
//! 2)-nets. Instead dimension `d` is component `d mod 2`
//! of the Sobol pair (0, 1) within pair `d / 2`, each pair with its own
//! shuffle of the sample index (Burley 2020's padding; pbrt-v4's
//! `PaddedSobolSampler`): the pairs `(0, 1), (2, 3), (4, 5), ...` are each
//! stratified 2D sets, and different pairs are decorrelated.
//!
//! **Shuffle and scramble.** The sample index is shuffled by a nested uniform
//! scramble (reverse the bits, apply the Laine-Karras-style hash permutation,
//! reverse back), keyed by a hash of (seed, pixel, pair); since bit `j` of the
//! shuffled index depends only on bits `>= j` of the index, the first `2^k`
//! indices map onto an aligned block of `2^k` Sobol indices and every
//! power-of-two prefix of a pixel's samples stays a net. Each value is then
//! Owen-scrambled (Owen 1995) by the same nested uniform scramble keyed by
//! (seed, pixel, dimension), which makes every point uniformly distributed
//! while keeping the net property.

use super::rng::hash_u64;

/// Laine-Karras-style hash permutation with Burley 2020's constants: a
/// bijection of `u32` in which bit `i` of the result depends only on bits
/// `<= i` of `x` (the additions and products by even constants carry only
/// upward), so applied to bit-reversed values it is a nested uniform
/// scramble.
#[inline]
pub fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

/// Nested uniform (Owen) scramble of the 32-bit fixed-point value `x` keyed
/// by `seed`: bit `j` (counted from the most significant) is flipped or not
/// depending on `seed` and the bits above it (Burley 2020, listing 3).
#[inline]
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// Direction numbers of Sobol dimension 1 (polynomial `x + 1`, Joe and Kuo
/// 2008): `v_0 = 2^31`, `v_k = v_{k-1} ^ (v_{k-1} >> 1)`.
const fn sobol_1_directions() -> [u32; 32] {
    let mut v = [0u32; 32];
    v[0] = 1 << 31;
    let mut k = 1;
    while k < 32 {
        v[k] = v[k - 1] ^ (v[k - 1] >> 1);
        k += 1;
    }
    v
}

/// Sobol dimension 1 by bytes of the index: `TABLE[j][b]` is the XOR of the
/// direction numbers of the bits set in byte value `b` at byte `j`.
static SOBOL_1_TABLE: [[u32; 256]; 4] = byte_tables(false);

/// Sobol point `index` in dimensions 0 and 1, as 32-bit fixed-point values
/// (value / 2^32 in [0, 1)).
///
/// ```
/// use niebla::sampling::sobol_2d;
/// assert_eq!(sobol_2d(0), [0, 0]);
/// assert_eq!(sobol_2d(1), [1 << 31, 1 << 31]);
/// assert_eq!(sobol_2d(2), [1 << 30, 3 << 30]);
/// ```
#[inline]
pub fn sobol_2d(index: u32) -> [u32; 2] {
    let b = index.to_le_bytes();
    let y = SOBOL_1_TABLE[0][b[0] as usize]
        ^ SOBOL_1_TABLE[1][b[1] as usize]
        ^ SOBOL_1_TABLE[2][b[2] as usize]
        ^ SOBOL_1_TABLE[3][b[3] as usize];
    [index.reverse_bits(), y]
}

/// Sobol dimension 1 bit-reversed, by bytes of the bit-reversed index:
/// `REVERSED_TABLE[j][b]` is the XOR of `reverse_bits(v_i)` over the bits set
/// in byte value `b` at byte `j` of `reverse_bits(index)` (bit `k` of that
/// byte is bit `31 - 8 j - k` of the index). The value scramble works on the
/// bit-reversed value, so this saves two bit reversals per pair.
static SOBOL_1_REVERSED_TABLE: [[u32; 256]; 4] = byte_tables(true);

/// The byte tables of Sobol dimension 1: entry `[j][b]` XORs the direction
/// numbers of the bits set in byte value `b` at byte `j` of the index
/// (`reversed`: of the bit-reversed index, XORing bit-reversed direction
/// numbers; bit `k` of that byte is bit `31 - 8 j - k` of the index).
const fn byte_tables(reversed: bool) -> [[u32; 256]; 4] {
    let v = sobol_1_directions();
    let mut t = [[0u32; 256]; 4];
    let mut j = 0;
    while j < 4 {
        let mut b = 0;
        while b < 256 {
            let mut x = 0u32;
            let mut bit = 0;
            while bit < 8 {
                if (b >> bit) & 1 == 1 {
                    x ^= if reversed { v[31 - 8 * j - bit].reverse_bits() } else { v[8 * j + bit] };
                }
                bit += 1;
            }
            t[j][b] = x;
            b += 1;
        }
        j += 1;
    }
    t
}

/// Dimensions `2 pair` and `2 pair + 1` of Owen-scrambled Sobol point
/// `index` of the sequence keyed by `key` (a hash of seed and pixel), as
/// 32-bit fixed-point values (value / 2^32 in [0, 1)), given
/// `index_reversed = index.reverse_bits()`:
/// - `h = hash(key, pair)`; the index is shuffled by
///   `nested_uniform_scramble(index, h mod 2^32)`;
/// - the Sobol point (dimensions 0 and 1) of the shuffled index is taken;
/// - its components are scrambled by `nested_uniform_scramble` with the low
///   and high halves of `hash(h)`.
///
/// ```
/// use niebla::sampling::sobol::{owen_scrambled_sobol_pair, nested_uniform_scramble, sobol_2d};
/// use niebla::sampling::hash_u64;
/// let (key, index, pair) = (12345u64, 77u32, 3u64);
/// let h = hash_u64(key ^ pair.wrapping_mul(0xD6E8_FEB8_6659_FD93));
/// let point = sobol_2d(nested_uniform_scramble(index, h as u32));
/// let seeds = hash_u64(h);
/// let expected = [
///     nested_uniform_scramble(point[0], seeds as u32),
///     nested_uniform_scramble(point[1], (seeds >> 32) as u32),
/// ];
/// assert_eq!(owen_scrambled_sobol_pair(key, index.reverse_bits(), pair), expected);
/// ```
#[inline]
pub fn owen_scrambled_sobol_pair(key: u64, index_reversed: u32, pair: u64) -> [u32; 2] {
    let h = hash_u64(key ^ pair.wrapping_mul(0xD6E8_FEB8_6659_FD93));
    // The shuffled index, bit-reversed: its van der Corput value.
    let x0 = laine_karras_permutation(index_reversed, h as u32);
    let b = x0.to_le_bytes();
    // Sobol dimension 1 of the shuffled index, bit-reversed.
    let y_reversed = SOBOL_1_REVERSED_TABLE[0][b[0] as usize]
        ^ SOBOL_1_REVERSED_TABLE[1][b[1] as usize]
        ^ SOBOL_1_REVERSED_TABLE[2][b[2] as usize]
        ^ SOBOL_1_REVERSED_TABLE[3][b[3] as usize];
    let seeds = hash_u64(h);
    [
        laine_karras_permutation(x0.reverse_bits(), seeds as u32).reverse_bits(),
        laine_karras_permutation(y_reversed, (seeds >> 32) as u32).reverse_bits(),
    ]
}

/// Dimension `dimension` of Owen-scrambled Sobol point `index` of the
/// sequence keyed by `key`: component `dimension mod 2` of
/// [`owen_scrambled_sobol_pair`] for pair `dimension / 2` (see the module
/// documentation).
#[inline]
pub fn owen_scrambled_sobol_1d(key: u64, index: u32, dimension: u64) -> u32 {
    owen_scrambled_sobol_pair(key, index.reverse_bits(), dimension >> 1)[(dimension & 1) as usize]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direction numbers by the Joe-Kuo recurrence for `x + 1` (s = 1,
    /// m_1 = 1): m_k = 2 m_{k-1} ^ m_{k-1}, v_k = m_k 2^(32-k).
    #[test]
    fn dimension_1_matches_the_joe_kuo_recurrence() {
        let mut m = vec![1u64];
        for k in 1..32 {
            m.push((m[k - 1] << 1) ^ m[k - 1]);
        }
        let v: Vec<u32> = (0..32).map(|k| (m[k] << (31 - k)) as u32).collect();
        assert_eq!(&v[..], &sobol_1_directions()[..]);
        for index in [0u32, 1, 2, 3, 77, 1 << 20, 0xdead_beef, u32::MAX] {
            let mut y = 0;
            for (bit, d) in v.iter().enumerate() {
                if (index >> bit) & 1 == 1 {
                    y ^= d;
                }
            }
            assert_eq!(sobol_2d(index)[1], y, "index {index}");
        }
    }

    #[test]
    fn hash_permutations_are_nested_bijections() {
        // Bijective on 16-bit values embedded in the high bits, and bit j
        // (from the top) of the scramble depends only on bits above and at j:
        // values sharing their top k bits stay together.
        for seed in [0u32, 1, 0x1234_5678, u32::MAX] {
            let mut seen = std::collections::HashSet::new();
            for v in 0..1u32 << 16 {
                let s = nested_uniform_scramble(v << 16, seed);
                assert!(seen.insert(s >> 16), "seed {seed}: collision at {v}");
                for k in [1, 5, 12] {
                    let w = (v << 16) ^ (1 << (31 - k));
                    assert_eq!(s >> (32 - k), nested_uniform_scramble(w, seed) >> (32 - k));
                }
            }
        }
    }

    #[test]
    fn pairs_are_scrambled_sobol_points_of_the_shuffled_index() {
        // The table of bit-reversed values against the definition.
        for key in [0u64, 99, u64::MAX] {
            for index in [0u32, 1, 5, 1000, 0x8000_0001, u32::MAX] {
                for pair in 0..4u64 {
                    let h = hash_u64(key ^ pair.wrapping_mul(0xD6E8_FEB8_6659_FD93));
                    let point = sobol_2d(nested_uniform_scramble(index, h as u32));
                    let seeds = hash_u64(h);
                    let expected = [
                        nested_uniform_scramble(point[0], seeds as u32),
                        nested_uniform_scramble(point[1], (seeds >> 32) as u32),
                    ];
                    assert_eq!(owen_scrambled_sobol_pair(key, index.reverse_bits(), pair), expected);
                    assert_eq!(owen_scrambled_sobol_1d(key, index, 2 * pair + 1), expected[1]);
                }
            }
        }
    }
}
