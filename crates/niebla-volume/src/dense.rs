//! Dense scalar grids: `nx * ny * nz` values at cell centers of an
//! axis-aligned box, read by trilinear interpolation.
//!
//! Conventions (Mitsuba 3's, fixed by the project's design):
//! - The grid lives in its own *local* space; `bounds_min..bounds_max` is the
//!   box it fills. Cell `(x, y, z)` has its value at the cell center
//!   `bounds_min + (x + 0.5, y + 0.5, z + 0.5) * cell_size`.
//! - Storage is indexed `[z][y][x]` with x fastest:
//!   `index = (z * ny + y) * nx + x`.
//! - Within half a cell of a face the nearest cells' values extend to the
//!   face (clamp); outside the closed box the value is zero.

use half::f16;

use crate::VolumeError;

/// The values of a dense grid, as 32-bit or 16-bit floats.
#[derive(Clone, Debug, PartialEq)]
pub enum GridStorage {
    /// IEEE single precision.
    F32(Vec<f32>),
    /// IEEE half precision (about 3 significant digits, max 65504): half the
    /// memory, values rounded on conversion.
    F16(Vec<f16>),
}

impl GridStorage {
    /// Number of values.
    pub fn len(&self) -> usize {
        match self {
            GridStorage::F32(v) => v.len(),
            GridStorage::F16(v) => v.len(),
        }
    }

    /// Whether there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Value `i` as f32.
    pub fn get(&self, i: usize) -> f32 {
        match self {
            GridStorage::F32(v) => v[i],
            GridStorage::F16(v) => v[i].to_f32(),
        }
    }
}

/// A stored voxel value type that converts to f32.
pub(crate) trait VoxelValue: Copy {
    fn to_f32(self) -> f32;
}

impl VoxelValue for f32 {
    #[inline(always)]
    fn to_f32(self) -> f32 {
        self
    }
}

impl VoxelValue for f16 {
    #[inline(always)]
    fn to_f32(self) -> f32 {
        f16::to_f32(self)
    }
}

/// Where a point falls among the cell centers of a box-mapped grid: the
/// lowest of the 8 neighbouring cells, the index steps to the others (0 along
/// an axis with a single cell) and the interpolation weights.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stencil {
    pub base: usize,
    pub step: [usize; 3],
    pub frac: [f32; 3],
}

/// The mapping from a box in local space to `dims` cells, shared by the
/// scalar and RGB dense grids.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct BoxMapping {
    pub dims: [usize; 3],
    pub bounds_min: [f32; 3],
    pub bounds_max: [f32; 3],
    /// Cells per unit length along each axis.
    pub scale: [f32; 3],
}

impl BoxMapping {
    pub(crate) fn new(
        dims: [usize; 3],
        bounds_min: [f32; 3],
        bounds_max: [f32; 3],
        values: usize,
    ) -> Result<Self, VolumeError> {
        if dims.contains(&0) {
            return Err(VolumeError::invalid(format!("grid dimensions {dims:?} contain a zero")));
        }
        let count = dims[0]
            .checked_mul(dims[1])
            .and_then(|n| n.checked_mul(dims[2]))
            .ok_or_else(|| VolumeError::invalid(format!("grid dimensions {dims:?} overflow")))?;
        if count != values {
            return Err(VolumeError::invalid(format!("grid dimensions {dims:?} need {count} values, got {values}")));
        }
        for a in 0..3 {
            let (lo, hi) = (bounds_min[a], bounds_max[a]);
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(VolumeError::invalid(format!(
                    "bounds {bounds_min:?}..{bounds_max:?} are not a finite box with min < max"
                )));
            }
        }
        let scale = std::array::from_fn(|a| dims[a] as f32 / (bounds_max[a] - bounds_min[a]));
        Ok(Self { dims, bounds_min, bounds_max, scale })
    }

    /// The interpolation stencil at local point `p`, or `None` outside the
    /// closed box (or for NaN coordinates).
    #[inline(always)]
    pub(crate) fn stencil(&self, p: [f32; 3]) -> Option<Stencil> {
        let mut cell = [0usize; 3];
        let mut frac = [0f32; 3];
        let mut step = [0usize; 3];
        let strides = [1, self.dims[0], self.dims[0] * self.dims[1]];
        for a in 0..3 {
            if !(p[a] >= self.bounds_min[a] && p[a] <= self.bounds_max[a]) {
                return None;
            }
            let n = self.dims[a];
            let last = (n - 1) as f32;
            // Continuous cell coordinate with centers at integers, clamped so
            // that the half cell next to each face takes the face cell's value.
            let u = ((p[a] - self.bounds_min[a]) * self.scale[a] - 0.5).clamp(0.0, last);
            let i = (u as usize).min(n.saturating_sub(2));
            cell[a] = i;
            frac[a] = u - i as f32;
            step[a] = if n > 1 { strides[a] } else { 0 };
        }
        let base = cell[0] + strides[1] * cell[1] + strides[2] * cell[2];
        Some(Stencil { base, step, frac })
    }

    /// Linear index of cell `(x, y, z)`.
    #[inline(always)]
    pub(crate) fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.dims[1] + y) * self.dims[0] + x
    }
}

