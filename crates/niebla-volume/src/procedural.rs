//! Procedural densities: seeded fractal noise shaped into a cumulus cloud or
//! a rising plume, baked into a [`DenseGrid`] over the unit box, so that
//! examples and tests need no files.
//!
//! The noise is gradient noise (Perlin 2002, "Improving noise") summed over
//! octaves as fractional Brownian motion (Musgrave, "Texturing and Modeling",
//! chapter 16). Every octave has its own permutation table and lattice
//! offset drawn from the seed by SplitMix64, so a grid depends on its
//! parameters only: the same parameters give the same grid, bit for bit,
//! on every run and thread count.
//!
//! Shapes, with y up, in the unit box `[0, 1]^3`:
//! - [`ProceduralShape::Cloud`]: a flattened ellipsoid, wider than tall,
//!   squashed below its base height so that the bottom is flat-ish, whose
//!   edge is eroded by the noise, more on top (billows) than at the base.
//! - [`ProceduralShape::Plume`]: a vertical column rising from the bottom
//!   face, widening and thinning with height, its axis swayed and its
//!   cross-section twisted by low-frequency noise and eroded by the fBm;
//!   densest at its base.
//!
//! Both are a signed "inside" field `s` (1 on the core, 0 on the shape's
//! surface, negative outside), plus noise `e * n` (`n` the fBm in `[-1, 1]`,
//! `e` the erosion strength), minus a threshold set by `coverage`, times
//! `sharpness`, clamped to `[0, 1]`, and multiplied by a window that is
//! exactly zero within one voxel of each face. Voxels that no noise value
//! can make positive are never evaluated, which keeps bakes fast.

use crate::{DenseGrid, VolumeError};

/// Shape of a procedural density.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ProceduralShape {
    /// A cumulus-like blob: wider than tall, flat-ish bottom, eroded edge.
    #[default]
    Cloud,
    /// A rising column (y up), dense at the base, widening, thinning and
    /// turbulent with height.
    Plume,
}

/// Parameters of [`procedural_density`]; see each field for its range and
/// default.
///
/// ```
/// use niebla_volume::{procedural_density, ProceduralParams, ProceduralShape};
/// let params = ProceduralParams {
///     shape: ProceduralShape::Plume,
///     seed: 7,
///     resolution: [32, 48, 32],
///     ..ProceduralParams::default()
/// };
/// let grid = procedural_density(&params)?;
/// assert_eq!(grid.dims(), [32, 48, 32]);
/// assert!(grid.max_value() <= 1.0);
/// # Ok::<(), niebla_volume::VolumeError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct ProceduralParams {
    /// Cloud or plume. Default: [`ProceduralShape::Cloud`].
    pub shape: ProceduralShape,
    /// Seed of the noise; any value. Equal seeds (with equal other
    /// parameters) give identical grids. Default: 0.
    pub seed: u64,
    /// Voxels of the baked grid along x, y, z (y up), each in `1..=1024`
    /// with at most 2^28 in all. The first and last voxel along each axis
    /// are always zero, so each should be at least 3. Default: `[64; 3]`.
    pub resolution: [usize; 3],
    /// Octaves of fBm noise, in `1..=12`; each adds detail `lacunarity`
    /// times finer and costs one more noise evaluation per voxel.
    /// Default: 5.
    pub octaves: u32,
    /// Base noise frequency in cycles per unit box, finite in `(0, 1000]`:
    /// about how many blobs fit across the box. Default: 3.
    pub frequency: f32,
    /// Frequency ratio between successive octaves, finite in `[1, 8]`.
    /// Default: 2.
    pub lacunarity: f32,
    /// Amplitude ratio between successive octaves, in `[0, 1]`: higher is
    /// rougher. Default: 0.5.
    pub gain: f32,
    /// How much of the shape is filled, in `[0, 1]`: 0 is empty, 1 fills
    /// the whole shape (and its eroded fringe, up to the box's faces).
    /// Default: 0.5.
    pub coverage: f32,
    /// Edge sharpness, finite in `(0, 1000]`: the density rises from 0 to 1
    /// over a band `1 / sharpness` wide in the shape's inside field (1 at
    /// the core, 0 on the surface), so 1 gives soft gradients and 50 nearly
    /// hard edges. Default: 4.
    pub sharpness: f32,
}

