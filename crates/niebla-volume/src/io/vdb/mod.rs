//! OpenVDB `.vdb` files: the header, the grid descriptors, and reading
//! scalar grids into [`SparseGrid`]s and vector grids into
//! [`SparseVec3Grid`]s.
//!
//! File layout (format versions 222-224; `openvdb/io/Archive.cc`,
//! `File.cc`, `GridDescriptor.cc`): magic `0x56444220` as i64, format
//! version u32, library major and minor u32, a "has grid offsets" byte, a
//! 36-character UUID, the file metadata, the grid count, then per grid a
//! descriptor (unique name, type name with an optional `_HalfFloat` suffix,
//! instance parent name, and the i64 offsets of the grid, its buffers and
//! its end) followed by the grid itself: compression flags u32, grid
//! metadata, transform, tree topology, leaf buffers. All little-endian;
//! strings are a u32 length and bytes; metadata entries are name, type
//! name, u32 size and that many bytes.

mod transform;
mod tree;
mod values;

use std::path::{Path, PathBuf};

use crate::io::bytes::ByteReader;
use crate::{SparseGrid, SparseVec3Grid, VolumeError};
use values::{ScalarKind, ValueCodec};

const MAGIC: i64 = 0x5644_4220;
/// OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION: the oldest layout read here.
const MIN_VERSION: u32 = 222;
/// The newest layout known (OpenVDB 6 to 12 write 224).
const MAX_VERSION: u32 = 224;
/// Separator between a grid's name and the suffix that makes it unique.
const UNIQUE_SEPARATOR: char = '\u{1e}';
const HALF_SUFFIX: &str = "_HalfFloat";

/// What a VDB file says about one of its grids (read without loading it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VdbGridInfo {
    /// The grid's name, e.g. `density`.
    pub name: String,
    /// The name as stored: `name`, or `name` + `\u{1e}` + a suffix when
    /// several grids share a name.
    pub unique_name: String,
    /// The tree type without the half suffix, e.g. `Tree_float_5_4_3`.
    pub grid_type: String,
    /// Whether the values are stored as 16-bit half floats.
    pub half: bool,
    /// The grid whose tree this grid shares (an instance), if any.
    pub instance_parent: Option<String>,
    grid_pos: u64,
    end_pos: u64,
}

impl VdbGridInfo {
    /// The type as written in the file (with `_HalfFloat` for half grids).
    pub fn file_type_name(&self) -> String {
        if self.half {
            format!("{}{HALF_SUFFIX}", self.grid_type)
        } else {
            self.grid_type.clone()
        }
    }

    /// What the grid's voxels hold, read from its type name.
    pub fn value_kind(&self) -> VdbValueKind {
        match self.grid_type.as_str() {
            "Tree_float_5_4_3" => VdbValueKind::Float,
            "Tree_double_5_4_3" => VdbValueKind::Double,
            "Tree_vec3s_5_4_3" => VdbValueKind::Vec3Float,
            "Tree_vec3d_5_4_3" => VdbValueKind::Vec3Double,
            _ => VdbValueKind::Other,
        }
    }

    /// (component type, components) of the grids this crate decodes.
    fn decoded_kind(&self) -> Option<(ScalarKind, usize)> {
        match self.value_kind() {
            VdbValueKind::Float => Some((ScalarKind::Float, 1)),
            VdbValueKind::Double => Some((ScalarKind::Double, 1)),
            VdbValueKind::Vec3Float => Some((ScalarKind::Float, 3)),
            VdbValueKind::Vec3Double => Some((ScalarKind::Double, 3)),
            VdbValueKind::Other => None,
        }
    }
}

/// The value types of VDB grids, as far as this crate reads them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VdbValueKind {
    /// `FloatGrid` (`Tree_float_5_4_3`), full or half precision on disk.
    Float,
    /// `DoubleGrid` (`Tree_double_5_4_3`), read as `f32`.
    Double,
    /// `Vec3SGrid` (`Tree_vec3s_5_4_3`), full or half precision on disk.
    Vec3Float,
    /// `Vec3DGrid` (`Tree_vec3d_5_4_3`), read as `f32`.
    Vec3Double,
    /// Any other type (booleans, integers, masks, points): listed, not read.
    Other,
}

impl VdbValueKind {
    /// Whether the grid holds 3-vectors.
    pub fn is_vec3(self) -> bool {
        matches!(self, VdbValueKind::Vec3Float | VdbValueKind::Vec3Double)
    }