#[inline(always)]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// Trilinear interpolation of `data` on stencil `s`.
#[inline(always)]
pub(crate) fn trilinear<T: VoxelValue>(data: &[T], s: &Stencil) -> f32 {
    let [sx, sy, sz] = s.step;
    let [fx, fy, fz] = s.frac;
    let b = s.base;
    let v = |i: usize| data[i].to_f32();
    let c00 = lerp(v(b), v(b + sx), fx);
    let c10 = lerp(v(b + sy), v(b + sy + sx), fx);
    let c01 = lerp(v(b + sz), v(b + sz + sx), fx);
    let c11 = lerp(v(b + sz + sy), v(b + sz + sy + sx), fx);
    lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz)
}

/// A dense scalar grid in its own local space (see the module docs for the
/// cell-centered, clamp-then-zero convention and the `[z][y][x]` layout).
///
/// ```
/// use niebla_volume::DenseGrid;
/// // 2 x 1 x 1 cells filling [0,2] x [0,1] x [0,1]: centers at x = 0.5 and 1.5.
/// let g = DenseGrid::new([2, 1, 1], vec![1.0, 3.0], [0.0; 3], [2.0, 1.0, 1.0]).unwrap();
/// assert_eq!(g.lookup([0.5, 0.5, 0.5]), 1.0);
/// assert_eq!(g.lookup([1.0, 0.5, 0.5]), 2.0);
/// assert_eq!(g.lookup([0.1, 0.5, 0.5]), 1.0); // clamped near the face
/// assert_eq!(g.lookup([2.5, 0.5, 0.5]), 0.0); // outside
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct DenseGrid {
    mapping: BoxMapping,
    data: GridStorage,
    max_value: f32,
    min_value: f32,
}

impl DenseGrid {
    /// A grid of `dims = [nx, ny, nz]` f32 values indexed `[z][y][x]`,
    /// filling the local-space box `bounds_min..bounds_max`.
    pub fn new(
        dims: [usize; 3],
        data: Vec<f32>,
        bounds_min: [f32; 3],
        bounds_max: [f32; 3],
    ) -> Result<Self, VolumeError> {
        Self::from_storage(dims, GridStorage::F32(data), bounds_min, bounds_max)
    }

    /// Like [`DenseGrid::new`] with either storage precision.
    pub fn from_storage(
        dims: [usize; 3],
        data: GridStorage,
        bounds_min: [f32; 3],
        bounds_max: [f32; 3],
    ) -> Result<Self, VolumeError> {
        let mapping = BoxMapping::new(dims, bounds_min, bounds_max, data.len())?;
        let (max_value, min_value) = match &data {
            GridStorage::F32(v) => {
                (v.iter().copied().fold(f32::NEG_INFINITY, f32::max), v.iter().copied().fold(f32::INFINITY, f32::min))
            }
            GridStorage::F16(v) => (
                v.iter().map(|x| x.to_f32()).fold(f32::NEG_INFINITY, f32::max),
                v.iter().map(|x| x.to_f32()).fold(f32::INFINITY, f32::min),
            ),
        };
        Ok(Self { mapping, data, max_value, min_value })
    }

    /// The same grid stored as half floats (values rounded to nearest).
    pub fn to_f16(&self) -> DenseGrid {
        let data = match &self.data {
            GridStorage::F32(v) => v.iter().map(|&x| f16::from_f32(x)).collect(),
            GridStorage::F16(v) => v.clone(),
        };
        Self::from_storage(self.dims(), GridStorage::F16(data), self.mapping.bounds_min, self.mapping.bounds_max)
            .expect("same shape as a valid grid")
    }

