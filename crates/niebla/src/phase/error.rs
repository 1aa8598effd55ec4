//! Errors of phase-function construction: each says which parameter is wrong
//! and what range it must lie in.

use std::path::PathBuf;

/// Why a phase function could not be built.
///
/// ```
/// use niebla::phase::{HenyeyGreenstein, PhaseError};
/// let e = HenyeyGreenstein::new(1.0).unwrap_err();
/// assert_eq!(e.to_string(), "phase parameter g = 1 is out of range: expected -1 < g < 1");
/// ```
#[derive(Debug, thiserror::Error)]
pub enum PhaseError {
    /// A parameter outside its documented range.
    #[error("phase parameter {name} = {value} is out of range: expected {expected}")]
    Parameter {
        /// Parameter name (`g`, `g1`, `w`, `k`, ...).
        name: &'static str,
        /// The value given.
        value: f64,
        /// The admissible range, in words.
        expected: &'static str,
    },
    /// A bad row of an in-memory table ([`super::Tabulated::from_table`]);
    /// rows count from 1.
    #[error("phase table, row {row}: {what}")]
    Table {
        /// 1-based row index.
        row: usize,
        /// What is wrong and what was expected.
        what: String,
    },
    /// A bad line of a CSV table.
    #[error("{source_name}, line {line}: {what}")]
    Csv {
        /// File path or name of the text.
        source_name: String,
        /// 1-based line number in the text.
        line: usize,
        /// What is wrong and what was expected.
        what: String,
    },
    /// The table file could not be read.
    #[error("cannot read phase table {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
}

impl PhaseError {
    /// A parameter out of range.
    pub(crate) fn parameter(name: &'static str, value: f32, expected: &'static str) -> PhaseError {
        PhaseError::Parameter { name, value: value as f64, expected }
    }
}

/// `Ok(g)` if `-1 < g < 1` (NaN rejected), else the error naming `name`.
pub(crate) fn check_open_unit(name: &'static str, value: f32) -> Result<f32, PhaseError> {
    if value > -1.0 && value < 1.0 {
        Ok(value)
    } else {
        Err(PhaseError::parameter(
            name,
            value,
            match name {
                "g" => "-1 < g < 1",
                "g1" => "-1 < g1 < 1",
                "g2" => "-1 < g2 < 1",
                "k" => "-1 < k < 1",
                _ => "a value in (-1, 1)",
            },
        ))
    }
}
