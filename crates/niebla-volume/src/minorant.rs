//! Minorant grids: a coarse grid of lower bounds of a density field, one
//! per cell, for residual ratio tracking (Novák et al. 2014, "Residual ratio
//! tracking for estimating attenuation in participating media"), where the
//! minorant is the control density `sigma_c` and only the residual
//! `sigma_t - sigma_c` is tracked.
//!
//! A minorant grid is a [`DensityBoundGrid`] holding minima instead of maxima,
//! with exactly the cells of the majorant grid built from the same grid and
//! parameters (same resolution and box, so the same DDA segments): cell
//! `(x, y, z)` of one pairs with cell `(x, y, z)` of the other, and a
//! tracker walks the majorant grid with [`DensityBoundGrid::walk_cells`] and
//! reads the minorant of each cell with [`DensityBoundGrid::value`]
//! ([`DensityBoundGrid::same_layout`] checks the pairing).
//!
//! A cell's value is the smallest voxel value whose interpolation support
//! touches the cell, over the same voxels (support grown by 1/1000 voxel)
//! as the majorant, so trilinear interpolation anywhere in the closed cell
//! is at least the minorant (up to the rounding of a lerp). Voxels that a
//! sparse grid does not store read as its background, so a cell whose
//! support reaches anything not stored has a minorant at most the
//! background. Unlike majorants, minorants are not clamped at zero: a
//! negative voxel gives a negative minorant (clamp it if the tracker needs
//! a non-negative control).
//!
//! One exception, at measure zero: a dense grid reads zero *outside* its
//! box, so a point that rounding puts an ulp outside the box (at a segment
//! end on the box's faces) can read below the minorant of the face cell.

use crate::majorant::{reduce_dense, SparseLayout};
use crate::{DenseGrid, DensityBoundGrid, SparseGrid, LEAF_DIM};

impl DensityBoundGrid {
    /// The minorants of a dense grid over its local-space box, with `res`
    /// cells per axis (each at least 1): the same cells as
    /// [`MajorantGrid::from_dense`](crate::MajorantGrid::from_dense)`(grid, res)`.
    ///
    /// ```
    /// use niebla_volume::{DenseGrid, DensityBoundGrid, MajorantGrid};
    /// let g = DenseGrid::new([4, 1, 1], vec![2.0, 2.0, 0.5, 3.0], [0.0; 3], [4.0, 1.0, 1.0]).unwrap();
    /// let minorant = DensityBoundGrid::minorant_from_dense(&g, [2, 1, 1]);
    /// let majorant = MajorantGrid::from_dense(&g, [2, 1, 1]);
    /// // Cell 0 spans x in [0, 2]: interpolation there reaches voxel 2 (center 2.5).
    /// assert_eq!(minorant.values(), &[0.5, 0.5]);
    /// assert_eq!(majorant.values(), &[2.0, 3.0]);
    /// assert!(minorant.same_layout(&majorant));
    /// ```
    pub fn minorant_from_dense(grid: &DenseGrid, res: [usize; 3]) -> DensityBoundGrid {
        let res = res.map(|r| r.max(1));
        let (bounds_min, bounds_max) = grid.bounds();
        DensityBoundGrid::from_parts(res, bounds_min, bounds_max, reduce_dense(grid, res, f32::INFINITY, f32::min))
    }

    /// The minorants of a sparse grid in its index space: the same cells as
    /// [`MajorantGrid::from_sparse`](crate::MajorantGrid::from_sparse)`(grid, max_cells)`.
    /// A grid that stores nothing gives the same single cell as its majorant
    /// grid, holding the background.
    ///
    /// ```
    /// use niebla_volume::{Affine, DensityBoundGrid, MajorantGrid, SparseGridBuilder};
    /// let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
    /// b.fill_tile(1, [0, 0, 0], 2.0, true); // voxels 0..128 along each axis
    /// b.set_voxel([60, 60, 60], 0.5, true);
    /// let g = b.build();
    /// let majorant = MajorantGrid::from_sparse(&g, MajorantGrid::DEFAULT_MAX_CELLS);
    /// let minorant = DensityBoundGrid::minorant_from_sparse(&g, MajorantGrid::DEFAULT_MAX_CELLS);
    /// assert!(minorant.same_layout(&majorant));
    /// // Cells are 8 voxels from -8: cell (3, 3, 3) covers voxels 16..24,
    /// // inside the tile and away from (60, 60, 60).
    /// let (lo, _) = minorant.bounds();
    /// assert_eq!(lo, [-8.0; 3]);
    /// assert_eq!(minorant.value(3, 3, 3), 2.0);
    /// // The cell holding (60, 60, 60), and a face cell that reaches the background.
    /// assert_eq!(minorant.value(8, 8, 8), 0.5);
    /// assert_eq!(minorant.value(0, 3, 3), 0.0);
    /// ```
    pub fn minorant_from_sparse(grid: &SparseGrid, max_cells: usize) -> DensityBoundGrid {
        DensityBoundGrid::minorant_from_sparse_with_min_cell(grid, max_cells, LEAF_DIM as usize)
    }