    /// Whether the grid holds scalars this crate reads.
    pub fn is_scalar(self) -> bool {
        matches!(self, VdbValueKind::Float | VdbValueKind::Double)
    }
}

const EXPECTED_SCALAR: &str = "a scalar float, half or double grid";
const EXPECTED_VEC3: &str = "a Vec3 grid (vec3s or vec3d, full or half precision)";

/// An OpenVDB file held in memory, with its grid list.
///
/// ```no_run
/// use niebla_volume::VdbFile;
/// let file = VdbFile::open("plume.vdb")?;
/// println!("{:?}", file.grid_names());
/// let density = file.read_float_grid("density")?;
/// let d = density.lookup_world([0.0, 1.0, 0.0]);
/// # Ok::<(), niebla_volume::VolumeError>(())
/// ```
#[derive(Clone, Debug)]
pub struct VdbFile {
    path: PathBuf,
    /// The file's bytes when parsed from memory; `None` when opened from
    /// disk, where each grid is streamed from the file when it is read (so
    /// that reading a grid does not hold the file next to the grid).
    data: Option<Vec<u8>>,
    version: u32,
    library_version: (u32, u32),
    grids: Vec<VdbGridInfo>,
}

impl VdbFile {
    /// Reads the header and grid descriptors of the file at `path`; grids
    /// are decoded on demand by [`VdbFile::read_float_grid`], streaming
    /// their bytes from the file (peak memory: the decoded grid plus a
    /// window of about 1 MiB), so the file must stay in place meanwhile.
    pub fn open(path: impl AsRef<Path>) -> Result<VdbFile, VolumeError> {
        let path = path.as_ref().to_path_buf();
        let (version, library_version, grids) = parse_header(ByteReader::open_stream(&path, 0, usize::MAX)?, &path)?;
        Ok(VdbFile { path, data: None, version, library_version, grids })
    }

    /// Parses a file already in memory; `path` is used in error messages.
    pub fn from_bytes(data: Vec<u8>, path: impl Into<PathBuf>) -> Result<VdbFile, VolumeError> {
        let path = path.into();
        let (version, library_version, grids) = parse_header(ByteReader::new(&data, 0, &path), &path)?;
        Ok(VdbFile { path, data: Some(data), version, library_version, grids })
    }

    /// A cursor at byte `pos` of the file, readable up to byte `end`.
    fn reader(&self, pos: u64, end: u64) -> Result<ByteReader<'_>, VolumeError> {
        // Descriptor offsets were checked against the file size.
        match &self.data {
            Some(data) => Ok(ByteReader::new(&data[..end as usize], pos as usize, &self.path)),
            None => ByteReader::open_stream(&self.path, pos as usize, end as usize),
        }
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The file format version (224 for OpenVDB 6 to 12).
    pub fn file_version(&self) -> u32 {
        self.version
    }

    /// The (major, minor) version of the library that wrote the file.
    pub fn library_version(&self) -> (u32, u32) {
        self.library_version
    }

    /// The grids in file order.
    pub fn grids(&self) -> &[VdbGridInfo] {
        &self.grids
    }

    /// The grids' unique names in file order.
    pub fn grid_names(&self) -> Vec<&str> {
        self.grids.iter().map(|g| g.unique_name.as_str()).collect()
    }

    /// The grid called `name`: an exact unique name first, else the first
    /// grid (in file order) whose name is `name`.
    pub fn grid(&self, name: &str) -> Result<&VdbGridInfo, VolumeError> {
        self.grids
            .iter()
            .find(|g| g.unique_name == name)
            .or_else(|| self.grids.iter().find(|g| g.name == name))
            .ok_or_else(|| VolumeError::GridNotFound {
                path: self.path.clone(),
                name: name.to_string(),
                available: self.grids.iter().map(|g| g.unique_name.clone()).collect(),
            })
    }

    /// Decodes the scalar grid `name` (float, double or half; see
    /// [`VdbFile::grid`] for how names match) into a [`SparseGrid`] in index
    /// space with the grid's index-to-world transform. Other value types
    /// (vectors, booleans, integers, points) are a
    /// [`VolumeError::UnsupportedGridType`].
    pub fn read_float_grid(&self, name: &str) -> Result<SparseGrid, VolumeError> {
        self.read_float_grid_limited(name, u64::MAX)
    }

