//! Triangle meshes for niebla: [`MeshData`] (positions, optional normals and
//! uvs, triangles) with validation ([`MeshData::from_arrays`]), degenerate
//! triangle counts and a closedness check for meshes that bound a medium
//! ([`MeshData::closedness`]); readers for PLY (ASCII and binary, own
//! parser) and Wavefront OBJ (through `tobj`); a memory estimate taken
//! before reading ([`estimate_mesh_bytes`]); writers and generators for
//! tests and benchmarks. No rendering here.
//!
//! # Conventions
//! Counter-clockwise winding seen from outside gives the outward face
//! normal by the right-hand rule; texture coordinates have their origin at
//! the bottom-left (v up); see [`MeshData`].
//!
//! # Errors
//! Every failure is a [`MeshError`] naming the file (or the arrays), the
//! line or element, and what was expected. Corrupt, truncated or lying
//! files give errors, never panics, and no count read from a file is
//! trusted before it is checked against the bytes that follow.
//!
//! # Example
//! ```
//! let sphere = niebla_mesh::icosphere(2, 1.0);
//! assert_eq!(sphere.triangle_count(), 320);
//! assert!(sphere.closedness().is_closed());
//! let bytes = niebla_mesh::ply_binary_bytes(&sphere, niebla_mesh::ByteOrder::LittleEndian);
//! let back = niebla_mesh::parse_ply(&bytes, std::path::Path::new("sphere.ply")).unwrap();
//! assert_eq!(back, sphere);
//! ```

mod data;
mod error;
mod generate;
mod obj;
mod ply;
mod topology;
mod write;

use std::io::Read;
use std::path::Path;

pub use data::MeshData;
pub use error::MeshError;
pub use generate::{blob, icosphere, random_soup, uv_sphere, MAX_ICOSPHERE_SUBDIVISIONS, MAX_SOUP_TRIANGLES};
pub use obj::{parse_obj, read_obj};
pub use ply::{parse_ply, read_ply};
pub use topology::Closedness;
pub use write::{
    obj_bytes, ply_ascii_bytes, ply_binary_bytes, write_obj, write_ply_ascii, write_ply_binary, ByteOrder,
};

/// The mesh file formats [`read_mesh`] reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// PLY, ASCII or binary (`.ply`).
    Ply,
    /// Wavefront OBJ (`.obj`).
    Obj,
}

impl MeshFormat {
    /// The format named by the file's extension, case-insensitive (`.ply`,
    /// `.PLY`, `.obj`, ...); any other extension is an
    /// [`MeshError::UnknownFormat`] naming it.
    pub fn from_path(path: &Path) -> Result<MeshFormat, MeshError> {
        let ext = path.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
        match ext.to_ascii_lowercase().as_str() {
            "ply" => Ok(MeshFormat::Ply),
            "obj" => Ok(MeshFormat::Obj),
            _ => Err(MeshError::UnknownFormat { path: path.to_path_buf(), extension: ext }),
        }
    }
}

/// Options of [`read_mesh`].
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct MeshReadOptions {
    /// OBJ only: read only the objects and groups of this name (`o` or `g`
    /// lines) instead of merging all of them. Giving one for a PLY file is
    /// an error (a PLY file holds one mesh).
    pub object: Option<String>,
    /// Refuse, before reading, a file whose [`estimate_mesh_bytes`] exceeds
    /// this many bytes ([`MeshError::TooLarge`]).
    pub max_bytes: Option<u64>,
}

/// Reads a mesh file, choosing the reader by extension ([`MeshFormat::from_path`]):
/// [`read_ply`] or [`read_obj`].
pub fn read_mesh(path: impl AsRef<Path>, options: &MeshReadOptions) -> Result<MeshData, MeshError> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    if let Some(limit) = options.max_bytes {
        let estimate = estimate_mesh_bytes(path)?;
        if estimate > limit {
            return Err(MeshError::TooLarge { path: path.to_path_buf(), estimate, limit });
        }
    }
    match format {
        MeshFormat::Ply => {
            if let Some(name) = &options.object {
                return Err(MeshError::Invalid {
                    origin: path.display().to_string(),
                    what: format!("object {name:?} requested, but only OBJ files have named objects"),
                });
            }
            read_ply(path)
        }
        MeshFormat::Obj => read_obj(path, options.object.as_deref()),
    }
}

/// Bytes of memory per byte of file that [`estimate_mesh_bytes`] assumes
/// for OBJ: the file itself, tobj's intermediate arrays, face list and
/// vertex map, and the resulting [`MeshData`]. Measured peaks (maximum
/// resident set of a reader process less its 2 MB baseline) were 2.4x the
/// file size (random soup with normals and uvs, 104 MB), 2.7x (uv sphere
/// with normals and uvs, 68 MB), 3.3x (icosphere with normals, 26 MB) and
/// 5.2x (icosphere with positions only, 13 MB: short `f a b c` lines cost
/// the most per byte); 8 leaves a margin above the worst.
pub const OBJ_BYTES_PER_FILE_BYTE: u64 = 8;

/// How many bytes of the start of a PLY file [`estimate_mesh_bytes`] reads
/// to find the header.
pub const PLY_HEADER_READ_LIMIT: u64 = 1 << 20;

/// Estimates the memory, in bytes, that reading the mesh at `path` takes,
/// without reading more than the PLY header, so that a caller can refuse a
/// mesh over its memory limit first.
///
/// - **PLY**: `file_size + V * (12 + 12 [normals] + 8 [uvs]) + T * 12`,
///   where `V` is the declared vertex count and `T` the triangle count:
///   exact for binary files whose only list is the face's index list
///   (`T = I - 2 F` from the `I` indices the remaining bytes hold and the
///   `F` declared faces, at least `F`), otherwise `T = F` (exact for
///   triangle meshes, low for polygon meshes). The file is read whole
///   before parsing, hence `file_size`. The header must lie within the
///   first [`PLY_HEADER_READ_LIMIT`] bytes.
/// - **OBJ**: `OBJ_BYTES_PER_FILE_BYTE * file_size` (no header to read).
///
/// Errors: the file cannot be read, the extension is unknown, or the PLY
/// header is malformed.
pub fn estimate_mesh_bytes(path: impl AsRef<Path>) -> Result<u64, MeshError> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    let io = |source| MeshError::Io { path: path.to_path_buf(), action: "read", source };
    let file_size = std::fs::metadata(path).map_err(io)?.len();
    match format {
        MeshFormat::Obj => Ok(file_size.saturating_mul(OBJ_BYTES_PER_FILE_BYTE)),
        MeshFormat::Ply => {
            let mut head = Vec::new();
            std::fs::File::open(path).map_err(io)?.take(PLY_HEADER_READ_LIMIT).read_to_end(&mut head).map_err(io)?;
            ply::estimate_ply_bytes(&head, file_size, path)
        }
    }
}

/// Reads a whole file, with the path in the error.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, MeshError> {
    std::fs::read(path).map_err(|source| MeshError::Io { path: path.to_path_buf(), action: "read", source })
}
