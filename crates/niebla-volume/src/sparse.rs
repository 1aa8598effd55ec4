//! Sparse grids: the non-empty 8^3 leaf blocks and the constant tiles of a
//! VDB tree, read by trilinear interpolation in index space.
//!
//! Layout (OpenVDB's 5-4-3 tree, kept so that tiles survive exactly):
//! - a root hash map from `ijk >> 12` to either a constant *root tile*
//!   (4096^3 voxels) or an *upper node*;
//! - an upper node is a table of 32^3 entries, each background, a tile of
//!   128^3 voxels, or a *lower node*;
//! - a lower node is a table of 16^3 entries, each background, a tile of
//!   8^3 voxels, or a *leaf* of 8^3 stored values.
//!
//! Node tables are flat `u32` arrays (one allocation for all upper nodes,
//! one for all lower nodes), so a voxel fetch is one root look-up (a scan
//! of at most 8 entries, else a hash) and two array reads. Empty regions cost nothing below the root, and a large constant
//! region costs one tile.
//!
//! Index space: voxel `(i, j, k)` has its value at the point `(i, j, k)`;
//! [`SparseGrid::lookup_index`] interpolates between the 8 voxels around a
//! point (OpenVDB's `BoxSampler`), with the background value wherever
//! nothing is stored. [`SparseGrid::transform`] maps index to world space.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use crate::Affine;

/// Number of voxels along a leaf's edge.
pub const LEAF_DIM: i32 = 8;
pub(crate) const LEAF_SIZE: usize = 512;
pub(crate) const UPPER_SIZE: usize = 32 * 32 * 32;
pub(crate) const LOWER_SIZE: usize = 16 * 16 * 16;
/// Log2 of the edge (in voxels) of a root child, lower node and leaf.
pub(crate) const UPPER_TOTAL: u32 = 12;
pub(crate) const LOWER_TOTAL: u32 = 7;
pub(crate) const LEAF_TOTAL: u32 = 3;

/// Node-table entry meaning "background, inactive".
pub(crate) const EMPTY: u32 = u32::MAX;
/// Node-table entries with this bit are tile indices; others child indices.
pub(crate) const TILE_BIT: u32 = 1 << 31;

/// A constant region of a VDB tree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tile {
    /// Index-space coordinates of the tile's lowest voxel.
    pub origin: [i32; 3],
    /// Tree depth of the node holding the tile: 0 = root (4096^3 voxels),
    /// 1 = upper node (128^3), 2 = lower node (8^3).
    pub depth: u8,
    /// The value of every voxel in the tile.
    pub value: f32,
    /// Whether the tile's voxels are active.
    pub active: bool,
}

impl Tile {
    /// Edge length in voxels.
    pub fn size(&self) -> i32 {
        1 << tile_log2(self.depth)
    }
}

pub(crate) fn tile_log2(depth: u8) -> u32 {
    match depth {
        0 => UPPER_TOTAL,
        1 => LOWER_TOTAL,
        _ => LEAF_TOTAL,
    }
}

/// An 8^3 block of stored voxel values.
#[derive(Clone, Debug, PartialEq)]
pub struct Leaf {
    /// Index-space coordinates of the lowest voxel (multiples of 8).
    pub origin: [i32; 3],
    /// Values indexed `(i & 7) << 6 | (j & 7) << 3 | (k & 7)` (z fastest,
    /// OpenVDB's order).
    pub values: [f32; LEAF_SIZE],
    /// Active-state bits, bit `n % 64` of word `n / 64` for value `n`.
    pub active: [u64; 8],
}

impl Leaf {
    pub(crate) fn new(origin: [i32; 3], fill: f32, active: bool) -> Self {
        Leaf { origin, values: [fill; LEAF_SIZE], active: [if active { u64::MAX } else { 0 }; 8] }
    }