    /// [`VdbFile::read_float_grid`] refusing, with a
    /// [`VolumeError::TooLarge`], a tree whose node tables and leaves would
    /// take more than `max_bytes` (checked before each node is allocated,
    /// so at most one node over the limit is ever allocated).
    ///
    /// ```no_run
    /// let file = niebla_volume::VdbFile::open("plume.vdb")?;
    /// let density = file.read_float_grid_limited("density", 1 << 30)?; // at most 1 GiB
    /// # Ok::<(), niebla_volume::VolumeError>(())
    /// ```
    pub fn read_float_grid_limited(&self, name: &str, max_bytes: u64) -> Result<SparseGrid, VolumeError> {
        let info = self.grid(name)?;
        let [grid] = self.read_components::<1>(info, EXPECTED_SCALAR, max_bytes)?;
        Ok(grid)
    }

    /// Decodes the vector grid `name` (`Vec3SGrid` or `Vec3DGrid`, full or
    /// half precision; see [`VdbFile::grid`] for how names match) into a
    /// [`SparseVec3Grid`]. A scalar grid, or any other type, is a
    /// [`VolumeError::UnsupportedGridType`]. Component values are as stored
    /// (no change of basis for covariant or contravariant vector types).
    pub fn read_vec3_grid(&self, name: &str) -> Result<SparseVec3Grid, VolumeError> {
        self.read_vec3_grid_limited(name, u64::MAX)
    }

    /// [`VdbFile::read_vec3_grid`] refusing, with a [`VolumeError::TooLarge`],
    /// a tree whose three component grids would take more than `max_bytes`.
    pub fn read_vec3_grid_limited(&self, name: &str, max_bytes: u64) -> Result<SparseVec3Grid, VolumeError> {
        let info = self.grid(name)?;
        let components = self.read_components::<3>(info, EXPECTED_VEC3, max_bytes)?;
        Ok(SparseVec3Grid { components })
    }

    /// Reads the string metadata `key` of grid `name` (e.g. `class`, which
    /// OpenVDB writes as `fog volume`, `level set`, `staggered` or
    /// `unknown`), `None` if the grid has no such entry or it is not a string.
    pub fn grid_string_metadata(&self, name: &str, key: &str) -> Result<Option<String>, VolumeError> {
        let info = self.grid(name)?;
        let mut r = self.reader(info.grid_pos, info.end_pos)?;
        r.u32("grid compression flags")?;
        let count = r.u32("grid metadata")?;
        let mut found = None;
        for _ in 0..count {
            let entry = r.string("grid metadata name")?;
            let type_name = r.string("grid metadata type")?;
            let size = r.u32("grid metadata size")? as usize;
            let bytes = r.bytes(size, "grid metadata value")?;
            if entry == key && type_name == "string" && found.is_none() {
                found = Some(String::from_utf8_lossy(bytes).into_owned());
            }
        }
        Ok(found)
    }

    /// Decodes grid `info` into `N` component grids (1 for scalar grids, 3
    /// for Vec3 grids), refusing other types with an error that says
    /// `expected`.
    fn read_components<const N: usize>(
        &self,
        info: &VdbGridInfo,
        expected: &'static str,
        max_bytes: u64,
    ) -> Result<[SparseGrid; N], VolumeError> {
        let kind = match info.decoded_kind() {
            Some((kind, arity)) if arity == N => kind,
            _ => {
                return Err(VolumeError::UnsupportedGridType {
                    path: self.path.clone(),
                    grid: info.unique_name.clone(),
                    grid_type: info.file_type_name(),
                    expected,
                })
            }
        };
        // An instance stores its own metadata and transform, and shares the
        // tree of its parent.
        let tree_source = match &info.instance_parent {
            None => info,
            Some(parent) => self
                .grids
                .iter()
                .find(|g| &g.unique_name == parent)
                .filter(|g| g.instance_parent.is_none() && g.grid_type == info.grid_type)
                .ok_or_else(|| VolumeError::Corrupt {
                    path: self.path.clone(),
                    offset: info.grid_pos,
                    what: format!("instance parent {parent:?} of grid {:?} is missing", info.unique_name),
                })?,
        };
        let (_, _, map_type, affine) = self.grid_reader(info)?;
        let mut grids: [SparseGrid; N] = std::array::from_fn(|_| {
            let mut grid = SparseGrid::empty(0.0, affine);
            grid.name = info.name.clone();
            grid.map_type = map_type.clone();
            grid
        });

        let (mut r, compression, _, _) = self.grid_reader(tree_source)?;
        let mut codec = ValueCodec { kind, arity: N, half: info.half, compression, background: [0.0; 3] };
        let limit = tree::MemoryLimit { max_bytes, grid: &info.unique_name };
        tree::read_tree(&mut r, &mut codec, &mut grids, &limit)?;
        Ok(grids)
    }

