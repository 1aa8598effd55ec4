//! The crate's one error type: every failure names the file (or the arrays
//! being checked), where in it, and what was expected there.

use std::path::PathBuf;

/// Everything that can go wrong while reading, checking or writing a mesh.
///
/// File errors carry the file's path. PLY errors say the header line, the
/// body line (ASCII) or the element and its byte offset (binary); OBJ errors
/// say the line where it can be found. A corrupt or truncated file always
/// gives an error, never a panic, and no count read from a file is trusted
/// before it is checked against the bytes that follow.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The operating system could not open, read or write the file.
    #[error("{path}: cannot {action}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// `"read"` or `"write"`.
        action: &'static str,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file's extension is not one of the supported mesh formats.
    #[error("{path}: unknown mesh format {extension:?}; supported: .ply (ASCII or binary) and .obj")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// The extension as written (empty when the name has none).
        extension: String,
    },
    /// The PLY header is malformed or uses something this reader does not
    /// read.
    #[error("{path}: PLY header line {line}: {what}")]
    Header {
        /// The file.
        path: PathBuf,
        /// 1-based line number in the header.
        line: usize,
        /// What is wrong and what was expected.
        what: String,
    },
    /// A value in the body of a file could not be read: `location` is
    /// `line N (face 3)` in text files, `face 3 at byte 120` in binary ones.
    #[error("{path}: {location}: {what}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// Where: line and element (text) or element and byte (binary).
        location: String,
        /// What is wrong and what was expected.
        what: String,
    },
    /// The file holds less data than its header declares (checked before
    /// anything is allocated) or ends inside an element.
    #[error("{path}: file too short: {what}")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// What the header declares or what was being read.
        what: String,
    },
    /// The arrays of a mesh are inconsistent: an index out of range, a
    /// non-finite coordinate, an attribute whose count differs from the
    /// vertex count. `origin` is the file, or the caller's name for arrays
    /// given directly (see [`MeshError::with_origin`]).
    #[error("{origin}: {what}")]
    Invalid {
        /// The file, or `"mesh arrays"` for [`crate::MeshData::from_arrays`].
        origin: String,
        /// Which element is wrong, e.g. `indices[12][2]: vertex index 907
        /// out of range (the mesh has 800 vertices)`.
        what: String,
    },
    /// The memory estimate of [`crate::estimate_mesh_bytes`] exceeds the
    /// limit given in [`crate::MeshReadOptions::max_bytes`]; nothing was
    /// loaded.
    #[error("{path}: reading this mesh would take about {estimate} bytes, more than the limit of {limit} bytes")]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// The estimate, in bytes.
        estimate: u64,
        /// The limit, in bytes.
        limit: u64,
    },
    /// An OBJ object was requested by a name the file does not have.
    #[error("{path}: no object named {name:?} with faces; the file has {available:?}")]
    ObjectNotFound {
        /// The file.
        path: PathBuf,
        /// The requested name.
        name: String,
        /// The names of the objects and groups that have faces, in file order.
        available: Vec<String>,
    },
}

impl MeshError {
    /// Replaces the origin of an [`MeshError::Invalid`] error (e.g. with the
    /// scene file and JSON path of an inline mesh); other errors are returned
    /// unchanged.
    pub fn with_origin(self, origin: impl Into<String>) -> MeshError {
        match self {
            MeshError::Invalid { what, .. } => MeshError::Invalid { origin: origin.into(), what },
            other => other,
        }
    }
}