impl Default for ProceduralParams {
    fn default() -> Self {
        ProceduralParams {
            shape: ProceduralShape::Cloud,
            seed: 0,
            resolution: [64; 3],
            octaves: 5,
            frequency: 3.0,
            lacunarity: 2.0,
            gain: 0.5,
            coverage: 0.5,
            sharpness: 4.0,
        }
    }
}

impl ProceduralParams {
    /// Checks every parameter against its documented range; the error
    /// names the first one out of range.
    pub fn validate(&self) -> Result<(), VolumeError> {
        let fail = |parameter: &'static str, value: String, expected: &'static str| {
            Err(VolumeError::InvalidParameter { parameter, value, expected })
        };
        if self.resolution.iter().any(|r| !(1..=1024).contains(r)) {
            return fail("resolution", format!("{:?}", self.resolution), "each axis in 1..=1024");
        }
        if self.resolution.iter().product::<usize>() > 1 << 28 {
            return fail("resolution", format!("{:?}", self.resolution), "at most 2^28 voxels in all");
        }
        if !(1..=12).contains(&self.octaves) {
            return fail("octaves", self.octaves.to_string(), "an integer in 1..=12");
        }
        let in_range =
            |v: f32, lo: f32, hi: f32, open_lo: bool| v.is_finite() && v <= hi && (v > lo || (!open_lo && v == lo));
        if !in_range(self.frequency, 0.0, 1000.0, true) {
            return fail("frequency", self.frequency.to_string(), "a finite value in (0, 1000]");
        }
        if !in_range(self.lacunarity, 1.0, 8.0, false) {
            return fail("lacunarity", self.lacunarity.to_string(), "a finite value in [1, 8]");
        }
        if !in_range(self.gain, 0.0, 1.0, false) {
            return fail("gain", self.gain.to_string(), "a value in [0, 1]");
        }
        if !in_range(self.coverage, 0.0, 1.0, false) {
            return fail("coverage", self.coverage.to_string(), "a value in [0, 1]");
        }
        if !in_range(self.sharpness, 0.0, 1000.0, true) {
            return fail("sharpness", self.sharpness.to_string(), "a finite value in (0, 1000]");
        }
        Ok(())
    }
}

/// Bakes the density described by `params` over the unit box `[0, 1]^3`
/// (y up) at `params.resolution` voxel centers: values in `[0, 1]`, zero
/// on the voxels next to each face. Single-threaded (bake times are printed
/// by `benches/lookup.rs`; figures in ARCHITECTURE.md).
///
/// ```
/// use niebla_volume::{procedural_density, MajorantGrid, ProceduralParams};
/// let grid = procedural_density(&ProceduralParams::default())?;
/// assert_eq!(grid.bounds(), ([0.0; 3], [1.0; 3]));
/// // Empty space near the faces: the majorant grid's corner cell is zero.
/// let majorants = MajorantGrid::from_dense(&grid, [16; 3]);
/// assert_eq!(majorants.value(0, 0, 0), 0.0);
/// # Ok::<(), niebla_volume::VolumeError>(())
/// ```
pub fn procedural_density(params: &ProceduralParams) -> Result<DenseGrid, VolumeError> {
    params.validate()?;
    let [nx, ny, nz] = params.resolution;
    let field = Field::new(params);
    let windows: [Vec<f32>; 3] = std::array::from_fn(|a| face_window(params.resolution[a]));
    let centers: [Vec<f32>; 3] = std::array::from_fn(|a| {
        let n = params.resolution[a];
        (0..n).map(|i| (i as f32 + 0.5) / n as f32).collect()
    });
    let mut data = vec![0f32; nx * ny * nz];
    for z in 0..nz {
        for y in 0..ny {
            let w_zy = windows[2][z] * windows[1][y];
            if w_zy == 0.0 {
                continue;
            }
            let row = &mut data[(z * ny + y) * nx..][..nx];
            for (x, out) in row.iter_mut().enumerate() {
                let w = w_zy * windows[0][x];
                if w > 0.0 {
                    *out = w * field.density([centers[0][x], centers[1][y], centers[2][z]]);
                }
            }
        }
    }
    DenseGrid::new(params.resolution, data, [0.0; 3], [1.0; 3])
}

