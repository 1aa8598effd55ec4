//! A flat table of a [`SparseGrid`]'s 8^3 blocks over the box of its
//! leaves: one `u32` per block, the node-table entry that the tree's
//! descent (root, upper node, lower node) ends with for that block. A
//! lookup inside the box then costs one array read instead of a root scan
//! and two dependent node-table reads; outside it, the tree is descended as
//! before. The table only shortcuts the descent: every block resolves to
//! the same leaf, tile or background, so values are bit-identical.
//!
//! (A dense index over the occupied region, as NanoVDB's and GVDB's
//! flattened top levels; Museth, "NanoVDB: A GPU-friendly and portable VDB
//! data structure for real-time rendering and simulation", SIGGRAPH 2021
//! talks.)

use crate::sparse::{Slot, EMPTY, LEAF_TOTAL, TILE_BIT};
use crate::SparseGrid;

/// Largest table, in entries per stored leaf (4 bytes each against a leaf's
/// 2 KiB of values: at most 1.5% of the leaves' memory); a grid whose leaf
/// box needs more keeps descending the tree.
const MAX_ENTRIES_PER_LEAF: usize = 8;

/// Tables of up to this many entries (16 KiB) are built for any grid.
const MIN_MAX_ENTRIES: usize = 4096;

/// The per-block entries over the box of a grid's leaves, `[x][y][z]` with
/// z fastest (empty when the grid has no leaf or the box is too large).
#[derive(Clone, Debug, Default)]
pub(crate) struct BlockTable {
    /// `ijk >> 3` of the box's lowest block.
    origin: [i32; 3],
    /// Blocks per axis (all zero without a table).
    dims: [u32; 3],
    /// Per block: a leaf index, a tile entry (with [`TILE_BIT`]) or
    /// [`EMPTY`] (background), as in the lower-node tables.
    entries: Vec<u32>,
}

impl BlockTable {
    /// The table of `grid`'s leaf box, filled by descending its tree once
    /// per block; empty when `grid` has no leaves or the box holds more than
    /// `max(8 x leaves, 4096)` blocks.
    pub(crate) fn build(grid: &SparseGrid) -> BlockTable {
        let Some(first) = grid.leaves.first() else {
            return BlockTable::default();
        };
        let key = |o: [i32; 3]| o.map(|v| v >> LEAF_TOTAL);
        let (mut lo, mut hi) = (key(first.origin), key(first.origin));
        for leaf in &grid.leaves {
            let k = key(leaf.origin);
            for a in 0..3 {
                lo[a] = lo[a].min(k[a]);
                hi[a] = hi[a].max(k[a]);
            }
        }
        let dims = std::array::from_fn(|a| (hi[a] as i64 - lo[a] as i64 + 1) as u64);
        let count = dims.iter().product::<u64>();
        let budget = (grid.leaves.len() * MAX_ENTRIES_PER_LEAF).max(MIN_MAX_ENTRIES) as u64;
        if count > budget {
            return BlockTable::default();
        }
        let mut entries = Vec::with_capacity(count as usize);
        for x in 0..dims[0] as i32 {
            for y in 0..dims[1] as i32 {
                for z in 0..dims[2] as i32 {
                    let block = [lo[0] + x, lo[1] + y, lo[2] + z];
                    entries.push(match grid.slot(block.map(|v| v << LEAF_TOTAL)) {
                        Slot::Background => EMPTY,
                        Slot::Tile(t) => t | TILE_BIT,
                        Slot::Leaf(l) => l,
                    });
                }
            }
        }
        BlockTable { origin: lo, dims: dims.map(|n| n as u32), entries }
    }

    /// The entry of the block holding voxel `ijk`, if the table covers it.
    #[inline(always)]
    pub(crate) fn entry(&self, ijk: [i32; 3]) -> Option<u32> {
        // Coordinates below the origin wrap to large values and fail the
        // bounds test like those past the end.
        let r: [u32; 3] = std::array::from_fn(|a| ((ijk[a] >> LEAF_TOTAL).wrapping_sub(self.origin[a])) as u32);
        if r[0] < self.dims[0] && r[1] < self.dims[1] && r[2] < self.dims[2] {
            let n = (r[0] as usize * self.dims[1] as usize + r[1] as usize) * self.dims[2] as usize + r[2] as usize;
            Some(self.entries[n])
        } else {
            None
        }
    }

    /// Heap bytes held (by allocated capacity).
    pub(crate) fn memory_bytes(&self) -> usize {
        self.entries.capacity() * std::mem::size_of::<u32>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Affine, SparseGridBuilder};

    /// Every block of and around the table's box gives the entry that the
    /// tree's slot gives (leaves, a lower-node tile inside the box, and the
    /// background), and blocks outside the box are not covered.
    #[test]
    fn entries_match_the_tree_descent() {
        let mut b = SparseGridBuilder::new(0.5, Affine::IDENTITY);
        b.set_voxel([-9, 3, 17], 1.0, true);
        b.set_voxel([40, -30, 0], 2.0, true);
        b.set_voxel([7, 7, 7], 3.0, true);
        b.fill_tile(2, [16, 0, 0], 4.0, true);
        let g = b.build();
        let t = BlockTable::build(&g);
        // Leaf blocks x -2..=5, y -4..=0, z 0..=2.
        assert_eq!((t.origin, t.dims), ([-2, -4, 0], [8, 5, 3]));
        let (mut covered, mut tiles, mut leaves) = (0, 0, 0);
        for x in -4..8 {
            for y in -6..3 {
                for z in -2..5 {
                    let ijk = [x * 8 + 3, y * 8 + 5, z * 8 + 1];
                    let expected = match g.slot(ijk) {
                        Slot::Background => EMPTY,
                        Slot::Tile(t) => t | TILE_BIT,
                        Slot::Leaf(l) => l,
                    };
                    let inside = (-2..6).contains(&x) && (-4..1).contains(&y) && (0..3).contains(&z);
                    match t.entry(ijk) {
                        Some(e) => {
                            assert!(inside, "{ijk:?}");
                            assert_eq!(e, expected, "{ijk:?}");
                            covered += 1;
                            tiles += (e != EMPTY && e & TILE_BIT != 0) as u32;
                            leaves += (e & TILE_BIT == 0) as u32;
                        }
                        None => assert!(!inside, "{ijk:?}"),
                    }
                }
            }
        }
        assert_eq!((covered, tiles, leaves), (120, 1, 3));
    }

    /// A grid whose leaves are far apart gets no table (its box would hold
    /// far more blocks than the budget), and lookups still descend the tree.
    #[test]
    fn scattered_leaves_get_no_table() {
        let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
        b.set_voxel([0, 0, 0], 1.0, true);
        b.set_voxel([4000, 4000, 4000], 1.0, true);
        let g = b.build();
        let t = BlockTable::build(&g);
        assert_eq!((t.dims, t.memory_bytes()), ([0; 3], 0));
        assert_eq!(t.entry([0, 0, 0]), None);
        assert_eq!(g.accessor().value([4000, 4000, 4000]), 1.0);
        assert_eq!(BlockTable::build(&SparseGridBuilder::new(0.0, Affine::IDENTITY).build()).dims, [0; 3]);
    }
}