    /// Offset of voxel `ijk` (any coordinates; only the low 3 bits count).
    #[inline(always)]
    pub fn offset(ijk: [i32; 3]) -> usize {
        (((ijk[0] & 7) << 6) | ((ijk[1] & 7) << 3) | (ijk[2] & 7)) as usize
    }

    /// Whether value `n` is active.
    pub fn is_active(&self, n: usize) -> bool {
        self.active[n / 64] >> (n % 64) & 1 == 1
    }
}

/// A fast hash for integer coordinates (the root map is hit on every voxel
/// fetch; SipHash would dominate the lookup).
#[derive(Default, Clone, Copy)]
pub(crate) struct CoordHasher(u64);

impl Hasher for CoordHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    /// Eight bytes per step: a `[i32; 3]` key (hashed as its 12 bytes after
    /// the length) costs three multiplications, not thirteen.
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            self.write_u64(u64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]));
        }
        let rest = chunks.remainder();
        if !rest.is_empty() {
            let mut tail = [0u8; 8];
            tail[..rest.len()].copy_from_slice(rest);
            // The length marks the tail, so that trailing zero bytes still count.
            self.write_u64(u64::from_le_bytes(tail) ^ ((rest.len() as u64) << 56));
        }
    }
    fn write_i32(&mut self, v: i32) {
        self.write_u64(v as u32 as u64);
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, v: usize) {
        self.write_u64(v as u64);
    }
}

/// Up to this many root entries, [`RootMap::get`] scans a list of them
/// instead of hashing the key.
const SMALL_ROOT: usize = 8;

/// The root table: a hash map from `ijk >> 12` to an entry, whose entries
/// are also kept in a short list while there are at most [`SMALL_ROOT`] of
/// them (most grids span one to eight 4096^3 regions): comparing a few keys
/// costs less than hashing one, and the root is read on every voxel fetch
/// that no accessor caches.
#[derive(Clone, Debug, Default)]
pub(crate) struct RootMap {
    map: HashMap<[i32; 3], u32, BuildHasherDefault<CoordHasher>>,
    /// Every entry of `map` while it holds at most [`SMALL_ROOT`], else empty.
    small: Vec<([i32; 3], u32)>,
}

impl RootMap {
    /// The entry of `key`, if any.
    #[inline]
    pub(crate) fn get(&self, key: &[i32; 3]) -> Option<&u32> {
        if self.map.len() <= SMALL_ROOT {
            return self.small.iter().find(|(k, _)| k == key).map(|(_, v)| v);
        }
        self.map.get(key)
    }

    /// Sets the entry of `key`, returning the one it replaces.
    pub(crate) fn insert(&mut self, key: [i32; 3], value: u32) -> Option<u32> {
        let old = self.map.insert(key, value);
        if self.map.len() <= SMALL_ROOT {
            match self.small.iter_mut().find(|(k, _)| *k == key) {
                Some(e) => e.1 = value,
                None => self.small.push((key, value)),
            }
        } else if !self.small.is_empty() {
            self.small = Vec::new();
        }
        old
    }

    /// Whether `key` has an entry.
    pub(crate) fn contains_key(&self, key: &[i32; 3]) -> bool {
        self.get(key).is_some()
    }

    /// The keys, in no particular order.
    pub(crate) fn keys(&self) -> impl Iterator<Item = &[i32; 3]> {
        self.map.keys()
    }

    /// Heap bytes allocated (the map's buckets with their control bytes, and
    /// the list).
    pub(crate) fn memory_bytes(&self) -> usize {
        let entry = std::mem::size_of::<([i32; 3], u32)>();
        self.map.capacity() * (entry + 1) + self.small.capacity() * entry
    }

    /// Frees unused capacity.
    pub(crate) fn shrink_to_fit(&mut self) {
        self.map.shrink_to_fit();
        self.small.shrink_to_fit();
    }
}

impl std::ops::Index<&[i32; 3]> for RootMap {
    type Output = u32;
    fn index(&self, key: &[i32; 3]) -> &u32 {
        self.get(key).expect("no root entry for the key")
    }
}

