//! Building sparse grids: node allocation (shared with the VDB reader) and
//! [`SparseGridBuilder`] for grids made in code (tests, procedural data).

use crate::sparse::{
    lower_offset, upper_offset, Leaf, Tile, EMPTY, LEAF_TOTAL, LOWER_SIZE, LOWER_TOTAL, TILE_BIT, UPPER_SIZE,
    UPPER_TOTAL,
};
use crate::{Affine, SparseGrid};

/// Largest tile index an entry can encode (`EMPTY` is reserved).
const MAX_TILES: usize = (TILE_BIT - 1) as usize;

impl SparseGrid {
    /// Adds an upper node (32^3 entries, all `fill`) and returns its index.
    pub(crate) fn push_upper(&mut self, origin: [i32; 3], fill: u32) -> u32 {
        let index = self.upper_origins.len() as u32;
        self.uppers.resize(self.uppers.len() + UPPER_SIZE, fill);
        self.upper_origins.push(origin);
        index
    }

    /// Adds a lower node (16^3 entries, all `fill`) and returns its index.
    pub(crate) fn push_lower(&mut self, origin: [i32; 3], fill: u32) -> u32 {
        let index = self.lower_origins.len() as u32;
        self.lowers.resize(self.lowers.len() + LOWER_SIZE, fill);
        self.lower_origins.push(origin);
        index
    }

    /// Adds a leaf and returns its index.
    pub(crate) fn push_leaf(&mut self, leaf: Leaf) -> u32 {
        self.leaves.push(leaf);
        (self.leaves.len() - 1) as u32
    }

    /// The node-table entry for a tile: [`EMPTY`] for an inactive
    /// background tile, else a new tile index with [`TILE_BIT`] set.
    /// Returns `None` when no more tiles can be encoded.
    pub(crate) fn tile_entry(&mut self, tile: Tile) -> Option<u32> {
        if !tile.active && tile.value.to_bits() == self.background.to_bits() {
            return Some(EMPTY);
        }
        if self.tiles.len() >= MAX_TILES {
            return None;
        }
        self.tiles.push(tile);
        Some((self.tiles.len() - 1) as u32 | TILE_BIT)
    }

    /// The value and active state an entry stands for (children excluded).
    fn entry_fill(&self, e: u32) -> (f32, bool) {
        if e == EMPTY {
            (self.background, false)
        } else {
            let t = &self.tiles[(e & !TILE_BIT) as usize];
            (t.value, t.active)
        }
    }

    /// Fills the new node `node` at tree `depth` (1 upper, 2 lower) with
    /// one tile per entry carrying the value of tile entry `e`.
    fn split_tile(&mut self, e: u32, depth: u8, node: u32) {
        if e == EMPTY {
            return;
        }
        let (value, active) = self.entry_fill(e);
        let (log2_dim, child_log2, size, origin) = if depth == 1 {
            (5, LOWER_TOTAL, UPPER_SIZE, self.upper_origins[node as usize])
        } else {
            (4, LEAF_TOTAL, LOWER_SIZE, self.lower_origins[node as usize])
        };
        let mask = (1 << log2_dim) - 1;
        for n in 0..size {
            let d = [n >> (2 * log2_dim), (n >> log2_dim) & mask, n & mask];
            let origin = std::array::from_fn(|a| origin[a] + ((d[a] as i32) << child_log2));
            let entry = self.tile_entry(Tile { origin, depth, value, active }).expect("too many tiles");
            if depth == 1 {
                self.uppers[node as usize * UPPER_SIZE + n] = entry;
            } else {
                self.lowers[node as usize * LOWER_SIZE + n] = entry;
            }
        }
    }

    /// A copy holding only the nodes and tiles reachable from the root, in
    /// sorted root order (drops whatever a builder overwrote).
    fn compacted(&self) -> SparseGrid {
        let mut out = SparseGrid::empty(self.background, self.index_to_world);
        out.name = self.name.clone();
        out.map_type = self.map_type.clone();
        let mut keys: Vec<_> = self.root.keys().copied().collect();
        keys.sort_unstable();
        for key in keys {
            let e = self.root[&key];
            let new = self.copy_entry(&mut out, e, 0);
            if new != EMPTY {
                out.root.insert(key, new);
            }
        }
        out.shrink_to_fit();
        out
    }

    /// Releases the spare capacity of every table (grids are built by
    /// pushing, which leaves up to half of each vector unused).
    pub(crate) fn shrink_to_fit(&mut self) {
        self.root.shrink_to_fit();
        self.uppers.shrink_to_fit();
        self.upper_origins.shrink_to_fit();
        self.lowers.shrink_to_fit();
        self.lower_origins.shrink_to_fit();
        self.leaves.shrink_to_fit();
        self.tiles.shrink_to_fit();
    }

