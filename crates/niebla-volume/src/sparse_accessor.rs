//! Cached reads of a [`SparseGrid`]: [`SparseAccessor`] remembers the last
//! 8^3 block, lower node and upper node it visited, so that coherent
//! lookups (points marched along a ray) skip the root hash and the node
//! tables (OpenVDB's `ValueAccessor`, NanoVDB's `ReadAccessor`; Museth,
//! "VDB: High-resolution sparse volumes with dynamic topology", ACM TOG
//! 32(3), 2013, section 5.1).
//!
//! The cache lives in [`Cell`]s, so the accessor reads through `&self`
//! like the grid does; it is `Send` but not `Sync`: make one per ray (or
//! per thread), never share one between threads. Every read returns
//! exactly what the uncached [`SparseGrid`] method returns (the same
//! stored values, combined by the same arithmetic).

use std::cell::Cell;

use crate::sparse::{
    lower_offset, split_index_point, trilinear, upper_offset, Leaf, EMPTY, LEAF_TOTAL, LOWER_SIZE, LOWER_TOTAL,
    TILE_BIT, UPPER_SIZE, UPPER_TOTAL,
};
use crate::SparseGrid;

/// A cache key no voxel can have (voxel coordinates shifted right by 3 or
/// more bits stay above `i32::MIN`).
const NO_KEY: [i32; 3] = [i32::MIN; 3];

/// What an 8^3 block of voxels holds: a leaf's values, or one value for
/// all 512 voxels (background, or a tile at any depth).
#[derive(Clone, Copy)]
enum Block<'a> {
    Leaf(&'a [f32; 512]),
    Constant(f32),
}

impl Block<'_> {
    #[inline(always)]
    fn get(self, n: usize) -> f32 {
        match self {
            Block::Leaf(v) => v[n],
            Block::Constant(c) => c,
        }
    }
}

/// A read cursor into a [`SparseGrid`] that caches the last block, lower
/// node and upper node it visited (see the module docs).
///
/// ```
/// use niebla_volume::{Affine, SparseGridBuilder};
/// let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
/// b.set_voxel([1, 2, 3], 4.0, true);
/// let g = b.build();
/// let acc = g.accessor();
/// for t in 0..8 {
///     let p = [1.0 + t as f32 * 0.125, 2.0, 3.0];
///     assert_eq!(acc.lookup_index(p).to_bits(), g.lookup_index(p).to_bits());
/// }
/// ```
pub struct SparseAccessor<'a> {
    grid: &'a SparseGrid,
    /// `ijk >> 3` of the cached block.
    block_key: Cell<[i32; 3]>,
    block: Cell<Block<'a>>,
    /// `ijk >> 7` of the cached lower-node entry of its upper node.
    lower_key: Cell<[i32; 3]>,
    /// The upper node's entry for that 128^3 region: a lower-node index or
    /// a tile entry (with [`TILE_BIT`]).
    lower_entry: Cell<u32>,
    /// `ijk >> 12` of the cached root entry.
    upper_key: Cell<[i32; 3]>,
    /// The root's entry for that 4096^3 region ([`EMPTY`] when absent).
    upper_entry: Cell<u32>,
}

impl SparseGrid {
    /// A cached read accessor for coherent lookups (see [`SparseAccessor`]).
    #[inline]
    pub fn accessor(&self) -> SparseAccessor<'_> {
        SparseAccessor::new(self)
    }
}

impl<'a> SparseAccessor<'a> {
    /// An accessor with an empty cache.
    #[inline]
    pub fn new(grid: &'a SparseGrid) -> Self {
        SparseAccessor {
            grid,
            block_key: Cell::new(NO_KEY),
            block: Cell::new(Block::Constant(grid.background)),
            lower_key: Cell::new(NO_KEY),
            lower_entry: Cell::new(EMPTY),
            upper_key: Cell::new(NO_KEY),
            upper_entry: Cell::new(EMPTY),
        }
    }