/// Where a voxel's value is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Slot {
    Background,
    Tile(u32),
    Leaf(u32),
}

/// A sparse scalar grid in the layout of a VDB tree (see the module docs).
///
/// ```
/// use niebla_volume::{Affine, SparseGridBuilder};
/// let mut b = SparseGridBuilder::new(0.0, Affine::scale_translate([0.5; 3], [0.0; 3]));
/// b.set_voxel([1, 2, 3], 4.0, true);
/// let g = b.build();
/// assert_eq!(g.value([1, 2, 3]), 4.0);
/// assert_eq!(g.lookup_index([1.5, 2.0, 3.0]), 2.0);
/// assert_eq!(g.lookup_world([0.5, 1.0, 1.5]), 4.0);
/// ```
#[derive(Clone, Debug)]
pub struct SparseGrid {
    pub(crate) name: String,
    pub(crate) map_type: String,
    pub(crate) background: f32,
    pub(crate) index_to_world: Affine,
    pub(crate) world_to_index: Affine,
    pub(crate) root: RootMap,
    /// All upper-node tables, `UPPER_SIZE` entries each.
    pub(crate) uppers: Vec<u32>,
    /// Index-space origin of each upper node.
    pub(crate) upper_origins: Vec<[i32; 3]>,
    /// All lower-node tables, `LOWER_SIZE` entries each.
    pub(crate) lowers: Vec<u32>,
    pub(crate) lower_origins: Vec<[i32; 3]>,
    pub(crate) leaves: Vec<Leaf>,
    pub(crate) tiles: Vec<Tile>,
}

/// `floor(v)` as an integer and as a float, the float bit-identical to
/// `v.floor()` (the sign of a zero included), for `|v| < 1e9` (callers
/// check; larger values and NaN give unspecified results, no panic).
///
/// `f32::floor` is a call to libm's `floorf` on baseline x86-64 (no SSE4.1
/// `roundss`); this is a truncating conversion, one compare and a sign copy.
/// Exact: truncation toward zero is the floor for `v >= 0` and one more than
/// it for a negative non-integer `v` (then `t as f32 > v`); every integer of
/// magnitude below 2^31 that is the floor of an `f32` is itself an `f32`, so
/// `i as f32` is exact; and `floor(v)` has the sign of `v` (`floor(-0.0)` is
/// `-0.0`, `floor(-0.5)` is `-1`).
#[inline(always)]
pub(crate) fn floor_to_i32(v: f32) -> (i32, f32) {
    let t = v as i32;
    let i = t - ((t as f32) > v) as i32;
    (i, (i as f32).copysign(v))
}

/// The voxel `floor(p)` and the fractional offset `p - floor(p)` of an
/// index-space point with every `|p[a]| < 1e9` (shared by the tree lookup
/// and the cached accessor so that both compute bit-identical results).
#[inline(always)]
pub(crate) fn split_index_point(p: [f32; 3]) -> ([i32; 3], [f32; 3]) {
    let [(i0, b0), (i1, b1), (i2, b2)] = p.map(floor_to_i32);
    ([i0, i1, i2], [p[0] - b0, p[1] - b1, p[2] - b2])
}

/// Trilinear interpolation of 8 corner values ordered `(dx, dy, dz)` with
/// `dz` fastest, at fractional offset `f`.
#[inline(always)]
pub(crate) fn trilinear(v: [f32; 8], f: [f32; 3]) -> f32 {
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let c00 = lerp(v[0], v[4], f[0]);
    let c01 = lerp(v[1], v[5], f[0]);
    let c10 = lerp(v[2], v[6], f[0]);
    let c11 = lerp(v[3], v[7], f[0]);
    lerp(lerp(c00, c10, f[1]), lerp(c01, c11, f[1]), f[2])
}