    fn copy_entry(&self, out: &mut SparseGrid, e: u32, depth: u8) -> u32 {
        if e & TILE_BIT != 0 {
            if e == EMPTY {
                return EMPTY;
            }
            let tile = self.tiles[(e & !TILE_BIT) as usize];
            return out.tile_entry(tile).expect("fewer tiles than the source grid");
        }
        match depth {
            0 => {
                let u = out.push_upper(self.upper_origins[e as usize], EMPTY);
                for n in 0..UPPER_SIZE {
                    let child = self.uppers[e as usize * UPPER_SIZE + n];
                    let new = self.copy_entry(out, child, 1);
                    out.uppers[u as usize * UPPER_SIZE + n] = new;
                }
                u
            }
            1 => {
                let l = out.push_lower(self.lower_origins[e as usize], EMPTY);
                for n in 0..LOWER_SIZE {
                    let child = self.lowers[e as usize * LOWER_SIZE + n];
                    let new = self.copy_entry(out, child, 2);
                    out.lowers[l as usize * LOWER_SIZE + n] = new;
                }
                l
            }
            _ => out.push_leaf(self.leaves[e as usize].clone()),
        }
    }
}

/// Builds a [`SparseGrid`] voxel by voxel or tile by tile, in index space.
///
/// ```
/// use niebla_volume::{Affine, SparseGridBuilder};
/// let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
/// b.fill_tile(1, [130, 0, 0], 0.5, true); // the 128^3 tile holding (130, 0, 0)
/// b.set_voxel([128, 0, 0], 2.0, true);    // splits the tile down to one leaf
/// let g = b.build();
/// assert_eq!(g.value([128, 0, 0]), 2.0);
/// assert_eq!(g.value([255, 127, 127]), 0.5);
/// assert_eq!(g.active_voxel_count(), 128 * 128 * 128);
/// ```
#[derive(Clone, Debug)]
pub struct SparseGridBuilder {
    grid: SparseGrid,
}

impl SparseGridBuilder {
    /// An empty grid with the given background and index-to-world map.
    pub fn new(background: f32, index_to_world: Affine) -> Self {
        SparseGridBuilder { grid: SparseGrid::empty(background, index_to_world) }
    }

    /// Sets voxel `ijk` (index space) to `value` with the given active state,
    /// splitting any tile that covers it.
    pub fn set_voxel(&mut self, ijk: [i32; 3], value: f32, active: bool) {
        let leaf = self.ensure_child(ijk, 3) as usize;
        let leaf = &mut self.grid.leaves[leaf];
        let n = Leaf::offset(ijk);
        leaf.values[n] = value;
        if active {
            leaf.active[n / 64] |= 1 << (n % 64);
        } else {
            leaf.active[n / 64] &= !(1 << (n % 64));
        }
    }

    /// Makes the whole tile at tree `depth` (0: 4096^3, 1: 128^3, 2: 8^3)
    /// that contains voxel `ijk` constant, replacing what was there.
    pub fn fill_tile(&mut self, depth: u8, ijk: [i32; 3], value: f32, active: bool) {
        let depth = depth.min(2);
        let log2 = crate::sparse::tile_log2(depth);
        let origin = ijk.map(|v| v >> log2 << log2);
        let tile = Tile { origin, depth, value, active };
        let e = self.grid.tile_entry(tile).expect("too many tiles");
        match depth {
            0 => {
                self.grid.root.insert(ijk.map(|v| v >> UPPER_TOTAL), e);
            }
            1 => {
                let u = self.ensure_child(ijk, 1) as usize;
                self.grid.uppers[u * UPPER_SIZE + upper_offset(ijk)] = e;
            }
            _ => {
                let l = self.ensure_child(ijk, 2) as usize;
                self.grid.lowers[l * LOWER_SIZE + lower_offset(ijk)] = e;
            }
        }
    }