    /// The minorants of a sparse grid over the same cells as
    /// [`MajorantGrid::from_sparse_with_min_cell`](crate::MajorantGrid::from_sparse_with_min_cell)
    /// `(grid, max_cells, min_cell)`.
    pub fn minorant_from_sparse_with_min_cell(
        grid: &SparseGrid,
        max_cells: usize,
        min_cell: usize,
    ) -> DensityBoundGrid {
        let background = grid.background();
        let Some(layout) = SparseLayout::new(grid, max_cells, min_cell) else {
            return SparseLayout::empty_grid(background);
        };
        let mut m = layout.filled(f32::INFINITY);
        // Stored voxels counted in each cell's support: leaves and tiles
        // never overlap, so a support is free of background voxels exactly
        // when its count reaches the support's volume.
        let mut covered = vec![0u128; m.values.len()];
        let extent = |sub: [(usize, usize); 3]| sub.iter().map(|&(lo, hi)| (hi - lo + 1) as u128).product::<u128>();
        for leaf in grid.leaves() {
            let o = leaf.origin.map(|v| v as i64);
            layout.for_each_cell_touching(o, LEAF_DIM as i64, |c, sub| {
                let mut v = f32::INFINITY;
                for i in sub[0].0..=sub[0].1 {
                    for j in sub[1].0..=sub[1].1 {
                        for k in sub[2].0..=sub[2].1 {
                            v = v.min(leaf.values[(i << 6) | (j << 3) | k]);
                        }
                    }
                }
                let i = m.cell_index(c);
                m.values[i] = m.values[i].min(v);
                covered[i] += extent(sub);
            });
        }
        for tile in grid.tiles() {
            let o = tile.origin.map(|v| v as i64);
            layout.for_each_cell_touching(o, tile.size() as i64, |c, sub| {
                let i = m.cell_index(c);
                m.values[i] = m.values[i].min(tile.value);
                covered[i] += extent(sub);
            });
        }
        // Supports that reach a voxel nothing stores read the background.
        let volume = layout.support_volume();
        for (value, &count) in m.values.iter_mut().zip(&covered) {
            debug_assert!(count <= volume, "leaves and tiles overlap");
            if count < volume {
                *value = value.min(background);
            }
        }
        m.with_zero_blocks()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Affine, SparseGridBuilder};

    #[test]
    fn minorant_of_a_fully_stored_region_ignores_the_background() {
        // A 128^3 tile of 1.0 over a background of 0: inner cells have
        // minorant 1, cells whose support leaves the tile have 0.
        let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
        b.fill_tile(1, [0, 0, 0], 1.0, true);
        let g = b.build();
        let m = DensityBoundGrid::minorant_from_sparse(&g, DensityBoundGrid::DEFAULT_MAX_CELLS);
        let [rx, ry, rz] = m.res();
        assert_eq!(m.res(), [18, 18, 18]); // voxels -8..136: tile plus margins
        for z in 0..rz {
            for y in 0..ry {
                for x in 0..rx {
                    // Cell c covers voxels 8 (c - 1) ..= 8 c and reads 8 c - 9 ..= 8 c + 1.
                    let inner = [x, y, z].iter().all(|&c| (2..=15).contains(&c));
                    let expected = if inner { 1.0 } else { 0.0 };
                    assert_eq!(m.value(x, y, z), expected, "cell ({x}, {y}, {z})");
                }
            }
        }
    }

    #[test]
    fn empty_sparse_grid_minorant_is_the_background() {
        let g = SparseGridBuilder::new(-0.5, Affine::IDENTITY).build();
        let min = DensityBoundGrid::minorant_from_sparse(&g, 100);
        let max = DensityBoundGrid::from_sparse(&g, 100);
        assert!(min.same_layout(&max));
        assert_eq!(min.values(), &[-0.5]);
    }
}
