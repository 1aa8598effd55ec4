//! Majorant grids: a coarse grid of upper bounds of a density field, one
//! per cell, for trackers that need a local bound `sigma_maj` (pbrt-v4
//! section 11.4.3, `MajorantGrid`).
//!
//! A cell's value is the largest voxel value whose interpolation support
//! touches the cell: for every point `p` in the closed cell, the 8 voxels
//! that trilinear interpolation at `p` reads are included, with a margin of
//! 1/1000 voxel so that a point an ulp outside the cell (rounding in
//! `o + t d`) is still covered. Majorants are clamped below at zero.
//!
//! - Dense grids: the majorant grid covers the grid's local-space box with
//!   `res` cells ([`MajorantGrid::DEFAULT_RESOLUTION`] is 16^3).
//! - Sparse grids: the majorant grid covers, in index space, the box where
//!   the interpolated field can differ from the background
//!   ([`SparseGrid::data_bounds_index`] grown by one voxel), with cubic
//!   cells of `8 * 2^k` voxels aligned to the VDB leaves: one cell per leaf
//!   when that fits in `max_cells`, else the smallest power-of-two multiple
//!   that does. Outside that box the field is exactly the background.

use crate::{DenseGrid, SparseGrid, VolumeError, LEAF_DIM};

/// Margin, in voxels, by which each cell's interpolation support is grown.
const SUPPORT_EPSILON: f64 = 1e-3;

/// A coarse grid of per-cell bounds of a density over a box, indexed
/// `[z][y][x]`: maxima when built by [`DensityBoundGrid::from_dense`] or
/// [`DensityBoundGrid::from_sparse`] (a majorant grid), minima when built by
/// [`DensityBoundGrid::minorant_from_dense`] or
/// [`DensityBoundGrid::minorant_from_sparse`] (a minorant grid, see
/// `minorant.rs`). Both kinds share the cells and the DDA walk.
#[derive(Clone, Debug, PartialEq)]
pub struct DensityBoundGrid {
    pub(crate) res: [usize; 3],
    pub(crate) bounds_min: [f32; 3],
    pub(crate) bounds_max: [f32; 3],
    pub(crate) values: Vec<f32>,
    /// Per block of [`ZERO_BLOCK`]^3 cells (`[z][y][x]`, x fastest, the
    /// last block per axis possibly partial): whether every cell's value is
    /// exactly zero. Derived from `values` by [`DensityBoundGrid::with_zero_blocks`];
    /// [`MajorantGrid::walk_nonzero`] jumps over such blocks.
    pub(crate) zero_blocks: Vec<bool>,
    /// Per-grid constants of the DDA walk, derived from `res` and the
    /// bounds by [`DensityBoundGrid::from_parts`].
    pub(crate) walk: WalkConstants,
}

/// Constants the DDA walk of a [`DensityBoundGrid`] would otherwise
/// recompute on every walk: each is the same expression of `res` and the
/// bounds that the walk evaluated, evaluated once, so a walk reading them
/// gets the same bits.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct WalkConstants {
    /// `bounds_max[a] - bounds_min[a]` per axis.
    pub(crate) extent: [f32; 3],
    /// `res[a] as f32` per axis.
    pub(crate) res_f32: [f32; 3],
    /// Linear-index step of a cell step along x, y and z.
    pub(crate) stride: [usize; 3],
    /// Where axis `a`'s planes start in `crossing` and `start` (each axis
    /// has `res[a] + 1` planes, `k = 0..=res[a]`).
    pub(crate) offset: [usize; 3],
    /// The planes the walk steps across: `bounds_min + k * width` with
    /// `width = (bounds_max - bounds_min) / res` for `k < res`, exactly
    /// `bounds_max` for `k = res`.
    pub(crate) crossing: Vec<f32>,
    /// The planes [`DensityBoundGrid::plane`] gives (the cell boxes'
    /// faces), against which the walk settles its start cell.
    pub(crate) start: Vec<f32>,
}

