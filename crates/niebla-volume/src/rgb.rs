//! Three-channel (RGB) dense grids, as stored in 3-channel Mitsuba `.vol`
//! files and `(nz, ny, nx, 3)` `.npy` arrays, and the [`DenseVolume`] enum
//! that the dense file readers return.
//!
//! Same conventions as [`DenseGrid`]: local-space box, values at cell
//! centers, `[z][y][x]` with x fastest, clamp within half a cell of a face,
//! zero outside.

use crate::dense::{trilinear, BoxMapping, Stencil};
use crate::{DenseGrid, VolumeError};

/// A dense grid of RGB triples (linear Rec.709 when it holds color).
///
/// ```
/// use niebla_volume::DenseRgbGrid;
/// let g = DenseRgbGrid::new([1, 1, 2], vec![[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
///                           [0.0; 3], [1.0; 3]).unwrap();
/// assert_eq!(g.lookup([0.5, 0.5, 0.5]), [0.5, 0.0, 0.5]);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct DenseRgbGrid {
    mapping: BoxMapping,
    data: Vec<[f32; 3]>,
    max_value: [f32; 3],
}

impl DenseRgbGrid {
    /// A grid of `dims = [nx, ny, nz]` RGB values indexed `[z][y][x]`,
    /// filling the local-space box `bounds_min..bounds_max`.
    pub fn new(
        dims: [usize; 3],
        data: Vec<[f32; 3]>,
        bounds_min: [f32; 3],
        bounds_max: [f32; 3],
    ) -> Result<Self, VolumeError> {
        let mapping = BoxMapping::new(dims, bounds_min, bounds_max, data.len())?;
        let mut max_value = [f32::NEG_INFINITY; 3];
        for v in &data {
            for c in 0..3 {
                max_value[c] = max_value[c].max(v[c]);
            }
        }
        Ok(Self { mapping, data, max_value })
    }

    /// The same values mapped to another local-space box.
    pub fn with_bounds(self, bounds_min: [f32; 3], bounds_max: [f32; 3]) -> Result<Self, VolumeError> {
        let mapping = BoxMapping::new(self.dims(), bounds_min, bounds_max, self.data.len())?;
        Ok(Self { mapping, ..self })
    }

    /// `[nx, ny, nz]`.
    pub fn dims(&self) -> [usize; 3] {
        self.mapping.dims
    }

    /// The local-space box `(bounds_min, bounds_max)` the grid fills.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        (self.mapping.bounds_min, self.mapping.bounds_max)
    }

    /// The stored values, `[z][y][x]` with x fastest.
    pub fn values(&self) -> &[[f32; 3]] {
        &self.data
    }

    /// Per-channel largest stored value.
    pub fn max_value(&self) -> [f32; 3] {
        self.max_value
    }

    /// The value stored for cell `(x, y, z)`; panics out of range.
    pub fn voxel(&self, x: usize, y: usize, z: usize) -> [f32; 3] {
        let [nx, ny, nz] = self.dims();
        assert!(x < nx && y < ny && z < nz, "voxel ({x}, {y}, {z}) outside {:?}", self.dims());
        self.data[self.mapping.index(x, y, z)]
    }

    /// Trilinearly interpolated RGB value at local-space point `p` (zero
    /// outside the box).
    #[inline]
    pub fn lookup(&self, p: [f32; 3]) -> [f32; 3] {
        let Some(s) = self.mapping.stencil(p) else {
            return [0.0; 3];
        };
        std::array::from_fn(|c| trilinear_channel(&self.data, &s, c))
    }

    /// Channel `c` (0 = R, 1 = G, 2 = B) as a scalar grid.
    pub fn channel(&self, c: usize) -> DenseGrid {
        assert!(c < 3, "channel {c} of an RGB grid");
        self.map_to_scalar(|v| v[c])
    }

    /// The per-cell maximum over the channels: a scalar grid whose
    /// majorant bounds every channel (chromatic media sample with it).
    pub fn max_channel(&self) -> DenseGrid {
        self.map_to_scalar(|v| v[0].max(v[1]).max(v[2]))
    }

    fn map_to_scalar(&self, f: impl Fn(&[f32; 3]) -> f32) -> DenseGrid {
        let data = self.data.iter().map(f).collect();
        let (lo, hi) = self.bounds();
        DenseGrid::new(self.dims(), data, lo, hi).expect("same shape as a valid grid")
    }
}

