//! Reading a VDB tree (5-4-3 configuration) into a [`SparseGrid`]:
//! topology first (`RootNode::readTopology`, `InternalNode::readTopology`,
//! `LeafNode::readTopology`), then the leaf buffers in the same order
//! (`LeafNode::readBuffers`).
//!
//! Every node's child and value masks are read before anything is
//! allocated for it, so allocations stay proportional to the bytes actually
//! present in the file.

use crate::io::bytes::ByteReader;
use crate::io::vdb::values::{bit, ones, read_compressed_values, read_mask, read_value, ValueCodec};
use crate::sparse::{Leaf, Tile, EMPTY, LEAF_SIZE, LEAF_TOTAL, LOWER_SIZE, LOWER_TOTAL, UPPER_SIZE, UPPER_TOTAL};
use crate::{SparseGrid, VolumeError};

/// The most memory a tree may take, checked before each node is allocated.
pub(crate) struct MemoryLimit<'a> {
    pub(crate) max_bytes: u64,
    /// The grid's name, for the error.
    pub(crate) grid: &'a str,
}

impl MemoryLimit<'_> {
    /// An error when `grid` plus one more node of `extra` bytes exceeds the
    /// limit.
    fn check(&self, r: &ByteReader, grid: &SparseGrid, extra: usize) -> Result<(), VolumeError> {
        let bytes = (grid.leaves.len() * std::mem::size_of::<Leaf>()
            + (grid.uppers.len() + grid.lowers.len()) * std::mem::size_of::<u32>()
            + grid.tiles.len() * std::mem::size_of::<Tile>()
            + extra) as u64;
        if bytes <= self.max_bytes {
            return Ok(());
        }
        Err(VolumeError::TooLarge {
            path: r.path().to_path_buf(),
            what: format!(
                "grid {:?} ({} leaves, {} internal nodes so far)",
                self.grid,
                grid.leaves.len(),
                grid.upper_origins.len() + grid.lower_origins.len()
            ),
            bytes,
            limit: self.max_bytes,
        })
    }
}

/// Reads the tree at the reader's position into `grid` (whose transform,
/// name and background are set by the caller; the background is read
/// here). `codec.background` is updated with it.
pub(crate) fn read_tree(
    r: &mut ByteReader,
    codec: &mut ValueCodec,
    grid: &mut SparseGrid,
    limit: &MemoryLimit,
) -> Result<(), VolumeError> {
    let pos = r.pos();
    let buffer_count = r.i32("tree buffer count")?;
    if buffer_count != 1 {
        return Err(r.corrupt_at(pos, format!("tree buffer count {buffer_count} (expected 1)")));
    }
    codec.background = read_value(r, codec.kind, "background value")?;
    grid.background = codec.background;
    let num_tiles = r.u32("root tile count")?;
    let num_children = r.u32("root child count")?;

    // Root tiles: origin, value, active byte.
    for _ in 0..num_tiles {
        let pos = r.pos();
        let origin = read_origin(r, "root tile origin")?;
        let value = read_value(r, codec.kind, "root tile value")?;
        let active = r.u8("root tile active flag")? != 0;
        check_aligned(r, pos, origin, UPPER_TOTAL)?;
        let key = origin.map(|v| v >> UPPER_TOTAL);
        let entry = grid
            .tile_entry(Tile { origin, depth: 0, value, active })
            .ok_or_else(|| r.corrupt_at(pos, "too many tiles"))?;
        if grid.root.insert(key, entry).is_some() {
            return Err(r.corrupt_at(pos, format!("two root entries at {origin:?}")));
        }
    }

    // Root children: origin, then the upper node's topology.
    let mut leaf_order = Vec::new();
    for _ in 0..num_children {
        let pos = r.pos();
        let origin = read_origin(r, "root child origin")?;
        check_aligned(r, pos, origin, UPPER_TOTAL)?;
        let key = origin.map(|v| v >> UPPER_TOTAL);
        if grid.root.contains_key(&key) {
            return Err(r.corrupt_at(pos, format!("two root entries at {origin:?}")));
        }
        let upper = read_upper(r, codec, grid, origin, &mut leaf_order, limit)?;
        grid.root.insert(key, upper);
    }

    // Leaf buffers, in topology order.
    let mut values = [0f32; LEAF_SIZE];
    for &l in &leaf_order {
        let mask = read_mask(r, LEAF_SIZE, "leaf value mask")?;
        read_compressed_values(r, codec, &mask, &mut values)?;
        let leaf = &mut grid.leaves[l as usize];
        leaf.values = values;
        for (w, word) in leaf.active.iter_mut().zip(mask) {
            *w = word;
        }
    }
    Ok(())
}

fn read_origin(r: &mut ByteReader, what: &str) -> Result<[i32; 3], VolumeError> {
    Ok([r.i32(what)?, r.i32(what)?, r.i32(what)?])
}

fn check_aligned(r: &ByteReader, pos: usize, origin: [i32; 3], log2: u32) -> Result<(), VolumeError> {
    if origin.iter().any(|v| v & ((1 << log2) - 1) != 0) {
        return Err(r.corrupt_at(pos, format!("node origin {origin:?} is not a multiple of {}", 1 << log2)));
    }
    Ok(())
}