/// Per-voxel window along one axis of `n` voxels: 0 within one voxel of
/// either face (so the face voxels are exactly zero), rising smoothly to 1
/// over the next 5% of the box.
fn face_window(n: usize) -> Vec<f32> {
    let start = 1.0 / n as f32;
    (0..n)
        .map(|i| {
            let p = (i as f32 + 0.5) / n as f32;
            let distance = p.min(1.0 - p);
            smoothstep(start, start + 0.05, distance)
        })
        .collect()
}

#[inline(always)]
fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Noise amplitude in units of the inside field `s`: the fringe the noise
/// can add to or erode from a shape.
const EROSION: f32 = 0.3;
/// Scale from normalized fBm (about +-0.2 standard deviation for gradient
/// noise) to the `[-1, 1]` range that [`EROSION`] multiplies.
const NOISE_GAIN: f32 = 2.0;

/// Cloud: base height of the ellipsoid's center and its semi-axes
/// (horizontal, above and below the base).
const CLOUD_BASE: f32 = 0.34;
const CLOUD_RADIUS: f32 = 0.66;
const CLOUD_ABOVE: f32 = 0.62;
const CLOUD_BELOW: f32 = 0.16;

/// Plume: source height, radius of the column at the source and at the top,
/// sway of the axis at the top (box units), twist of the noise domain over
/// the plume's height (radians).
const PLUME_SOURCE: f32 = 0.04;
const PLUME_RADIUS_BASE: f32 = 0.2;
const PLUME_RADIUS_TOP: f32 = 0.62;
const PLUME_SWAY: f32 = 0.12;
const PLUME_TWIST: f32 = 2.5;

/// A shape with its noise, ready to evaluate.
struct Field {
    shape: ProceduralShape,
    fbm: Fbm,
    /// Two single-octave noises for the plume's swaying axis.
    sway: [Fbm; 2],
    /// Threshold on `s + e n`: `1 + EROSION` (empty) at coverage 0,
    /// `-EROSION` (whole shape) at coverage 1.
    threshold: f32,
    sharpness: f32,
}

impl Field {
    fn new(params: &ProceduralParams) -> Field {
        let mut rng = SplitMix64(params.seed);
        let fbm = Fbm::new(&mut rng, params);
        let sway = std::array::from_fn(|_| {
            Fbm::new(&mut rng, &ProceduralParams { octaves: 2, frequency: params.frequency * 0.5, ..params.clone() })
        });
        Field {
            shape: params.shape,
            fbm,
            sway,
            threshold: 1.0 + EROSION - params.coverage * (1.0 + 2.0 * EROSION),
            sharpness: params.sharpness,
        }
    }

    /// Density at unit-box point `p`, in `[0, 1]` (before the face window).
    #[inline]
    fn density(&self, p: [f32; 3]) -> f32 {
        match self.shape {
            ProceduralShape::Cloud => self.cloud(p),
            ProceduralShape::Plume => self.plume(p),
        }
    }

    /// `sharpness * (s + e n - threshold)` clamped to `[0, 1]`, without
    /// evaluating the noise `n` when no `n` in `[-1, 1]` can make it
    /// positive.
    #[inline(always)]
    fn erode(&self, s: f32, e: f32, threshold: f32, noise: impl FnOnce() -> f32) -> f32 {
        if s + e - threshold <= 0.0 {
            return 0.0;
        }
        (self.sharpness * (s + e * noise() - threshold)).clamp(0.0, 1.0)
    }