impl WalkConstants {
    /// The constants of a grid with `res` cells over `bounds_min..bounds_max`.
    fn new(res: [usize; 3], bounds_min: [f32; 3], bounds_max: [f32; 3]) -> Self {
        let offset = [0, res[0] + 1, res[0] + res[1] + 2];
        let mut crossing = Vec::with_capacity(res.iter().sum::<usize>() + 3);
        let mut start = Vec::with_capacity(crossing.capacity());
        for a in 0..3 {
            let width = (bounds_max[a] - bounds_min[a]) / res[a] as f32;
            for k in 0..=res[a] {
                crossing.push(if k >= res[a] { bounds_max[a] } else { bounds_min[a] + k as f32 * width });
                start.push(plane_formula(res[a], bounds_min[a], bounds_max[a], k));
            }
        }
        WalkConstants {
            extent: std::array::from_fn(|a| bounds_max[a] - bounds_min[a]),
            res_f32: res.map(|r| r as f32),
            stride: [1, res[0], res[0] * res[1]],
            offset,
            crossing,
            start,
        }
    }
}

/// Boundary plane `k` of an axis with `res` cells over `lo..hi`: `hi` for
/// `k >= res`, else `lo + (hi - lo) * (k / res)`.
#[inline(always)]
fn plane_formula(res: usize, lo: f32, hi: f32, k: usize) -> f32 {
    if k >= res {
        return hi;
    }
    let f = k as f32 / res as f32;
    lo + (hi - lo) * f
}

/// Cells per axis of the blocks in which a majorant grid records runs of
/// zero cells (see [`MajorantGrid::walk_nonzero`]).
pub(crate) const ZERO_BLOCK: usize = 4;

/// A [`DensityBoundGrid`] of per-cell maxima: the name used where the grid
/// is a majorant (the local bound `sigma_maj` of the trackers).
pub type MajorantGrid = DensityBoundGrid;

impl DensityBoundGrid {
    /// Default resolution for dense grids.
    pub const DEFAULT_RESOLUTION: [usize; 3] = [16, 16, 16];
    /// Default cell budget for sparse grids (2^21 cells, 8 MiB).
    pub const DEFAULT_MAX_CELLS: usize = 1 << 21;
    /// Default smallest cell side (voxels) of a scene's sparse majorant
    /// grid: two VDB leaves. One cell per leaf bounds the density more
    /// tightly, but a ray then crosses twice as many cells, and on clouds
    /// the DDA steps cost more than the extra null collisions of the
    /// looser bound (see bench/README.md, "Production frame").
    pub const DEFAULT_SPARSE_MIN_CELL: usize = 16;

    /// A majorant grid from explicit values (`[z][y][x]`, x fastest) over
    /// the box `bounds_min..bounds_max`.
    pub fn new(
        res: [usize; 3],
        bounds_min: [f32; 3],
        bounds_max: [f32; 3],
        values: Vec<f32>,
    ) -> Result<Self, VolumeError> {
        // Same shape rules as a dense grid.
        DenseGrid::new(res, values.clone(), bounds_min, bounds_max)?;
        Ok(Self::from_parts(res, bounds_min, bounds_max, values))
    }

    /// The majorants of a dense grid over its local-space box, with `res`
    /// cells per axis (each at least 1).
    ///
    /// ```
    /// use niebla_volume::{DenseGrid, MajorantGrid};
    /// let g = DenseGrid::new([4, 1, 1], vec![0.0, 0.0, 1.0, 0.0], [0.0; 3], [4.0, 1.0, 1.0]).unwrap();
    /// let m = MajorantGrid::from_dense(&g, [2, 1, 1]);
    /// // Cell 0 spans x in [0, 2]: interpolation there reaches voxel 2 (center 2.5).
    /// assert_eq!(m.values(), &[1.0, 1.0]);
    /// ```
    pub fn from_dense(grid: &DenseGrid, res: [usize; 3]) -> MajorantGrid {
        let res = res.map(|r| r.max(1));
        let (bounds_min, bounds_max) = grid.bounds();
        // Clamped below at zero (NaN voxels are ignored by `max`).
        let values = reduce_dense(grid, res, f32::NEG_INFINITY, f32::max).into_iter().map(|v| v.max(0.0)).collect();
        MajorantGrid::from_parts(res, bounds_min, bounds_max, values)
    }

    /// The majorants of a sparse grid in its index space (see the module
    /// docs), with at most `max(max_cells, 8)` cells: cells are aligned to
    /// multiples of their size, so data straddling a cell boundary always
    /// takes two cells along that axis.
    pub fn from_sparse(grid: &SparseGrid, max_cells: usize) -> MajorantGrid {
        MajorantGrid::from_sparse_with_min_cell(grid, max_cells, LEAF_DIM as usize)
    }

