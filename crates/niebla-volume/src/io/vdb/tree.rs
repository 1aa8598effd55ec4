//! Reading a VDB tree (5-4-3 configuration) into one [`SparseGrid`] per
//! value component (one for scalar grids, three for Vec3 grids, all with the
//! same nodes and leaves):
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
    /// An error when the component grids plus one more node of `extra`
    /// bytes in each exceed the limit.
    fn check(&self, r: &ByteReader, grids: &[SparseGrid], extra: usize) -> Result<(), VolumeError> {
        let bytes: u64 = grids
            .iter()
            .map(|grid| {
                (grid.leaves.len() * std::mem::size_of::<Leaf>()
                    + (grid.uppers.len() + grid.lowers.len()) * std::mem::size_of::<u32>()
                    + grid.tiles.len() * std::mem::size_of::<Tile>()
                    + extra) as u64
            })
            .sum();
        let grid = &grids[0];
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

/// Reads the tree at the reader's position into `grids`, one per value
/// component (`codec.arity` of them, whose transform and name are set by
/// the caller; the background is read here). `codec.background` is updated
/// with it.
pub(crate) fn read_tree(
    r: &mut ByteReader,
    codec: &mut ValueCodec,
    grids: &mut [SparseGrid],
    limit: &MemoryLimit,
) -> Result<(), VolumeError> {
    debug_assert_eq!(grids.len(), codec.arity);
    let pos = r.pos();
    let buffer_count = r.i32("tree buffer count")?;
    if buffer_count != 1 {
        return Err(r.corrupt_at(pos, format!("tree buffer count {buffer_count} (expected 1)")));
    }
    codec.background = read_value(r, codec.kind, codec.arity, "background value")?;
    for (c, grid) in grids.iter_mut().enumerate() {
        grid.background = codec.background[c];
    }
    let num_tiles = r.u32("root tile count")?;
    let num_children = r.u32("root child count")?;

    // Root tiles: origin, value, active byte.
    for _ in 0..num_tiles {
        let pos = r.pos();
        let origin = read_origin(r, "root tile origin")?;
        let value = read_value(r, codec.kind, codec.arity, "root tile value")?;
        let active = r.u8("root tile active flag")? != 0;
        check_aligned(r, pos, origin, UPPER_TOTAL)?;
        let key = origin.map(|v| v >> UPPER_TOTAL);
        for (c, grid) in grids.iter_mut().enumerate() {
            let entry = grid
                .tile_entry(Tile { origin, depth: 0, value: value[c], active })
                .ok_or_else(|| r.corrupt_at(pos, "too many tiles"))?;
            if grid.root.insert(key, entry).is_some() {
                return Err(r.corrupt_at(pos, format!("two root entries at {origin:?}")));
            }
        }
    }

    // Root children: origin, then the upper node's topology.
    let mut leaf_order = Vec::new();
    for _ in 0..num_children {
        let pos = r.pos();
        let origin = read_origin(r, "root child origin")?;
        check_aligned(r, pos, origin, UPPER_TOTAL)?;
        let key = origin.map(|v| v >> UPPER_TOTAL);
        if grids[0].root.contains_key(&key) {
            return Err(r.corrupt_at(pos, format!("two root entries at {origin:?}")));
        }
        let upper = read_upper(r, codec, grids, origin, &mut leaf_order, limit)?;
        for grid in grids.iter_mut() {
            grid.root.insert(key, upper);
        }
    }

    // Leaf buffers, in topology order.
    let arity = codec.arity;
    let mut values = vec![0f32; LEAF_SIZE * arity];
    for &l in &leaf_order {
        let mask = read_mask(r, LEAF_SIZE, "leaf value mask")?;
        read_compressed_values(r, codec, &mask, &mut values)?;
        for (c, grid) in grids.iter_mut().enumerate() {
            let leaf = &mut grid.leaves[l as usize];
            for (n, v) in leaf.values.iter_mut().enumerate() {
                *v = values[n * arity + c];
            }
            for (w, &word) in leaf.active.iter_mut().zip(&mask) {
                *w = word;
            }
        }
    }
    for grid in grids.iter_mut() {
        grid.shrink_to_fit();
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
    /// `arity` components per entry.
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
    let mut values = vec![0f32; size * codec.arity];
    read_compressed_values(r, codec, &value_mask, &mut values)?;
    Ok(InternalNode { child_mask, value_mask, values })
}

/// Allocates the node table for `node` in every component grid and fills
/// its non-child slots with tiles (active ones, and inactive ones whose
/// value is not the background; a component equal to its background in an
/// inactive tile stays empty in that component's grid).
fn place_node(
    r: &ByteReader,
    codec: &ValueCodec,
    grids: &mut [SparseGrid],
    node: &InternalNode,
    origin: [i32; 3],
    level: Level,
) -> Result<usize, VolumeError> {
    let (size, log2_dim, child_log2, depth) = level.shape();
    let mut index = 0;
    for grid in grids.iter_mut() {
        index = match level {
            Level::Upper => grid.push_upper(origin, EMPTY),
            Level::Lower => grid.push_lower(origin, EMPTY),
        } as usize;
    }
    let arity = codec.arity;
    for (n, value) in node.values.chunks_exact(arity).enumerate() {
        let active = bit(&node.value_mask, n);
        let is_background = value.iter().zip(codec.background).all(|(v, b)| v.to_bits() == b.to_bits());
        if bit(&node.child_mask, n) || (!active && is_background) {
            continue;
        }
        for (c, grid) in grids.iter_mut().enumerate() {
            let tile = Tile { origin: child_origin(origin, n, log2_dim, child_log2), depth, value: value[c], active };
            let entry = grid.tile_entry(tile).ok_or_else(|| r.corrupt_at(r.pos(), "too many tiles"))?;
            match level {
                Level::Upper => grid.uppers[index * size + n] = entry,
                Level::Lower => grid.lowers[index * size + n] = entry,
            }
        }
    }
    Ok(index)
}

fn read_upper(
    r: &mut ByteReader,
    codec: &ValueCodec,
    grids: &mut [SparseGrid],
    origin: [i32; 3],
    leaf_order: &mut Vec<u32>,
    limit: &MemoryLimit,
) -> Result<u32, VolumeError> {
    let node = read_internal(r, codec, Level::Upper)?;
    limit.check(r, grids, UPPER_SIZE * std::mem::size_of::<u32>())?;
    let u = place_node(r, codec, grids, &node, origin, Level::Upper)?;
    for n in ones(&node.child_mask) {
        let o = child_origin(origin, n, 5, LOWER_TOTAL);
        let lower = read_lower(r, codec, grids, o, leaf_order, limit)?;
        for grid in grids.iter_mut() {
            grid.uppers[u * UPPER_SIZE + n] = lower;
        }
    }
    Ok(u as u32)
}

fn read_lower(
    r: &mut ByteReader,
    codec: &ValueCodec,
    grids: &mut [SparseGrid],
    origin: [i32; 3],
    leaf_order: &mut Vec<u32>,
    limit: &MemoryLimit,
) -> Result<u32, VolumeError> {
    let node = read_internal(r, codec, Level::Lower)?;
    limit.check(r, grids, LOWER_SIZE * std::mem::size_of::<u32>())?;
    let l = place_node(r, codec, grids, &node, origin, Level::Lower)?;
    for n in ones(&node.child_mask) {
        let o = child_origin(origin, n, 4, LEAF_TOTAL);
        // LeafNode::readTopology: just the value mask; values come later.
        let mask = read_mask(r, LEAF_SIZE, "leaf topology mask")?;
        limit.check(r, grids, std::mem::size_of::<Leaf>())?;
        let mut index = 0;
        for (c, grid) in grids.iter_mut().enumerate() {
            let mut leaf = Leaf::new(o, codec.background[c], false);
            leaf.active.copy_from_slice(&mask);
            index = grid.push_leaf(leaf);
            grid.lowers[l * LOWER_SIZE + n] = index;
        }
        leaf_order.push(index);
    }
    Ok(l as u32)
}