#[inline(always)]
fn root_key(ijk: [i32; 3]) -> [i32; 3] {
    ijk.map(|v| v >> UPPER_TOTAL)
}

#[inline(always)]
pub(crate) fn upper_offset(ijk: [i32; 3]) -> usize {
    let m = |v: i32| ((v & 4095) >> LOWER_TOTAL) as usize;
    (m(ijk[0]) << 10) | (m(ijk[1]) << 5) | m(ijk[2])
}

#[inline(always)]
pub(crate) fn lower_offset(ijk: [i32; 3]) -> usize {
    let m = |v: i32| ((v & 127) >> LEAF_TOTAL) as usize;
    (m(ijk[0]) << 8) | (m(ijk[1]) << 4) | m(ijk[2])
}

impl SparseGrid {
    /// An empty grid (every voxel is `background`, inactive).
    pub fn empty(background: f32, index_to_world: Affine) -> SparseGrid {
        SparseGrid {
            name: String::new(),
            map_type: String::new(),
            background,
            world_to_index: index_to_world.inverse().unwrap_or(Affine::IDENTITY),
            index_to_world,
            root: RootMap::default(),
            uppers: Vec::new(),
            upper_origins: Vec::new(),
            lowers: Vec::new(),
            lower_origins: Vec::new(),
            leaves: Vec::new(),
            tiles: Vec::new(),
        }
    }

    /// The grid's name (from its file; empty for grids built in code).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The OpenVDB map type the transform was read from, e.g.
    /// `"UniformScaleTranslateMap"` or `"AffineMap"` (empty if built in code).
    pub fn map_type(&self) -> &str {
        &self.map_type
    }

    /// The value of every voxel where nothing is stored.
    pub fn background(&self) -> f32 {
        self.background
    }

    /// The index-to-world map.
    pub fn transform(&self) -> &Affine {
        &self.index_to_world
    }

    /// The world-to-index map (inverse of [`SparseGrid::transform`]).
    pub fn inverse_transform(&self) -> &Affine {
        &self.world_to_index
    }

    /// Maps a world-space point to (continuous) index space.
    #[inline]
    pub fn world_to_index(&self, p: [f32; 3]) -> [f32; 3] {
        self.world_to_index.transform_point_f32(p)
    }

    /// Maps an index-space point to world space.
    #[inline]
    pub fn index_to_world(&self, p: [f32; 3]) -> [f32; 3] {
        self.index_to_world.transform_point_f32(p)
    }

    /// The stored leaves (8^3 blocks), in file order for grids read from VDB.
    pub fn leaves(&self) -> &[Leaf] {
        &self.leaves
    }

    /// The constant tiles that hold a value other than the background or
    /// are active (inactive background tiles are not kept).
    pub fn tiles(&self) -> &[Tile] {
        &self.tiles
    }

    /// Number of stored 8^3 leaves.
    pub fn leaf_count(&self) -> usize {
        self.leaves.len()
    }

    #[inline(always)]
    pub(crate) fn slot(&self, ijk: [i32; 3]) -> Slot {
        let Some(&e) = self.root.get(&root_key(ijk)) else {
            return Slot::Background;
        };
        if e & TILE_BIT != 0 {
            return if e == EMPTY { Slot::Background } else { Slot::Tile(e & !TILE_BIT) };
        }
        let e = self.uppers[e as usize * UPPER_SIZE + upper_offset(ijk)];
        if e & TILE_BIT != 0 {
            return if e == EMPTY { Slot::Background } else { Slot::Tile(e & !TILE_BIT) };
        }
        let e = self.lowers[e as usize * LOWER_SIZE + lower_offset(ijk)];
        if e & TILE_BIT != 0 {
            return if e == EMPTY { Slot::Background } else { Slot::Tile(e & !TILE_BIT) };
        }
        Slot::Leaf(e)
    }