    /// [`MajorantGrid::from_sparse`] with cells of at least `min_cell`
    /// voxels per side (rounded up to `8 * 2^k`): coarser cells than the
    /// budget needs, so that a ray crosses fewer of them (see
    /// [`MajorantGrid::DEFAULT_SPARSE_MIN_CELL`]).
    ///
    /// ```
    /// use niebla_volume::{Affine, MajorantGrid, SparseGridBuilder};
    /// let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
    /// b.set_voxel([3, 3, 3], 1.0, true);
    /// b.set_voxel([100, 3, 3], 4.0, true);
    /// let g = b.build();
    /// let m = MajorantGrid::from_sparse_with_min_cell(&g, MajorantGrid::DEFAULT_MAX_CELLS, 12);
    /// assert_eq!(m.cell_size(), [16.0; 3]);
    /// ```
    pub fn from_sparse_with_min_cell(grid: &SparseGrid, max_cells: usize, min_cell: usize) -> MajorantGrid {
        let floor = grid.background().max(0.0);
        let Some(layout) = SparseLayout::new(grid, max_cells, min_cell) else {
            return SparseLayout::empty_grid(floor);
        };
        let mut m = layout.filled(floor);
        for leaf in grid.leaves() {
            let o = leaf.origin.map(|v| v as i64);
            layout.for_each_cell_touching(o, LEAF_DIM as i64, |c, sub| {
                let mut v = f32::NEG_INFINITY;
                for i in sub[0].0..=sub[0].1 {
                    for j in sub[1].0..=sub[1].1 {
                        for k in sub[2].0..=sub[2].1 {
                            v = v.max(leaf.values[(i << 6) | (j << 3) | k]);
                        }
                    }
                }
                let i = m.cell_index(c);
                m.values[i] = m.values[i].max(v);
            });
        }
        for tile in grid.tiles() {
            let o = tile.origin.map(|v| v as i64);
            layout.for_each_cell_touching(o, tile.size() as i64, |c, _| {
                let i = m.cell_index(c);
                m.values[i] = m.values[i].max(tile.value);
            });
        }
        m.with_zero_blocks()
    }

    /// A grid from its parts, with its zero-block flags.
    pub(crate) fn from_parts(res: [usize; 3], bounds_min: [f32; 3], bounds_max: [f32; 3], values: Vec<f32>) -> Self {
        let walk = WalkConstants::new(res, bounds_min, bounds_max);
        DensityBoundGrid { res, bounds_min, bounds_max, values, zero_blocks: Vec::new(), walk }.with_zero_blocks()
    }

    /// `self` with `zero_blocks` recomputed from `values` (call after
    /// changing `values`).
    pub(crate) fn with_zero_blocks(mut self) -> Self {
        let blocks = self.res.map(|r| r.div_ceil(ZERO_BLOCK));
        let mut zero = vec![true; blocks[0] * blocks[1] * blocks[2]];
        for z in 0..self.res[2] {
            for y in 0..self.res[1] {
                for x in 0..self.res[0] {
                    if self.values[self.cell_index([x, y, z])] != 0.0 {
                        let b = [x, y, z].map(|c| c / ZERO_BLOCK);
                        zero[(b[2] * blocks[1] + b[1]) * blocks[0] + b[0]] = false;
                    }
                }
            }
        }
        self.zero_blocks = zero;
        self
    }

    /// Index in `zero_blocks` of the block holding cell `c` (in range).
    #[inline(always)]
    pub(crate) fn zero_block_index(&self, c: [usize; 3]) -> usize {
        let bx = self.res[0].div_ceil(ZERO_BLOCK);
        let by = self.res[1].div_ceil(ZERO_BLOCK);
        ((c[2] / ZERO_BLOCK) * by + c[1] / ZERO_BLOCK) * bx + c[0] / ZERO_BLOCK
    }

