//! Voxel data for niebla: dense and sparse grids with trilinear lookup,
//! majorant and minorant grids walked by a 3D DDA, seeded procedural
//! densities, and readers for OpenVDB (`.vdb`), Mitsuba 3 (`.vol`) and
//! NumPy (`.npy`) files. No rendering here.
//!
//! # Spaces and conventions
//! - **Dense grids** ([`DenseGrid`], [`DenseRgbGrid`]) live in their own
//!   *local* space: `nx * ny * nz` values at the cell centers of the box
//!   `bounds_min..bounds_max`, trilinear in between; within half a cell of a
//!   face the nearest cells' values extend to the face (clamp), and outside
//!   the box the value is zero (Mitsuba 3's convention). Storage is
//!   `[z][y][x]`, x fastest.
//! - **Sparse grids** ([`SparseGrid`]) keep a VDB tree's leaves and tiles in
//!   *index* space (voxel `(i, j, k)` has its value at the point `(i, j, k)`,
//!   OpenVDB's convention), with the background value wherever nothing is
//!   stored. [`SparseGrid::transform`] is the file's index-to-world
//!   [`Affine`]; the renderer composes a medium's `to_world` after it.
//! - **Majorant grids** ([`MajorantGrid`]) cover a box in the source grid's
//!   space (local space for dense grids, index space for sparse grids) and
//!   bound every value trilinear interpolation can produce inside each cell.
//!   [`MajorantGrid::walk`] runs a 3D DDA along a ray given in that space
//!   and reports [`Segment`]s in order through a `ControlFlow` callback. A
//!   ray mapped into that space by an affine map keeps its `t` parameter as
//!   long as the direction is mapped as a vector and not renormalized.
//! - **Minorant grids** ([`DensityBoundGrid::minorant_from_dense`],
//!   [`DensityBoundGrid::minorant_from_sparse`]) are [`DensityBoundGrid`]s (the
//!   type of majorant grids too, [`MajorantGrid`] being its alias) holding the
//!   per-cell *minimum* that interpolation can reach (the control density
//!   of residual ratio tracking), over the same voxels as the majorant.
//!   Built with the same arguments as a majorant grid they have exactly its
//!   cells ([`MajorantGrid::same_layout`]): walk the majorant grid with
//!   [`MajorantGrid::walk_cells`] and read the minorant of each cell with
//!   [`MajorantGrid::value`]. Not clamped at zero; a sparse grid's unstored
//!   voxels count as the background.
//! - **Procedural densities** ([`procedural_density`]) are dense grids over
//!   the unit box, y up, values in `[0, 1]` and zero on the face voxels: a
//!   cumulus [`ProceduralShape::Cloud`] or a rising
//!   [`ProceduralShape::Plume`] eroded by seeded fBm gradient noise, the
//!   same grid for the same [`ProceduralParams`]; out-of-range parameters
//!   give [`VolumeError::InvalidParameter`] naming the field.
//!
//! # Files
//! - [`VdbFile`]: OpenVDB files (format versions 222-224, as written by
//!   OpenVDB 6-12): float, double and half-float scalar grids by name, every
//!   linear transform map, compression none, zip and blosc (lz4 and zlib
//!   codecs), mask-compressed nodes, root and internal-node tiles.
//! - [`read_vol`]: Mitsuba 3 binary `VOL` version 3, float32, 1 or 3
//!   channels, with the bounding box stored in the file.
//! - [`read_npy`]: `.npy` float32/float64 little-endian C-order arrays of
//!   shape `(nz, ny, nx)` (scalar, indexed `[z][y][x]`) or `(nz, ny, nx, 3)`
//!   (RGB), mapped to the unit box until given bounds.
//!
//! Every failure is a [`VolumeError`] naming the file and what was expected;
//! corrupt or truncated files give errors, never panics, and no size read
//! from a file is trusted before it is checked against the remaining bytes
//! (memory grows at most linearly with the file: a node is allocated only
//! after its masks have been read).
//!
//! # Example
//! ```
//! use std::ops::ControlFlow;
//! use niebla_volume::{DenseGrid, DensityBoundGrid, MajorantGrid};
//!
//! // A 4^3 density grid filling [-1, 1]^3, one bright cell.
//! let mut data = vec![0.0; 64];
//! data[(2 * 4 + 1) * 4 + 3] = 5.0; // [z = 2][y = 1][x = 3]
//! let density = DenseGrid::new([4, 4, 4], data, [-1.0; 3], [1.0; 3])?;
//! assert_eq!(density.lookup([0.75, -0.25, 0.25]), 5.0); // that cell's center
//!
//! // Majorants for a tracker, and the pieces of a ray with their bounds.
//! let majorants = MajorantGrid::from_dense(&density, [2, 2, 2]);
//! let mut pieces = Vec::new();
//! let _ = majorants.walk([-2.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.0, f32::INFINITY, |s| {
//!     pieces.push((s.t0, s.t1, s.max_density));
//!     ControlFlow::Continue(())
//! });
//! assert_eq!(pieces, [(1.0, 2.0, 0.0), (2.0, 3.0, 5.0)]);
//!
//! // Minorants on the same cells: the bright cell's support reaches zeros.
//! let minorants = DensityBoundGrid::minorant_from_dense(&density, [2, 2, 2]);
//! assert!(minorants.same_layout(&majorants));
//! assert_eq!(minorants.max_value(), 0.0);
//!
//! // A procedural cloud needs no file.
//! use niebla_volume::{procedural_density, ProceduralParams};
//! let cloud = procedural_density(&ProceduralParams { resolution: [32; 3], ..Default::default() })?;
//! assert!(cloud.max_value() > 0.9 && cloud.voxel(0, 0, 0) == 0.0);
//! # Ok::<(), niebla_volume::VolumeError>(())
//! ```
//!
//! # Decisions
//! - Sparse grids keep OpenVDB's 5-4-3 node tables (flat `u32` arrays under
//!   a hash map of root entries) rather than a single leaf hash map, so
//!   that root and internal-node tiles are kept exactly, constant regions
//!   cost one entry, and a voxel fetch is one root look-up plus two array
//!   reads. The root look-up scans a list while the root has at most 8
//!   entries (most grids), which costs less than hashing the key; a
//!   trilinear lookup whose corners straddle 8^3 blocks finds each block once.
//! - Sparse majorant grids use cubic cells of `8 * 2^k` voxels aligned to
//!   the VDB leaves (one cell per leaf when the cell budget allows), over
//!   the box where the field can differ from the background; a uniform
//!   grid keeps the DDA identical for dense and sparse media.
//! - The DDA reports zero-majorant cells instead of skipping them, so the
//!   caller always sees contiguous `t`; [`MajorantGrid::walk_merged`] merges
//!   runs of equal majorant, which makes empty space one callback.
//! - Minorant grids share the type [`DensityBoundGrid`] (same cells, same DDA) instead
//!   of a type of their own, so a tracker walks one grid and reads both
//!   bounds by cell index. A sparse cell's minorant includes the background
//!   unless leaves and tiles store every voxel of its support, found by
//!   counting stored voxels per support (leaves and tiles never overlap),
//!   which costs the same as the majorant build.
//! - Procedural noise is written here (Perlin's improved gradient noise,
//!   permutations shuffled by SplitMix64 from the seed) rather than taken
//!   from a crate, so grids stay bit-identical across dependency updates;
//!   bakes are single-threaded (no rayon in this crate) and skip voxels no
//!   noise value can fill (bake times: `benches/lookup.rs`, figures in
//!   ARCHITECTURE.md).
//! - `.vol` and `.npy` readers load the whole file into memory. [`VdbFile`]
//!   reads only the header and grid descriptors on [`VdbFile::open`] and
//!   streams each grid's bytes from the file through a 1 MiB window when it
//!   is decoded, so the peak memory of reading a grid is the grid itself
//!   plus the window, not the file plus the grid ([`VdbFile::from_bytes`]
//!   still parses a file held in memory).
//! - Coherent sparse lookups go through a [`SparseAccessor`], which caches
//!   the last 8^3 block, lower node and upper node visited (OpenVDB's
//!   `ValueAccessor`) in `Cell`s: one per ray or thread, never shared;
//!   values bit-identical to the uncached [`SparseGrid`] lookups.
//! - Built and read grids release their vectors' spare capacity, so
//!   [`SparseGrid::memory_bytes`] is within 1% of the leaves and tiles
//!   ([`SparseGrid::payload_bytes`]) for grids of more than a few leaves
//!   per internal node.

mod affine;
mod dda;
mod dense;
mod error;
mod io;
mod majorant;
mod minorant;
mod procedural;
mod rgb;
mod sparse;
mod sparse_accessor;
mod sparse_builder;
mod sparse_vec3;

pub use affine::Affine;
pub use dda::Segment;
pub use dense::{DenseF32Lookup, DenseGrid, GridStorage};
pub use error::VolumeError;
pub use io::npy::{parse_npy, read_npy};
pub use io::vdb::{VdbFile, VdbGridInfo, VdbValueKind};
pub use io::vol::{parse_vol, read_vol};
pub use majorant::{DensityBoundGrid, MajorantGrid};
pub use procedural::{procedural_density, ProceduralParams, ProceduralShape};
pub use rgb::{DenseRgbGrid, DenseVolume};
pub use sparse::{Leaf, SparseGrid, Tile, LEAF_DIM};
pub use sparse_accessor::SparseAccessor;
pub use sparse_builder::SparseGridBuilder;
pub use sparse_vec3::SparseVec3Grid;