    /// The value of voxel `ijk` (stored for active and inactive voxels alike,
    /// as OpenVDB's `probeValue`).
    #[inline]
    pub fn value(&self, ijk: [i32; 3]) -> f32 {
        match self.slot(ijk) {
            Slot::Background => self.background,
            Slot::Tile(t) => self.tiles[t as usize].value,
            Slot::Leaf(l) => self.leaves[l as usize].values[Leaf::offset(ijk)],
        }
    }

    /// The value and active state of voxel `ijk`.
    pub fn probe(&self, ijk: [i32; 3]) -> (f32, bool) {
        match self.slot(ijk) {
            Slot::Background => (self.background, false),
            Slot::Tile(t) => {
                let t = &self.tiles[t as usize];
                (t.value, t.active)
            }
            Slot::Leaf(l) => {
                let leaf = &self.leaves[l as usize];
                let n = Leaf::offset(ijk);
                (leaf.values[n], leaf.is_active(n))
            }
        }
    }

    /// Trilinear interpolation at index-space point `p` between the voxels
    /// `floor(p)` and `floor(p) + 1` (the background where nothing is stored;
    /// `p` must be within about +-2^30 of the origin).
    #[inline]
    pub fn lookup_index(&self, p: [f32; 3]) -> f32 {
        if !(p.iter().all(|v| v.abs() < 1.0e9)) {
            return self.background;
        }
        let (ijk, f) = split_index_point(p);
        trilinear(self.corners(ijk), f)
    }

    /// Trilinear interpolation at world-space point `p`.
    #[inline]
    pub fn lookup_world(&self, p: [f32; 3]) -> f32 {
        self.lookup_index(self.world_to_index(p))
    }

    /// The 8 voxels `ijk + (dx, dy, dz)`, `d in {0,1}`, ordered with dz
    /// fastest, fetching one leaf when all 8 lie in the same leaf.
    #[inline(always)]
    fn corners(&self, ijk: [i32; 3]) -> [f32; 8] {
        if (ijk[0] & 7) != 7 && (ijk[1] & 7) != 7 && (ijk[2] & 7) != 7 {
            match self.slot(ijk) {
                Slot::Background => return [self.background; 8],
                Slot::Tile(t) => return [self.tiles[t as usize].value; 8],
                Slot::Leaf(l) => {
                    let values = &self.leaves[l as usize].values;
                    let n = Leaf::offset(ijk);
                    return [
                        values[n],
                        values[n + 1],
                        values[n + 8],
                        values[n + 9],
                        values[n + 64],
                        values[n + 65],
                        values[n + 72],
                        values[n + 73],
                    ];
                }
            }
        }
        // The corners straddle blocks along the axes where `ijk` is on a
        // block's last voxel: find each block they touch once (every voxel
        // of an 8^3 block has the same slot), not once per corner.
        let straddle = [(ijk[0] & 7 == 7) as usize, (ijk[1] & 7 == 7) as usize, (ijk[2] & 7 == 7) as usize];
        let mut slots: [Option<Slot>; 8] = [None; 8];
        std::array::from_fn(|c| {
            let d = [(c >> 2) & 1, (c >> 1) & 1, c & 1];
            let v = [ijk[0] + d[0] as i32, ijk[1] + d[1] as i32, ijk[2] + d[2] as i32];
            let block = ((d[0] & straddle[0]) << 2) | ((d[1] & straddle[1]) << 1) | (d[2] & straddle[2]);
            match *slots[block].get_or_insert_with(|| self.slot(v)) {
                Slot::Background => self.background,
                Slot::Tile(t) => self.tiles[t as usize].value,
                Slot::Leaf(l) => self.leaves[l as usize].values[Leaf::offset(v)],
            }
        })
    }

    /// Bytes of the stored leaves and kept tiles (`size_of::<Leaf>()` per
    /// leaf: 512 values, the active mask and the origin; `size_of::<Tile>()`
    /// per tile): the data itself, without the tree that finds it.
    pub fn payload_bytes(&self) -> u64 {
        (self.leaves.len() * std::mem::size_of::<Leaf>() + self.tiles.len() * std::mem::size_of::<Tile>()) as u64
    }