    /// The grid read through this accessor.
    #[inline]
    pub fn grid(&self) -> &'a SparseGrid {
        self.grid
    }

    /// The value a node-table tile entry stands for.
    #[inline(always)]
    fn tile_value(&self, e: u32) -> f32 {
        if e == EMPTY {
            self.grid.background
        } else {
            self.grid.tiles[(e & !TILE_BIT) as usize].value
        }
    }

    /// The block holding voxel `ijk`, from the cache when it is the last one.
    #[inline(always)]
    fn block(&self, ijk: [i32; 3]) -> Block<'a> {
        let key = ijk.map(|v| v >> LEAF_TOTAL);
        if key == self.block_key.get() {
            return self.block.get();
        }
        let b = self.descend(ijk);
        self.block_key.set(key);
        self.block.set(b);
        b
    }

    /// Tree descent starting from the deepest cached node that holds `ijk`.
    #[inline(never)]
    fn descend(&self, ijk: [i32; 3]) -> Block<'a> {
        let g = self.grid;
        let lower_key = ijk.map(|v| v >> LOWER_TOTAL);
        let e = if lower_key == self.lower_key.get() {
            self.lower_entry.get()
        } else {
            let upper_key = ijk.map(|v| v >> UPPER_TOTAL);
            let root = if upper_key == self.upper_key.get() {
                self.upper_entry.get()
            } else {
                let root = g.root.get(&upper_key).copied().unwrap_or(EMPTY);
                self.upper_key.set(upper_key);
                self.upper_entry.set(root);
                root
            };
            let e = if root & TILE_BIT != 0 { root } else { g.uppers[root as usize * UPPER_SIZE + upper_offset(ijk)] };
            self.lower_key.set(lower_key);
            self.lower_entry.set(e);
            e
        };
        let e = if e & TILE_BIT != 0 { e } else { g.lowers[e as usize * LOWER_SIZE + lower_offset(ijk)] };
        if e & TILE_BIT != 0 {
            Block::Constant(self.tile_value(e))
        } else {
            Block::Leaf(&g.leaves[e as usize].values)
        }
    }

    /// The value of voxel `ijk`, equal to [`SparseGrid::value`].
    #[inline]
    pub fn value(&self, ijk: [i32; 3]) -> f32 {
        self.block(ijk).get(Leaf::offset(ijk))
    }

    /// Trilinear interpolation at index-space point `p`, bit-identical to
    /// [`SparseGrid::lookup_index`].
    #[inline]
    pub fn lookup_index(&self, p: [f32; 3]) -> f32 {
        if !(p.iter().all(|v| v.abs() < 1.0e9)) {
            return self.grid.background;
        }
        let (ijk, f) = split_index_point(p);
        trilinear(self.corners(ijk), f)
    }

    /// Trilinear interpolation at world-space point `p`, bit-identical to
    /// [`SparseGrid::lookup_world`].
    #[inline]
    pub fn lookup_world(&self, p: [f32; 3]) -> f32 {
        self.lookup_index(self.grid.world_to_index(p))
    }

    /// The 8 voxels `ijk + (dx, dy, dz)` ordered with `dz` fastest.
    #[inline(always)]
    fn corners(&self, ijk: [i32; 3]) -> [f32; 8] {
        let n = Leaf::offset(ijk);
        let b = self.block(ijk);
        let inner = [(ijk[0] & 7) != 7, (ijk[1] & 7) != 7, (ijk[2] & 7) != 7];
        if inner[0] && inner[1] && inner[2] {
            return match b {
                Block::Constant(c) => [c; 8],
                Block::Leaf(v) => [v[n], v[n + 1], v[n + 8], v[n + 9], v[n + 64], v[n + 65], v[n + 72], v[n + 73]],
            };
        }
        // The stencil crosses a block face along the axes that are not
        // `inner`: fetch each neighbouring block once, without replacing the
        // cached block (the next point along the ray most likely needs it).
        let cross = ((!inner[0] as usize) << 2) | ((!inner[1] as usize) << 1) | (!inner[2] as usize);
        let mut blocks = [b; 8];
        for (c, block) in blocks.iter_mut().enumerate().skip(1) {
            if c & !cross == 0 {
                *block =
                    self.descend([ijk[0] + (c >> 2) as i32, ijk[1] + ((c >> 1) & 1) as i32, ijk[2] + (c & 1) as i32]);
            }
        }
        std::array::from_fn(|c| {
            let q = [ijk[0] + (c >> 2) as i32, ijk[1] + ((c >> 1) & 1) as i32, ijk[2] + (c & 1) as i32];
            blocks[c & cross].get(Leaf::offset(q))
        })
    }
}