    fn cloud(&self, p: [f32; 3]) -> f32 {
        let q = [p[0] - 0.5, p[1] - CLOUD_BASE, p[2] - 0.5];
        let vertical = if q[1] < 0.0 { CLOUD_BELOW } else { CLOUD_ABOVE };
        let d = ((q[0] * q[0] + q[2] * q[2]) / (CLOUD_RADIUS * CLOUD_RADIUS) + (q[1] / vertical) * (q[1] / vertical))
            .sqrt();
        // Erosion grows with height: a flat base, billowing top.
        let height = ((q[1] + CLOUD_BELOW) / (CLOUD_BELOW + CLOUD_ABOVE)).clamp(0.0, 1.0);
        let e = EROSION * (0.35 + 0.65 * height);
        self.erode(1.0 - d, e, self.threshold, || self.fbm.eval(p))
    }

    fn plume(&self, p: [f32; 3]) -> f32 {
        if p[1] <= PLUME_SOURCE {
            return 0.0;
        }
        let h = (p[1] - PLUME_SOURCE) / (1.0 - PLUME_SOURCE);
        let radius = PLUME_RADIUS_BASE + (PLUME_RADIUS_TOP - PLUME_RADIUS_BASE) * h.powf(0.7);
        // Thinner with height: fainter, and harder to fill.
        let fade = (1.0 - h) * (1.0 - h).sqrt();
        let threshold = self.threshold + 0.2 * h;
        // Cheap test before the sway noise: the axis moves by at most
        // `PLUME_SWAY * h` per axis.
        let (dx, dz) = (p[0] - 0.5, p[2] - 0.5);
        let reach = PLUME_SWAY * h * std::f32::consts::SQRT_2;
        let rho_min = ((dx * dx + dz * dz).sqrt() - reach).max(0.0);
        if 1.0 - rho_min / radius + EROSION - threshold <= 0.0 {
            return 0.0;
        }
        // Turbulent axis, and a noise domain twisted about it.
        let (sx, sz) = (PLUME_SWAY * h * self.sway[0].eval(p), PLUME_SWAY * h * self.sway[1].eval(p));
        let (dx, dz) = (dx - sx, dz - sz);
        let rho = (dx * dx + dz * dz).sqrt();
        let (sin, cos) = (PLUME_TWIST * h).sin_cos();
        let twisted = [0.5 + cos * dx - sin * dz, p[1], 0.5 + sin * dx + cos * dz];
        let core = self.erode(1.0 - rho / radius, EROSION, threshold, || self.fbm.eval(twisted));
        core * fade
    }
}

/// Fractional Brownian motion: octaves of gradient noise, normalized by
/// the sum of their amplitudes, scaled by [`NOISE_GAIN`] and clamped to
/// `[-1, 1]`.
struct Fbm {
    octaves: Vec<GradientNoise>,
    frequency: f64,
    lacunarity: f64,
    gain: f32,
    /// `NOISE_GAIN / sum of amplitudes`.
    scale: f32,
}

impl Fbm {
    fn new(rng: &mut SplitMix64, params: &ProceduralParams) -> Fbm {
        let octaves = (0..params.octaves).map(|_| GradientNoise::new(rng)).collect();
        let amplitude_sum: f32 = (0..params.octaves).map(|o| params.gain.powi(o as i32)).sum();
        Fbm {
            octaves,
            frequency: params.frequency as f64,
            lacunarity: params.lacunarity as f64,
            gain: params.gain,
            scale: NOISE_GAIN / amplitude_sum,
        }
    }

    #[inline]
    fn eval(&self, p: [f32; 3]) -> f32 {
        let (mut sum, mut amplitude, mut frequency) = (0.0f32, 1.0f32, self.frequency);
        for octave in &self.octaves {
            sum += amplitude * octave.eval(p.map(|v| v as f64 * frequency));
            amplitude *= self.gain;
            frequency *= self.lacunarity;
        }
        (sum * self.scale).clamp(-1.0, 1.0)
    }
}