    /// The same grid stored as f32 (exact for half input).
    pub fn to_f32(&self) -> DenseGrid {
        let data = (0..self.data.len()).map(|i| self.data.get(i)).collect();
        Self::new(self.dims(), data, self.mapping.bounds_min, self.mapping.bounds_max)
            .expect("same shape as a valid grid")
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

    /// Size of one cell along each axis, in local units.
    pub fn cell_size(&self) -> [f32; 3] {
        std::array::from_fn(|a| 1.0 / self.mapping.scale[a])
    }

    /// The stored values, `[z][y][x]` with x fastest.
    pub fn storage(&self) -> &GridStorage {
        &self.data
    }

    /// Largest stored value (no interpolated value exceeds it; `-inf` never
    /// occurs since a grid has at least one cell).
    pub fn max_value(&self) -> f32 {
        self.max_value
    }

    /// Smallest stored value (no interpolated value is below it; NaN
    /// values are ignored, as by [`DenseGrid::max_value`]).
    pub fn min_value(&self) -> f32 {
        self.min_value
    }

    /// The value stored for cell `(x, y, z)`; panics out of range.
    pub fn voxel(&self, x: usize, y: usize, z: usize) -> f32 {
        let [nx, ny, nz] = self.dims();
        assert!(x < nx && y < ny && z < nz, "voxel ({x}, {y}, {z}) outside {:?}", self.dims());
        self.data.get(self.mapping.index(x, y, z))
    }

    /// The grid's f32 values with its mapping unpacked for repeated
    /// lookups ([`DenseF32Lookup`]); `None` for half-float storage.
    pub fn f32_lookup(&self) -> Option<DenseF32Lookup<'_>> {
        let GridStorage::F32(data) = &self.data else { return None };
        let m = &self.mapping;
        let strides = [1, m.dims[0], m.dims[0] * m.dims[1]];
        Some(DenseF32Lookup {
            data,
            bounds_min: m.bounds_min,
            bounds_max: m.bounds_max,
            scale: m.scale,
            last: m.dims.map(|n| (n - 1) as f32),
            top: m.dims.map(|n| n.saturating_sub(2)),
            step: std::array::from_fn(|a| if m.dims[a] > 1 { strides[a] } else { 0 }),
            row: strides[1],
            slab: strides[2],
        })
    }

    /// Trilinearly interpolated value at local-space point `p`: cell values
    /// at cell centers, clamped within half a cell of a face, 0 outside the
    /// box.
    #[inline]
    pub fn lookup(&self, p: [f32; 3]) -> f32 {
        let Some(s) = self.mapping.stencil(p) else {
            return 0.0;
        };
        match &self.data {
            GridStorage::F32(v) => trilinear(v, &s),
            GridStorage::F16(v) => trilinear(v, &s),
        }
    }
}

/// A dense f32 grid's trilinear lookup with everything that does not depend
/// on the point computed once: for the many lookups of a ray march. It gives
/// the same bits as [`DenseGrid::lookup`] (the same operations in the same
/// order), without the storage match and with the cell index truncated as
/// `u32` (the clamped coordinate is in `[0, n - 1]`).
#[derive(Clone, Copy, Debug)]
pub struct DenseF32Lookup<'a> {
    data: &'a [f32],
    bounds_min: [f32; 3],
    bounds_max: [f32; 3],
    scale: [f32; 3],
    /// `n - 1` per axis (largest continuous cell coordinate).
    last: [f32; 3],
    /// `n - 2` per axis (largest lower stencil cell; 0 for one cell).
    top: [usize; 3],
    /// Index step to the upper neighbour per axis (0 for one cell).
    step: [usize; 3],
    /// Index stride of y and of z.
    row: usize,
    slab: usize,
}