    /// The index of the node at `level` (1 upper, 2 lower, 3 leaf) holding
    /// `ijk`, creating it (filled from the covering tile) if needed.
    fn ensure_child(&mut self, ijk: [i32; 3], level: u8) -> u32 {
        let g = &mut self.grid;
        let key = ijk.map(|v| v >> UPPER_TOTAL);
        let e = g.root.get(&key).copied().unwrap_or(EMPTY);
        let upper = if e & TILE_BIT == 0 {
            e
        } else {
            let u = g.push_upper(key.map(|v| v << UPPER_TOTAL), EMPTY);
            g.split_tile(e, 1, u);
            g.root.insert(key, u);
            u
        };
        if level == 1 {
            return upper;
        }
        let slot = upper as usize * UPPER_SIZE + upper_offset(ijk);
        let e = g.uppers[slot];
        let lower = if e & TILE_BIT == 0 {
            e
        } else {
            let l = g.push_lower(ijk.map(|v| v >> LOWER_TOTAL << LOWER_TOTAL), EMPTY);
            g.split_tile(e, 2, l);
            g.uppers[slot] = l;
            l
        };
        if level == 2 {
            return lower;
        }
        let slot = lower as usize * LOWER_SIZE + lower_offset(ijk);
        let e = g.lowers[slot];
        if e & TILE_BIT == 0 {
            return e;
        }
        let (fill, active) = g.entry_fill(e);
        let leaf = g.push_leaf(Leaf::new(ijk.map(|v| v >> LEAF_TOTAL << LEAF_TOTAL), fill, active));
        g.lowers[slot] = leaf;
        leaf
    }

    /// The finished grid (only reachable nodes and tiles are kept).
    pub fn build(self) -> SparseGrid {
        self.grid.compacted()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn voxels_tiles_and_background_read_back() {
        let mut b = SparseGridBuilder::new(-1.0, Affine::IDENTITY);
        b.set_voxel([0, 0, 0], 0.25, true);
        b.set_voxel([-1, -1, -1], 2.5, true);
        b.set_voxel([4095, 4096, -4097], 1.5, false);
        b.fill_tile(2, [200, 0, 0], 0.625, true);
        b.fill_tile(0, [8192, 0, 0], 0.375, true);
        let g = b.build();
        assert_eq!(g.probe([0, 0, 0]), (0.25, true));
        assert_eq!(g.probe([-1, -1, -1]), (2.5, true));
        assert_eq!(g.probe([4095, 4096, -4097]), (1.5, false));
        assert_eq!(g.probe([1, 0, 0]), (-1.0, false));
        assert_eq!(g.probe([207, 7, 7]), (0.625, true));
        assert_eq!(g.probe([208, 0, 0]), (-1.0, false));
        assert_eq!(g.probe([12287, 4095, 4095]), (0.375, true));
        assert_eq!(g.probe([9_000_000, 0, 0]), (-1.0, false));
        assert_eq!(g.leaf_count(), 3);
        assert_eq!(g.active_tile_counts(), [1, 0, 1]);
        assert_eq!(g.active_voxel_count(), 2 + 512 + 4096u64.pow(3));
        assert_eq!(g.active_bounds_index(), Some(([-1, -1, -1], [12287, 4095, 4095])));
    }

    #[test]
    fn splitting_a_tile_keeps_its_other_voxels() {
        let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
        b.fill_tile(0, [0, 0, 0], 0.5, true);
        b.set_voxel([5, 5, 5], 1.0, false);
        let g = b.build();
        assert_eq!(g.probe([5, 5, 5]), (1.0, false));
        assert_eq!(g.probe([5, 5, 6]), (0.5, true));
        assert_eq!(g.probe([4000, 3000, 2000]), (0.5, true));
        assert_eq!(g.active_voxel_count(), 4096u64.pow(3) - 1);
        assert_eq!(g.active_tile_counts(), [0, 32767, 4095]);
        assert!((g.active_value_sum() - 0.5 * (4096f64.powi(3) - 1.0)).abs() < 1.0);
    }

    #[test]
    fn trilinear_lookup_crosses_leaf_and_tile_borders() {
        let mut b = SparseGridBuilder::new(0.0, Affine::IDENTITY);
        b.set_voxel([7, 7, 7], 1.0, true);
        b.set_voxel([8, 8, 8], 3.0, true);
        b.fill_tile(2, [8, 0, 0], 2.0, true);
        let g = b.build();
        assert_eq!(g.lookup_index([7.0, 7.0, 7.0]), 1.0);
        assert_eq!(g.lookup_index([8.0, 8.0, 8.0]), 3.0);
        // Corners: (7,7,7) = 1, (8,8,8) = 3, (8,7,7) in the tile = 2, others 0.
        assert!((g.lookup_index([7.5, 7.5, 7.5]) - (1.0 + 3.0 + 2.0) / 8.0).abs() < 1e-6);
        // Between voxel (7, 0, 0) (background) and the tile at x = 8.
        assert!((g.lookup_index([7.25, 3.0, 3.0]) - 0.5).abs() < 1e-6);
        assert!((g.lookup_index([9.5, 3.5, 3.5]) - 2.0).abs() < 1e-6);
    }
}