    /// Heap bytes the grid holds: [`SparseGrid::payload_bytes`] plus the
    /// root map, the node tables and node origins, counted by allocated
    /// capacity (what the allocator was asked for).
    pub fn memory_bytes(&self) -> u64 {
        use std::mem::size_of;
        // hashbrown: one (key, value) slot plus one control byte per bucket.
        let root = self.root.memory_bytes();
        let tables = (self.uppers.capacity() + self.lowers.capacity()) * size_of::<u32>();
        let origins = (self.upper_origins.capacity() + self.lower_origins.capacity()) * size_of::<[i32; 3]>();
        let data = self.leaves.capacity() * size_of::<Leaf>() + self.tiles.capacity() * size_of::<Tile>();
        (root + tables + origins + data + self.name.capacity() + self.map_type.capacity()) as u64
    }

    /// Number of active voxels (leaf voxels plus the volume of active tiles).
    pub fn active_voxel_count(&self) -> u64 {
        let leaf: u64 = self.leaves.iter().map(|l| l.active.iter().map(|w| w.count_ones() as u64).sum::<u64>()).sum();
        let tiles: u64 = self.tiles.iter().filter(|t| t.active).map(|t| (t.size() as u64).pow(3)).sum();
        leaf + tiles
    }

    /// Sum of the values of all active voxels, in f64.
    pub fn active_value_sum(&self) -> f64 {
        let mut sum = 0.0f64;
        for l in &self.leaves {
            for n in 0..LEAF_SIZE {
                if l.is_active(n) {
                    sum += l.values[n] as f64;
                }
            }
        }
        for t in self.tiles.iter().filter(|t| t.active) {
            sum += t.value as f64 * (t.size() as f64).powi(3);
        }
        sum
    }

    /// Number of active tiles at tree depth 0 (root, 4096^3), 1 (128^3) and
    /// 2 (8^3).
    pub fn active_tile_counts(&self) -> [usize; 3] {
        let mut counts = [0; 3];
        for t in self.tiles.iter().filter(|t| t.active) {
            counts[t.depth.min(2) as usize] += 1;
        }
        counts
    }

    /// Inclusive index-space bounds `(min, max)` of the active voxels
    /// (OpenVDB's `evalActiveVoxelBoundingBox`), or `None` if none is active.
    pub fn active_bounds_index(&self) -> Option<([i32; 3], [i32; 3])> {
        let mut b = Bounds::new();
        for l in &self.leaves {
            for n in 0..LEAF_SIZE {
                if l.is_active(n) {
                    let d = [(n >> 6) as i32, ((n >> 3) & 7) as i32, (n & 7) as i32];
                    b.add(std::array::from_fn(|a| l.origin[a] + d[a]));
                }
            }
        }
        for t in self.tiles.iter().filter(|t| t.active) {
            b.add(t.origin);
            b.add(t.origin.map(|v| v + t.size() - 1));
        }
        b.get()
    }

    /// Inclusive index-space bounds of every stored voxel that may differ
    /// from the background: all leaves (whole 8^3 blocks) and all kept
    /// tiles. Outside this box the grid is exactly the background.
    pub fn data_bounds_index(&self) -> Option<([i32; 3], [i32; 3])> {
        let mut b = Bounds::new();
        for l in &self.leaves {
            b.add(l.origin);
            b.add(l.origin.map(|v| v + LEAF_DIM - 1));
        }
        for t in &self.tiles {
            b.add(t.origin);
            b.add(t.origin.map(|v| v + t.size() - 1));
        }
        b.get()
    }

