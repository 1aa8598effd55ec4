//! The crate's one error type: every failure says which file (or which
//! constructor) and what was expected there.

use std::path::PathBuf;

/// Everything that can go wrong while building or reading voxel data.
///
/// File errors carry the file's path and, where it helps, the byte offset at
/// which reading stopped. A corrupt or truncated file always gives an error,
/// never a panic, and sizes read from a file are checked against the bytes
/// that remain before anything is allocated.
#[derive(Debug, thiserror::Error)]
pub enum VolumeError {
    /// The operating system could not open or read the file.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file does not start like a file of the expected format.
    #[error("{path}: not {expected} file ({found})")]
    WrongFormat {
        /// The file.
        path: PathBuf,
        /// The format that was expected, with its article ("an OpenVDB").
        expected: &'static str,
        /// What was found instead.
        found: String,
    },
    /// The file ends before the structure being read is complete.
    #[error("{path}: file ends early at byte {offset} while reading {what}")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// Byte offset at which the missing data should have started.
        offset: u64,
        /// What was being read.
        what: String,
    },
    /// The file has the right format but holds an impossible value.
    #[error("{path}: corrupt data at byte {offset}: {what}")]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// Byte offset of the offending data.
        offset: u64,
        /// What is wrong.
        what: String,
    },
    /// The file uses a feature of its format that this crate does not read.
    #[error("{path}: unsupported: {what}")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// The feature.
        what: String,
    },
    /// No grid of the requested name exists in a VDB file.
    #[error("{path}: no grid named {name:?}; the file has {available:?}")]
    GridNotFound {
        /// The file.
        path: PathBuf,
        /// The requested name.
        name: String,
        /// The names of the grids in the file (unique names, in file order).
        available: Vec<String>,
    },
    /// The grid exists but does not hold the values asked for (a scalar
    /// float grid was asked for and it holds vectors, or the reverse).
    #[error("{path}: grid {grid:?} has type {grid_type}, expected {expected}")]
    UnsupportedGridType {
        /// The file.
        path: PathBuf,
        /// The grid's name.
        grid: String,
        /// The grid's type as written in the file, e.g. `Tree_vec3s_5_4_3`.
        grid_type: String,
        /// What was asked for, e.g. "a scalar float, half or double grid".
        expected: &'static str,
    },
    /// A grid built in code has inconsistent arguments.
    #[error("invalid grid: {what}")]
    InvalidGrid {
        /// What is inconsistent.
        what: String,
    },
    /// Reading a file would take more memory than the caller allowed.
    #[error("{path}: {what} would need about {}, over the memory limit of {}", size_text(*bytes), size_text(*limit))]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// What would be allocated, e.g. `grid "density": 70000 leaves`.
        what: String,
        /// Estimated bytes.
        bytes: u64,
        /// The limit in bytes.
        limit: u64,
    },
    /// A parameter of a procedural generator is out of its range.
    #[error("invalid parameter {parameter} = {value}: expected {expected}")]
    InvalidParameter {
        /// The parameter's field name, e.g. `octaves`.
        parameter: &'static str,
        /// The value given.
        value: String,
        /// The accepted range, e.g. `an integer in 1..=12`.
        expected: &'static str,
    },
}

impl VolumeError {
    /// Shorthand for [`VolumeError::InvalidGrid`].
    pub(crate) fn invalid(what: impl Into<String>) -> Self {
        VolumeError::InvalidGrid { what: what.into() }
    }
}

/// A byte count in KiB (below 1 MiB) or MiB, for messages.
fn size_text(bytes: u64) -> String {
    if bytes < 1 << 20 {
        format!("{} KiB", bytes.div_ceil(1 << 10))
    } else {
        format!("{:.1} MiB", bytes as f64 / (1u64 << 20) as f64)
    }
}