    /// Linear index of cell `c` (in range).
    #[inline(always)]
    pub(crate) fn cell_index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.res[1] + c[1]) * self.res[0] + c[0]
    }

    /// Whether `other` has the same cells (resolution and box) as `self`,
    /// as a majorant grid and its minorant grid built with the same
    /// parameters do.
    ///
    /// ```
    /// use niebla_volume::{DenseGrid, MajorantGrid};
    /// let g = DenseGrid::new([4, 4, 4], vec![1.0; 64], [0.0; 3], [1.0; 3]).unwrap();
    /// let majorant = MajorantGrid::from_dense(&g, [2, 2, 2]);
    /// let minorant = MajorantGrid::minorant_from_dense(&g, [2, 2, 2]);
    /// assert!(majorant.same_layout(&minorant));
    /// ```
    pub fn same_layout(&self, other: &MajorantGrid) -> bool {
        self.res == other.res && self.bounds_min == other.bounds_min && self.bounds_max == other.bounds_max
    }

    /// Cells per axis.
    pub fn res(&self) -> [usize; 3] {
        self.res
    }

    /// The box covered, in the source grid's space (local space for dense
    /// grids, index space for sparse grids).
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        (self.bounds_min, self.bounds_max)
    }

    /// All majorants, `[z][y][x]` with x fastest.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The majorant of cell `(x, y, z)`; panics out of range.
    pub fn value(&self, x: usize, y: usize, z: usize) -> f32 {
        assert!(x < self.res[0] && y < self.res[1] && z < self.res[2]);
        self.values[(z * self.res[1] + y) * self.res[0] + x]
    }

    /// The largest majorant (a global bound for the whole box).
    pub fn max_value(&self) -> f32 {
        self.values.iter().copied().fold(0.0, f32::max)
    }

    /// The box of cell `(x, y, z)`.
    pub fn cell_bounds(&self, x: usize, y: usize, z: usize) -> ([f32; 3], [f32; 3]) {
        let c = [x, y, z];
        let lo = std::array::from_fn(|a| self.plane(a, c[a]));
        let hi = std::array::from_fn(|a| self.plane(a, c[a] + 1));
        (lo, hi)
    }

    /// Cell size along each axis.
    pub fn cell_size(&self) -> [f32; 3] {
        std::array::from_fn(|a| (self.bounds_max[a] - self.bounds_min[a]) / self.res[a] as f32)
    }

    /// The majorants of the field displaced by at most `radius[a]` cells
    /// along each axis `a` (motion blur: the field at `x` read at `x - v
    /// t`): the box grown by `radius` cells on every side and each cell the
    /// largest value of the cells within `radius` of it (a separable max
    /// filter; cells outside the original box count as zero). The grown
    /// cells have the original cell size up to rounding, which the caller
    /// covers by a radius one larger than the displacement needs.
    ///
    /// ```
    /// use niebla_volume::MajorantGrid;
    /// let m = MajorantGrid::new([3, 1, 1], [0.0; 3], [3.0, 1.0, 1.0], vec![0.0, 2.0, 0.0]).unwrap();
    /// let d = m.dilated([1, 0, 0]);
    /// assert_eq!(d.res(), [5, 1, 1]);
    /// assert_eq!(d.bounds(), ([-1.0, 0.0, 0.0], [4.0, 1.0, 1.0]));
    /// assert_eq!(d.values(), &[0.0, 2.0, 2.0, 2.0, 0.0]);
    /// ```
    pub fn dilated(&self, radius: [usize; 3]) -> DensityBoundGrid {
        let h = self.cell_size();
        let res: [usize; 3] = std::array::from_fn(|a| self.res[a] + 2 * radius[a]);
        let bounds_min = std::array::from_fn(|a| self.bounds_min[a] - radius[a] as f32 * h[a]);
        let bounds_max = std::array::from_fn(|a| self.bounds_max[a] + radius[a] as f32 * h[a]);
        // Place the old values in the grown grid, then max-filter per axis.
        let index = |c: [usize; 3], res: [usize; 3]| (c[2] * res[1] + c[1]) * res[0] + c[0];
        let mut values = vec![0.0f32; res.iter().product()];
        for z in 0..self.res[2] {
            for y in 0..self.res[1] {
                for x in 0..self.res[0] {
                    let v = self.values[index([x, y, z], self.res)];
                    values[index([x + radius[0], y + radius[1], z + radius[2]], res)] = v;
                }
            }
        }
        for a in 0..3 {
            let r = radius[a];
            if r == 0 {
                continue;
            }
            let source = values.clone();
            for z in 0..res[2] {
                for y in 0..res[1] {
                    for x in 0..res[0] {
                        let c = [x, y, z];
                        let lo = c[a].saturating_sub(r);
                        let hi = (c[a] + r).min(res[a] - 1);
                        let mut m = 0.0f32;
                        for k in lo..=hi {
                            let mut n = c;
                            n[a] = k;
                            m = m.max(source[index(n, res)]);
                        }
                        values[index(c, res)] = m;
                    }
                }
            }
        }
        DensityBoundGrid::from_parts(res, bounds_min, bounds_max, values)
    }

    /// Coordinate of the cell boundary plane `k` along axis `a` (the same
    /// formula the DDA uses, so both agree to the bit).
    #[inline(always)]
    pub(crate) fn plane(&self, a: usize, k: usize) -> f32 {
        plane_formula(self.res[a], self.bounds_min[a], self.bounds_max[a], k)
    }
}