    /// World-space axis-aligned box enclosing the region where the
    /// interpolated field can differ from the background: the data bounds
    /// grown by one voxel (interpolation reaches one voxel further), mapped
    /// to world space. `None` for an empty grid.
    pub fn world_bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let (lo, hi) = self.data_bounds_index()?;
        let lo = lo.map(|v| v as f64 - 1.0);
        let hi = hi.map(|v| v as f64 + 1.0);
        let mut out_lo = [f64::INFINITY; 3];
        let mut out_hi = [f64::NEG_INFINITY; 3];
        for c in 0..8 {
            let corner = [
                if c & 1 == 0 { lo[0] } else { hi[0] },
                if c & 2 == 0 { lo[1] } else { hi[1] },
                if c & 4 == 0 { lo[2] } else { hi[2] },
            ];
            let w = self.index_to_world.transform_point(corner);
            for a in 0..3 {
                out_lo[a] = out_lo[a].min(w[a]);
                out_hi[a] = out_hi[a].max(w[a]);
            }
        }
        Some((out_lo.map(|v| v as f32), out_hi.map(|v| v as f32)))
    }

    /// Largest value the grid holds anywhere (stored voxels, tiles and the
    /// background), an upper bound of every interpolated value.
    pub fn max_value(&self) -> f32 {
        let leaf_max = self.leaves.iter().flat_map(|l| l.values.iter().copied()).fold(f32::NEG_INFINITY, f32::max);
        let tile_max = self.tiles.iter().map(|t| t.value).fold(f32::NEG_INFINITY, f32::max);
        self.background.max(leaf_max).max(tile_max)
    }
}

/// Running inclusive integer bounds.
struct Bounds {
    lo: [i32; 3],
    hi: [i32; 3],
}