/// Improved Perlin noise (Perlin 2002) with a permutation table shuffled
/// from a seed and a random lattice offset (so that octaves do not all
/// vanish at the origin). Period 256 lattice cells.
struct GradientNoise {
    perm: [u8; 512],
    offset: [f64; 3],
}

impl GradientNoise {
    fn new(rng: &mut SplitMix64) -> GradientNoise {
        let mut table: [u8; 256] = std::array::from_fn(|i| i as u8);
        // Fisher-Yates.
        for i in (1..256).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            table.swap(i, j);
        }
        let offset = std::array::from_fn(|_| (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64);
        GradientNoise { perm: std::array::from_fn(|i| table[i & 255]), offset: offset.map(|u| 256.0 * u) }
    }

    /// Noise at lattice coordinates `x`, in about `[-1, 1]`; zero at
    /// lattice points (before the offset).
    #[inline(always)]
    fn eval(&self, x: [f64; 3]) -> f32 {
        let x = [0, 1, 2].map(|a| x[a] + self.offset[a]);
        let cell = x.map(f64::floor);
        let i = cell.map(|c| (c as i64 & 255) as usize);
        let [x, y, z] = [0, 1, 2].map(|a| (x[a] - cell[a]) as f32);
        let [u, v, w] = [x, y, z].map(fade);
        let p = &self.perm;
        let a = p[i[0]] as usize + i[1];
        let aa = p[a] as usize + i[2];
        let ab = p[a + 1] as usize + i[2];
        let b = p[i[0] + 1] as usize + i[1];
        let ba = p[b] as usize + i[2];
        let bb = p[b + 1] as usize + i[2];
        let (x1, y1, z1) = (x - 1.0, y - 1.0, z - 1.0);
        lerp(
            w,
            lerp(
                v,
                lerp(u, grad(p[aa], x, y, z), grad(p[ba], x1, y, z)),
                lerp(u, grad(p[ab], x, y1, z), grad(p[bb], x1, y1, z)),
            ),
            lerp(
                v,
                lerp(u, grad(p[aa + 1], x, y, z1), grad(p[ba + 1], x1, y, z1)),
                lerp(u, grad(p[ab + 1], x, y1, z1), grad(p[bb + 1], x1, y1, z1)),
            ),
        )
    }
}

/// Perlin's quintic fade `6t^5 - 15t^4 + 10t^3`.
#[inline(always)]
fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline(always)]
fn lerp(t: f32, a: f32, b: f32) -> f32 {
    a + t * (b - a)
}

/// Dot product with one of Perlin's 12 edge gradients (16 entries, four
/// repeated), chosen by the low bits of `hash`.
#[inline(always)]
fn grad(hash: u8, x: f32, y: f32, z: f32) -> f32 {
    let h = hash & 15;
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h == 12 || h == 14 {
        x
    } else {
        z
    };
    (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
}

/// SplitMix64 (Steele, Lea and Flood 2014): the seed's random stream.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradient_noise_vanishes_on_lattice_points_and_stays_bounded() {
        let mut rng = SplitMix64(3);
        let noise = GradientNoise::new(&mut rng);
        let o = noise.offset;
        for k in 0..50 {
            let lattice = [k as f64, (k * 7 % 13) as f64, (k * 3 % 5) as f64];
            // Shifted back onto the lattice (up to rounding of the offset).
            let v = noise.eval([0, 1, 2].map(|a| lattice[a] - o[a]));
            assert!(v.abs() < 1e-3, "{v} at lattice point {lattice:?}");
        }
        let mut max = 0f32;
        for k in 0..100_000 {
            let t = k as f64 * 0.0137;
            let v = noise.eval([t, t * 0.71 + 3.3, t * 1.37 - 8.1]);
            max = max.max(v.abs());
        }
        assert!(max <= 1.1 && max > 0.5, "max |noise| {max}");
    }
}