    /// A reader positioned at the grid's tree, with its compression and
    /// transform.
    fn grid_reader(&self, info: &VdbGridInfo) -> Result<(ByteReader<'_>, u32, String, crate::Affine), VolumeError> {
        let mut r = self.reader(info.grid_pos, info.end_pos)?;
        let pos = r.pos();
        let compression = r.u32("grid compression flags")?;
        if compression & !0x7 != 0 {
            return Err(r.corrupt_at(pos, format!("grid compression flags {compression:#x}")));
        }
        skip_metadata(&mut r, "grid metadata")?;
        let (map_type, affine) = transform::read_transform(&mut r)?;
        Ok((r, compression, map_type, affine))
    }
}

/// Skips a metadata map (count, then name, type name, size, bytes).
fn skip_metadata(r: &mut ByteReader, what: &str) -> Result<(), VolumeError> {
    let count = r.u32(what)?;
    for _ in 0..count {
        r.string(what)?;
        r.string(what)?;
        let size = r.u32(what)? as usize;
        r.skip(size, what)?;
    }
    Ok(())
}

type Header = (u32, (u32, u32), Vec<VdbGridInfo>);

/// Parses the header and grid descriptors with `r` at byte 0.
fn parse_header(mut r: ByteReader, path: &Path) -> Result<Header, VolumeError> {
    let n = r.remaining().min(8);
    let head = r.bytes(n, "magic number")?;
    let magic = match head.try_into() {
        Ok(b) => i64::from_le_bytes(b),
        Err(_) => -1,
    };
    if magic != MAGIC {
        return Err(VolumeError::WrongFormat {
            path: path.to_path_buf(),
            expected: "an OpenVDB",
            found: format!("first bytes {head:02x?}"),
        });
    }
    let version = r.u32("file format version")?;
    if !(MIN_VERSION..=MAX_VERSION).contains(&version) {
        return Err(
            r.unsupported(format!("file format version {version} (versions {MIN_VERSION} to {MAX_VERSION} are read)"))
        );
    }
    let library_version = (r.u32("library version")?, r.u32("library version")?);
    let has_offsets = r.u8("grid offsets flag")?;
    if has_offsets == 0 {
        return Err(r.unsupported("VDB streams without grid offsets"));
    }
    r.skip(36, "file UUID")?;
    skip_metadata(&mut r, "file metadata")?;
    let count = r.u32("grid count")?;
    let mut grids = Vec::new();
    for _ in 0..count {
        let desc_pos = r.pos();
        let unique_name = r.string("grid name")?;
        let mut grid_type = r.string("grid type")?;
        let instance_parent = r.string("grid instance parent")?;
        let grid_pos = r.i64("grid offset")?;
        let _block_pos = r.i64("grid block offset")?;
        let end_pos = r.i64("grid end offset")?;
        let here = r.pos() as i64;
        if !(here <= grid_pos && grid_pos < end_pos) {
            return Err(r.corrupt_at(
                desc_pos,
                format!("grid {unique_name:?} has offsets {grid_pos}..{end_pos} (descriptor ends at {here})"),
            ));
        }
        if end_pos as u64 > r.len() as u64 {
            return Err(VolumeError::Truncated {
                path: path.to_path_buf(),
                offset: r.len() as u64,
                what: format!("grid {unique_name:?}, which should end at byte {end_pos}"),
            });
        }
        let half = grid_type.ends_with(HALF_SUFFIX);
        if half {
            grid_type.truncate(grid_type.len() - HALF_SUFFIX.len());
        }
        let name = unique_name.split(UNIQUE_SEPARATOR).next().unwrap_or_default().to_string();
        grids.push(VdbGridInfo {
            name,
            unique_name,
            grid_type,
            half,
            instance_parent: (!instance_parent.is_empty()).then_some(instance_parent),
            grid_pos: grid_pos as u64,
            end_pos: end_pos as u64,
        });
        r.seek(end_pos as usize);
    }
    Ok((version, library_version, grids))
}