impl Bounds {
    fn new() -> Self {
        Bounds { lo: [i32::MAX; 3], hi: [i32::MIN; 3] }
    }
    fn add(&mut self, p: [i32; 3]) {
        self.lo = std::array::from_fn(|a| self.lo[a].min(p[a]));
        self.hi = std::array::from_fn(|a| self.hi[a].max(p[a]));
    }
    fn get(&self) -> Option<([i32; 3], [i32; 3])> {
        (self.lo[0] <= self.hi[0]).then_some((self.lo, self.hi))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `floor_to_i32` equals `f32::floor` bit for bit (and its integer the
    /// floor's value) on every 9973rd bit pattern below 1e9 in magnitude
    /// (263,885 values: both signs, every exponent), every multiple of
    /// 1/64 in [-300, 300], and the boundary cases (zeros of both signs,
    /// integers and their neighbours, the largest values allowed).
    #[test]
    fn integer_floor_is_bit_identical_to_floorf() {
        let check = |v: f32| {
            if v.is_nan() || v.abs() >= 1.0e9 {
                return 0;
            }
            let (i, f) = floor_to_i32(v);
            assert_eq!(f.to_bits(), v.floor().to_bits(), "floor of {v:e} ({:#x})", v.to_bits());
            assert_eq!(i as f32, v.floor(), "integer floor of {v:e}");
            1
        };
        let mut n = 0;
        for bits in (0..=u32::MAX).step_by(9973) {
            n += check(f32::from_bits(bits));
        }
        assert_eq!(n, 263_885);
        for k in -300 * 64..=300 * 64 {
            check(k as f32 / 64.0);
        }
        let edges = [0.0f32, -0.0, 1.0, -1.0, 0.5, -0.5, 8388607.5, -8388607.5, 8388608.0, -8388609.0, 999_999_940.0];
        for v in edges {
            check(v);
            check(-v);
            check(f32::from_bits(v.to_bits().wrapping_add(1)));
            check(f32::from_bits(v.to_bits().wrapping_sub(1)));
        }
    }

    /// The root table answers like a plain hash map below, at and above the
    /// size where it stops keeping the list of entries, replacements included.
    #[test]
    fn root_map_answers_like_a_hash_map_at_every_size() {
        let mut root = RootMap::default();
        let mut reference: HashMap<[i32; 3], u32> = HashMap::new();
        let key = |i: i32| [i % 3 - 1, (i / 3) % 3 - 1, i / 9 - 1];
        for i in 0..27 {
            assert_eq!(root.insert(key(i), i as u32), reference.insert(key(i), i as u32));
            // Replace an earlier entry now and then.
            if i % 4 == 0 {
                assert_eq!(root.insert(key(i / 2), 100 + i as u32), reference.insert(key(i / 2), 100 + i as u32));
            }
            for j in -2..30 {
                assert_eq!(root.get(&key(j)), reference.get(&key(j)), "{i} entries, key {:?}", key(j));
                assert_eq!(root.contains_key(&key(j)), reference.contains_key(&key(j)));
            }
            assert_eq!(root.small.is_empty(), reference.len() > SMALL_ROOT || reference.is_empty());
        }
        let mut keys: Vec<_> = root.keys().copied().collect();
        keys.sort_unstable();
        let mut want: Vec<_> = reference.keys().copied().collect();
        want.sort_unstable();
        assert_eq!(keys, want);
        assert_eq!(root[&key(5)], reference[&key(5)]);
    }

    /// Trilinear lookups whose corners straddle leaves, tiles and empty
    /// space (the path that finds each block once) return the trilinear
    /// blend of [`SparseGrid::value`] at the 8 corners, bit for bit.
    #[test]
    fn lookups_across_blocks_equal_the_blend_of_voxel_values() {
        use crate::{Affine, SparseGridBuilder};
        let mut b = SparseGridBuilder::new(0.25, Affine::IDENTITY);
        let mut state = 0x2545_f491_u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state
        };
        for i in -12..12 {
            for j in -12..12 {
                for k in -12..12 {
                    if next() % 3 != 0 {
                        b.set_voxel([i, j, k], (next() % 1000) as f32 / 100.0, true);
                    }
                }
            }
        }
        // A constant tile of one 128^3 lower node, next to the leaves.
        b.fill_tile(1, [128, 0, 0], 3.5, true);
        let g = b.build();
        let mut straddling = 0;
        for n in 0..20000 {
            let r = |x: u32| (x % 4000) as f32 / 100.0 - 20.0;
            let mut p = [r(next()), r(next()), r(next())];
            if n % 4 == 0 {
                p[0] += 135.0;
            }
            let ijk = p.map(|v| v.floor() as i32);
            let f = [p[0] - p[0].floor(), p[1] - p[1].floor(), p[2] - p[2].floor()];
            straddling += ijk.iter().any(|v| v & 7 == 7) as u32;
            let v: [f32; 8] = std::array::from_fn(|c| {
                g.value([ijk[0] + ((c >> 2) & 1) as i32, ijk[1] + ((c >> 1) & 1) as i32, ijk[2] + (c & 1) as i32])
            });
            assert_eq!(g.lookup_index(p).to_bits(), trilinear(v, f).to_bits(), "at {p:?}");
        }
        assert!(straddling > 5000, "{straddling}");
    }

    /// The coordinate hasher reads a `[i32; 3]` in 8-byte steps: keys that
    /// differ in any coordinate (or only in the tail's zero bytes) hash apart.
    #[test]
    fn coordinate_hash_separates_keys() {
        use std::hash::BuildHasher;
        let h = |k: &[i32; 3]| BuildHasherDefault::<CoordHasher>::default().hash_one(k);
        let keys = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, 0, -1], [1 << 19, 0, 0]];
        for (a, ka) in keys.iter().enumerate() {
            for kb in &keys[a + 1..] {
                assert_ne!(h(ka), h(kb), "{ka:?} {kb:?}");
            }
        }
        let mut a = CoordHasher::default();
        a.write(&[1, 0, 0, 0]);
        let mut b = CoordHasher::default();
        b.write(&[1, 0, 0, 0, 0]);
        assert_ne!(a.finish(), b.finish());
    }
}