/// Origin of child `n` of a node with `log2_dim` children per axis, each
/// `child_log2` voxels wide.
fn child_origin(origin: [i32; 3], n: usize, log2_dim: u32, child_log2: u32) -> [i32; 3] {
    let mask = (1usize << log2_dim) - 1;
    let d = [n >> (2 * log2_dim), (n >> log2_dim) & mask, n & mask];
    std::array::from_fn(|a| origin[a] + ((d[a] as i32) << child_log2))
}

/// An internal node's masks and values (`InternalNode::readTopology` up to
/// its children).
struct InternalNode {
    child_mask: Vec<u64>,
    value_mask: Vec<u64>,
    values: Vec<f32>,
}

/// The two internal node levels of a 5-4-3 tree.
#[derive(Clone, Copy)]
enum Level {
    Upper,
    Lower,
}

impl Level {
    /// (entries, log2 children per axis, log2 child width, tile depth)
    fn shape(self) -> (usize, u32, u32, u8) {
        match self {
            Level::Upper => (UPPER_SIZE, 5, LOWER_TOTAL, 1),
            Level::Lower => (LOWER_SIZE, 4, LEAF_TOTAL, 2),
        }
    }
}

fn read_internal(r: &mut ByteReader, codec: &ValueCodec, level: Level) -> Result<InternalNode, VolumeError> {
    let (size, ..) = level.shape();
    let what = match level {
        Level::Upper => "upper node",
        Level::Lower => "lower node",
    };
    let child_mask = read_mask(r, size, &format!("{what} child mask"))?;
    let value_mask = read_mask(r, size, &format!("{what} value mask"))?;
    let mut values = vec![0f32; size];
    read_compressed_values(r, codec, &value_mask, &mut values)?;
    Ok(InternalNode { child_mask, value_mask, values })
}

/// Allocates the node table for `node` and fills its non-child slots with
/// tiles (active ones, and inactive ones whose value is not the background).
fn place_node(
    r: &ByteReader,
    codec: &ValueCodec,
    grid: &mut SparseGrid,
    node: &InternalNode,
    origin: [i32; 3],
    level: Level,
) -> Result<usize, VolumeError> {
    let (size, log2_dim, child_log2, depth) = level.shape();
    let index = match level {
        Level::Upper => grid.push_upper(origin, EMPTY),
        Level::Lower => grid.push_lower(origin, EMPTY),
    } as usize;
    for (n, &value) in node.values.iter().enumerate() {
        let active = bit(&node.value_mask, n);
        if bit(&node.child_mask, n) || (!active && value.to_bits() == codec.background.to_bits()) {
            continue;
        }
        let tile = Tile { origin: child_origin(origin, n, log2_dim, child_log2), depth, value, active };
        let entry = grid.tile_entry(tile).ok_or_else(|| r.corrupt_at(r.pos(), "too many tiles"))?;
        match level {
            Level::Upper => grid.uppers[index * size + n] = entry,
            Level::Lower => grid.lowers[index * size + n] = entry,
        }
    }
    Ok(index)
}

fn read_upper(
    r: &mut ByteReader,
    codec: &ValueCodec,
    grid: &mut SparseGrid,
    origin: [i32; 3],
    leaf_order: &mut Vec<u32>,
    limit: &MemoryLimit,
) -> Result<u32, VolumeError> {
    let node = read_internal(r, codec, Level::Upper)?;
    limit.check(r, grid, UPPER_SIZE * std::mem::size_of::<u32>())?;
    let u = place_node(r, codec, grid, &node, origin, Level::Upper)?;
    for n in ones(&node.child_mask) {
        let o = child_origin(origin, n, 5, LOWER_TOTAL);
        let lower = read_lower(r, codec, grid, o, leaf_order, limit)?;
        grid.uppers[u * UPPER_SIZE + n] = lower;
    }
    Ok(u as u32)
}

fn read_lower(
    r: &mut ByteReader,
    codec: &ValueCodec,
    grid: &mut SparseGrid,
    origin: [i32; 3],
    leaf_order: &mut Vec<u32>,
    limit: &MemoryLimit,
) -> Result<u32, VolumeError> {
    let node = read_internal(r, codec, Level::Lower)?;
    limit.check(r, grid, LOWER_SIZE * std::mem::size_of::<u32>())?;
    let l = place_node(r, codec, grid, &node, origin, Level::Lower)?;
    for n in ones(&node.child_mask) {
        let o = child_origin(origin, n, 4, LEAF_TOTAL);
        // LeafNode::readTopology: just the value mask; values come later.
        let mask = read_mask(r, LEAF_SIZE, "leaf topology mask")?;
        limit.check(r, grid, std::mem::size_of::<Leaf>())?;
        let mut leaf = Leaf::new(o, codec.background, false);
        leaf.active.copy_from_slice(&mask);
        let index = grid.push_leaf(leaf);
        leaf_order.push(index);
        grid.lowers[l * LOWER_SIZE + n] = index;
    }
    Ok(l as u32)
}