/// Per-cell reduction (`op` is `f32::max` for majorants, `f32::min` for
/// minorants) of the voxels whose interpolation support touches each of
/// `res` cells spanning a dense grid's box. Separable: along x, then y,
/// then z; `identity` is the value of an empty reduction.
pub(crate) fn reduce_dense<Op: Fn(f32, f32) -> f32>(
    grid: &DenseGrid,
    res: [usize; 3],
    identity: f32,
    op: Op,
) -> Vec<f32> {
    let dims = grid.dims();
    // Voxel range read by interpolation inside each cell, per axis.
    let ranges: [Vec<(usize, usize)>; 3] = std::array::from_fn(|a| {
        let (n, r) = (dims[a], res[a]);
        (0..r)
            .map(|c| {
                let u_lo = c as f64 * n as f64 / r as f64 - 0.5 - SUPPORT_EPSILON;
                let u_hi = (c + 1) as f64 * n as f64 / r as f64 - 0.5 + SUPPORT_EPSILON;
                let lo = u_lo.floor().max(0.0) as usize;
                let hi = (u_hi.floor() + 1.0).max(0.0) as usize;
                (lo.min(n - 1), hi.min(n - 1))
            })
            .collect()
    });
    let storage = grid.storage();
    let [nx, ny, nz] = dims;
    let [rx, ry, rz] = res;
    let mut along_x = vec![identity; rx * ny * nz];
    for zy in 0..ny * nz {
        for (cx, &(lo, hi)) in ranges[0].iter().enumerate() {
            let mut m = identity;
            for x in lo..=hi {
                m = op(m, storage.get(zy * nx + x));
            }
            along_x[zy * rx + cx] = m;
        }
    }
    let mut along_y = vec![identity; rx * ry * nz];
    for z in 0..nz {
        for (cy, &(lo, hi)) in ranges[1].iter().enumerate() {
            for cx in 0..rx {
                let mut m = identity;
                for y in lo..=hi {
                    m = op(m, along_x[(z * ny + y) * rx + cx]);
                }
                along_y[(z * ry + cy) * rx + cx] = m;
            }
        }
    }
    let mut values = vec![identity; rx * ry * rz];
    for (cz, &(lo, hi)) in ranges[2].iter().enumerate() {
        for cyx in 0..ry * rx {
            let mut m = identity;
            for z in lo..=hi {
                m = op(m, along_y[z * ry * rx + cyx]);
            }
            values[cz * ry * rx + cyx] = m;
        }
    }
    values
}

/// The cells of a sparse grid's majorant (and minorant) grid: cubes of
/// `size = 8 * 2^k` voxels from `origin`, `res` per axis, covering the
/// data bounds grown by one voxel.
pub(crate) struct SparseLayout {
    pub origin: [i64; 3],
    pub size: i64,
    pub res: [usize; 3],
}

impl SparseLayout {
    /// The layout for at most `max(max_cells, 1)` cells (8 when data
    /// straddles cell boundaries along every axis) of at least `min_cell`
    /// voxels per side, or `None` for a grid that stores nothing.
    pub(crate) fn new(grid: &SparseGrid, max_cells: usize, min_cell: usize) -> Option<SparseLayout> {
        let (lo, hi) = grid.data_bounds_index()?;
        // Cell size 8 * 2^k voxels, aligned to multiples of itself.
        let mut size: i64 = 8;
        while (size as u64) < (min_cell as u64).min(1 << 40) {
            size *= 2;
        }
        loop {
            let origin: [i64; 3] = std::array::from_fn(|a| (lo[a] as i64 - 1).div_euclid(size) * size);
            let res: [i64; 3] = std::array::from_fn(|a| (hi[a] as i64 + 1 - origin[a]).div_euclid(size) + 1);
            let cells = res.iter().map(|&r| r as u128).product::<u128>();
            if cells <= max_cells.max(1) as u128 || size >= 1 << 40 {
                return Some(SparseLayout { origin, size, res: res.map(|r| r as usize) });
            }
            size *= 2;
        }
    }

    /// The one-cell grid of a grid that stores nothing.
    pub(crate) fn empty_grid(value: f32) -> MajorantGrid {
        MajorantGrid::from_parts([1; 3], [-1.0; 3], [1.0; 3], vec![value])
    }