impl DenseF32Lookup<'_> {
    /// Trilinearly interpolated value at local-space point `p`, as
    /// [`DenseGrid::lookup`] (0 outside the closed box or for NaN).
    #[inline(always)]
    pub fn lookup(&self, p: [f32; 3]) -> f32 {
        let mut cell = [0usize; 3];
        let mut frac = [0f32; 3];
        for a in 0..3 {
            if !(p[a] >= self.bounds_min[a] && p[a] <= self.bounds_max[a]) {
                return 0.0;
            }
            let u = ((p[a] - self.bounds_min[a]) * self.scale[a] - 0.5).clamp(0.0, self.last[a]);
            let i = (u as u32 as usize).min(self.top[a]);
            cell[a] = i;
            frac[a] = u - i as f32;
        }
        let b = cell[0] + self.row * cell[1] + self.slab * cell[2];
        let [sx, sy, sz] = self.step;
        let [fx, fy, fz] = frac;
        let v = &self.data[b..=b + sx + sy + sz];
        let c00 = lerp(v[0], v[sx], fx);
        let c10 = lerp(v[sy], v[sy + sx], fx);
        let c01 = lerp(v[sz], v[sz + sx], fx);
        let c11 = lerp(v[sz + sy], v[sz + sy + sx], fx);
        lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp_grid() -> DenseGrid {
        // 4 x 3 x 2 cells over [-1,3] x [0,3] x [0,1]: cell size 1 x 1 x 0.5.
        let dims = [4, 3, 2];
        let data = (0..24).map(|i| (i * i % 7) as f32 + 0.25 * i as f32).collect();
        DenseGrid::new(dims, data, [-1.0, 0.0, 0.0], [3.0, 3.0, 1.0]).unwrap()
    }

    fn center(g: &DenseGrid, x: usize, y: usize, z: usize) -> [f32; 3] {
        let (lo, _) = g.bounds();
        let c = g.cell_size();
        [lo[0] + (x as f32 + 0.5) * c[0], lo[1] + (y as f32 + 0.5) * c[1], lo[2] + (z as f32 + 0.5) * c[2]]
    }

    #[test]
    fn lookup_at_cell_centers_returns_voxel_values() {
        let g = ramp_grid();
        for z in 0..2 {
            for y in 0..3 {
                for x in 0..4 {
                    let v = g.lookup(center(&g, x, y, z));
                    assert_eq!(v, g.voxel(x, y, z), "cell ({x},{y},{z})");
                }
            }
        }
    }

    #[test]
    fn storage_is_z_major_x_fastest() {
        let g = ramp_grid();
        // index = (z * ny + y) * nx + x
        assert_eq!(g.voxel(1, 2, 1), g.storage().get((3 + 2) * 4 + 1));
    }

    #[test]
    fn lookup_midway_is_the_average() {
        let g = ramp_grid();
        let a = center(&g, 1, 1, 0);
        let b = center(&g, 2, 1, 0);
        let mid = [(a[0] + b[0]) / 2.0, a[1], a[2]];
        let expected = (g.voxel(1, 1, 0) + g.voxel(2, 1, 0)) / 2.0;
        assert!((g.lookup(mid) - expected).abs() < 1e-6);
    }

    #[test]
    fn lookup_clamps_within_half_a_cell_of_faces() {
        let g = ramp_grid();
        // Corner region: every coordinate within half a cell of the low faces.
        assert_eq!(g.lookup([-1.0, 0.0, 0.0]), g.voxel(0, 0, 0));
        assert_eq!(g.lookup([-0.6, 0.3, 0.2]), g.voxel(0, 0, 0));
        // High faces.
        assert_eq!(g.lookup([3.0, 3.0, 1.0]), g.voxel(3, 2, 1));
        assert_eq!(g.lookup([2.7, 2.9, 0.9]), g.voxel(3, 2, 1));
        // Along one axis only: x clamped to the last cell, y and z at centers.
        let c = center(&g, 3, 1, 0);
        assert_eq!(g.lookup([2.8, c[1], c[2]]), g.voxel(3, 1, 0));
    }

    #[test]
    fn lookup_is_zero_outside_the_box() {
        let g = ramp_grid();
        for p in [
            [-1.001, 1.0, 0.5],
            [3.001, 1.0, 0.5],
            [0.0, -0.01, 0.5],
            [0.0, 3.01, 0.5],
            [0.0, 1.0, -1e-6],
            [0.0, 1.0, 1.5],
            [f32::NAN, 1.0, 0.5],
        ] {
            assert_eq!(g.lookup(p), 0.0, "at {p:?}");
        }
    }

    #[test]
    fn single_cell_axis_is_constant_along_that_axis() {
        let g = DenseGrid::new([2, 1, 1], vec![1.0, 3.0], [0.0; 3], [2.0, 1.0, 1.0]).unwrap();
        assert_eq!(g.lookup([1.0, 0.0, 1.0]), 2.0);
        assert_eq!(g.lookup([1.0, 0.9, 0.1]), 2.0);
    }

    #[test]
    fn f16_lookup_matches_f32_within_half_precision() {
        let g = ramp_grid();
        let h = g.to_f16();
        let mut state = 12345u32;
        for _ in 0..1000 {
            let mut p = [0f32; 3];
            for (a, pa) in p.iter_mut().enumerate() {
                state = state.wrapping_mul(1664525).wrapping_add(1013904223);
                let u = (state >> 8) as f32 / (1u32 << 24) as f32;
                let (lo, hi) = g.bounds();
                *pa = lo[a] + u * (hi[a] - lo[a]);
            }
            let (a, b) = (g.lookup(p), h.lookup(p));
            // Half has an 11-bit significand: relative rounding error <= 2^-11.
            assert!((a - b).abs() <= a.abs() * 2f32.powi(-11) + 1e-6, "{a} vs {b} at {p:?}");
        }
        assert_eq!(h.to_f32().max_value(), f16::from_f32(g.max_value()).to_f32());
    }

    /// The unpacked f32 lookup gives the same bits as the grid's own at
    /// random points in, on and around the box (single-cell axes included),
    /// and along lines crossing it.
    #[test]
    fn f32_lookup_matches_lookup_bit_for_bit() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let dims = [[7, 5, 3], [1, 4, 6], [5, 1, 1], [33, 17, 9]];
        for (k, dims) in dims.into_iter().enumerate() {
            let count = dims[0] * dims[1] * dims[2];
            let data = (0..count).map(|i| ((i * 37 + k) % 11) as f32 * 0.3 - 0.7).collect();
            let g = DenseGrid::new(dims, data, [-1.0, 0.5, -2.0], [2.0, 1.25, 3.0]).unwrap();
            let fast = g.f32_lookup().expect("f32 storage");
            let (lo, hi) = g.bounds();
            for _ in 0..20_000 {
                // Points in a box 20% larger than the grid's, some on its faces.
                let mut p: [f32; 3] = std::array::from_fn(|a| lo[a] + (hi[a] - lo[a]) * (1.4 * uniform() - 0.2));
                if uniform() < 0.1 {
                    let a = (uniform() * 3.0) as usize % 3;
                    p[a] = if uniform() < 0.5 { lo[a] } else { hi[a] };
                }
                assert_eq!(fast.lookup(p).to_bits(), g.lookup(p).to_bits(), "{dims:?} at {p:?}");
            }
            for _ in 0..200 {
                let o: [f32; 3] = std::array::from_fn(|a| lo[a] + (hi[a] - lo[a]) * (1.4 * uniform() - 0.2));
                let d: [f32; 3] = std::array::from_fn(|_| uniform() - 0.5);
                for i in 0..100 {
                    let t = i as f32 * 0.037;
                    let p = std::array::from_fn(|a| o[a] + d[a] * t);
                    assert_eq!(fast.lookup(p).to_bits(), g.lookup(p).to_bits(), "{dims:?} at {p:?}");
                }
            }
            assert_eq!(fast.lookup([f32::NAN, 1.0, 0.0]), 0.0);
        }
        assert!(g_half().f32_lookup().is_none());
    }

    fn g_half() -> DenseGrid {
        ramp_grid().to_f16()
    }

    #[test]
    fn min_value_is_the_smallest_stored_value() {
        let g = ramp_grid();
        let [nx, ny, nz] = g.dims();
        let mut min = f32::INFINITY;
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    min = min.min(g.voxel(x, y, z));
                }
            }
        }
        assert_eq!(g.min_value(), min);
        let negative = DenseGrid::new([2, 1, 1], vec![0.5, -0.25], [0.0; 3], [1.0; 3]).unwrap();
        assert_eq!(negative.min_value(), -0.25);
    }

    #[test]
    fn invalid_shapes_are_errors() {
        assert!(DenseGrid::new([2, 2, 2], vec![0.0; 7], [0.0; 3], [1.0; 3]).is_err());
        assert!(DenseGrid::new([0, 2, 2], vec![], [0.0; 3], [1.0; 3]).is_err());
        assert!(DenseGrid::new([1, 1, 1], vec![0.0], [0.0; 3], [1.0, 0.0, 1.0]).is_err());
        assert!(DenseGrid::new([usize::MAX, 2, 2], vec![], [0.0; 3], [1.0; 3]).is_err());
    }
}