/// Channel `c` of an interleaved RGB array, interpolated on stencil `s`.
#[inline(always)]
fn trilinear_channel(data: &[[f32; 3]], s: &Stencil, c: usize) -> f32 {
    // Gather the 8 corners of one channel, then reuse the scalar kernel.
    let d = data;
    let [sx, sy, sz] = s.step;
    let b = s.base;
    let corners = [
        d[b][c],
        d[b + sx][c],
        d[b + sy][c],
        d[b + sy + sx][c],
        d[b + sz][c],
        d[b + sz + sx][c],
        d[b + sz + sy][c],
        d[b + sz + sy + sx][c],
    ];
    let local = Stencil { base: 0, step: [1, 2, 4], frac: s.frac };
    trilinear(&corners, &local)
}

/// A dense grid read from a file: scalar or RGB.
#[derive(Clone, Debug, PartialEq)]
pub enum DenseVolume {
    /// One channel.
    Scalar(DenseGrid),
    /// Three channels.
    Rgb(DenseRgbGrid),
}

impl DenseVolume {
    /// `[nx, ny, nz]`.
    pub fn dims(&self) -> [usize; 3] {
        match self {
            DenseVolume::Scalar(g) => g.dims(),
            DenseVolume::Rgb(g) => g.dims(),
        }
    }

    /// The local-space box the grid fills.
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        match self {
            DenseVolume::Scalar(g) => g.bounds(),
            DenseVolume::Rgb(g) => g.bounds(),
        }
    }

    /// Number of channels (1 or 3).
    pub fn channels(&self) -> usize {
        match self {
            DenseVolume::Scalar(_) => 1,
            DenseVolume::Rgb(_) => 3,
        }
    }

    /// The same values mapped to another local-space box.
    pub fn with_bounds(self, bounds_min: [f32; 3], bounds_max: [f32; 3]) -> Result<Self, VolumeError> {
        Ok(match self {
            DenseVolume::Scalar(g) => DenseVolume::Scalar(g.with_bounds(bounds_min, bounds_max)?),
            DenseVolume::Rgb(g) => DenseVolume::Rgb(g.with_bounds(bounds_min, bounds_max)?),
        })
    }

    /// The scalar grid, or `None` for RGB data.
    pub fn into_scalar(self) -> Option<DenseGrid> {
        match self {
            DenseVolume::Scalar(g) => Some(g),
            DenseVolume::Rgb(_) => None,
        }
    }

    /// A scalar grid that bounds every channel: the grid itself, or the
    /// per-cell maximum over the channels of an RGB grid.
    pub fn max_channel(&self) -> DenseGrid {
        match self {
            DenseVolume::Scalar(g) => g.clone(),
            DenseVolume::Rgb(g) => g.max_channel(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgb_lookup_matches_per_channel_scalar_lookup() {
        let data: Vec<[f32; 3]> = (0..27).map(|i| [i as f32, (i * 7 % 5) as f32, 1.0 / (1.0 + i as f32)]).collect();
        let g = DenseRgbGrid::new([3, 3, 3], data, [0.0; 3], [1.0, 2.0, 3.0]).unwrap();
        for p in [[0.1, 0.2, 0.3], [0.5, 1.0, 1.5], [0.9, 1.9, 2.9], [0.33, 0.77, 2.2]] {
            let rgb = g.lookup(p);
            for (c, &value) in rgb.iter().enumerate() {
                assert!((value - g.channel(c).lookup(p)).abs() < 1e-6);
            }
            let m = g.max_channel().lookup(p);
            assert!(m + 1e-6 >= rgb[0].max(rgb[1]).max(rgb[2]));
        }
        assert_eq!(g.lookup([1.5, 0.0, 0.0]), [0.0; 3]);
        assert_eq!(g.max_value(), [26.0, 4.0, 1.0]);
    }
}