    /// A grid with this layout and every cell `value`.
    pub(crate) fn filled(&self, value: f32) -> MajorantGrid {
        let (origin, size, res) = (self.origin, self.size, self.res);
        MajorantGrid::from_parts(
            res,
            std::array::from_fn(|a| origin[a] as f32),
            std::array::from_fn(|a| (origin[a] + res[a] as i64 * size) as f32),
            vec![value; res[0] * res[1] * res[2]],
        )
    }

    /// Inclusive voxel range `(first, last)` along axis `a` read by
    /// interpolation inside cell `c` (grown by one voxel below for points
    /// an ulp outside the cell).
    pub(crate) fn support(&self, a: usize, c: i64) -> (i64, i64) {
        let start = self.origin[a] + c * self.size;
        (start - 1, start + self.size + 1)
    }

    /// Number of voxels in each cell's support.
    pub(crate) fn support_volume(&self) -> u128 {
        ((self.size + 3) as u128).pow(3)
    }

    /// Calls `f(cell, sub)` for every cell whose support meets the cube of
    /// `n` voxels from `origin`, with `sub` the inclusive range of the
    /// cube's voxels (relative to `origin`) inside that support, per axis.
    pub(crate) fn for_each_cell_touching(
        &self,
        origin: [i64; 3],
        n: i64,
        mut f: impl FnMut([usize; 3], [(usize, usize); 3]),
    ) {
        let ranges: [(i64, i64); 3] = std::array::from_fn(|a| {
            let (lo, hi) = (origin[a], origin[a] + n - 1);
            // ceil((lo - 1 - origin - size) / size) for integers.
            let first = (lo - 2 - self.origin[a] - self.size).div_euclid(self.size) + 1;
            let last = (hi + 1 - self.origin[a]).div_euclid(self.size);
            (first.max(0), last.min(self.res[a] as i64 - 1))
        });
        for cz in ranges[2].0..=ranges[2].1 {
            for cy in ranges[1].0..=ranges[1].1 {
                for cx in ranges[0].0..=ranges[0].1 {
                    let c = [cx, cy, cz];
                    let sub = std::array::from_fn(|a| {
                        let (s0, s1) = self.support(a, c[a]);
                        ((s0.max(origin[a]) - origin[a]) as usize, (s1.min(origin[a] + n - 1) - origin[a]) as usize)
                    });
                    f(c.map(|v| v as usize), sub);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The walk's tabulated planes are, bit for bit, the per-walk formulas
    /// they replace (`bounds_min + k * width` for the crossings, `plane`
    /// for the start checks), with `bounds_max` at `k = res`, on boxes
    /// whose extents and offsets round (not powers of two).
    #[test]
    fn walk_constants_equal_the_per_walk_formulas() {
        let boxes = [
            ([7, 1, 13], [-1.2f32, 0.3, 1000.1], [1.7f32, 0.30001, 1012.9]),
            ([64, 33, 5], [-1e-3, -7.77, 3.3], [2.2e-3, 9.1, 3.31]),
            ([1, 1, 1], [-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]),
        ];
        let mut checked = 0;
        for (res, lo, hi) in boxes {
            let n: usize = res.iter().product();
            let m = MajorantGrid::from_parts(res, lo, hi, vec![1.0; n]);
            let w = &m.walk;
            for a in 0..3 {
                assert_eq!(w.extent[a].to_bits(), (hi[a] - lo[a]).to_bits());
                assert_eq!(w.res_f32[a].to_bits(), (res[a] as f32).to_bits());
                let width = (hi[a] - lo[a]) / res[a] as f32;
                for k in 0..=res[a] {
                    let crossing = if k >= res[a] { hi[a] } else { lo[a] + k as f32 * width };
                    assert_eq!(w.crossing[w.offset[a] + k].to_bits(), crossing.to_bits(), "axis {a} plane {k}");
                    assert_eq!(w.start[w.offset[a] + k].to_bits(), m.plane(a, k).to_bits(), "axis {a} plane {k}");
                    let f = k as f32 / res[a] as f32;
                    let plane = if k >= res[a] { hi[a] } else { lo[a] + (hi[a] - lo[a]) * f };
                    assert_eq!(m.plane(a, k).to_bits(), plane.to_bits());
                    checked += 1;
                }
            }
            assert_eq!(w.stride, [1, res[0], res[0] * res[1]]);
            assert_eq!(w.crossing.len(), res.iter().sum::<usize>() + 3);
        }
        assert_eq!(checked, 24 + 105 + 6);
    }
}
