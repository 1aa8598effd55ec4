//! NumPy `.npy` arrays as dense grids.
//!
//! Read: format versions 1-3, dtype `<f4` or `<f8` (`float64` is converted
//! to f32), C order (`fortran_order: False`). A 3D array of shape
//! `(nz, ny, nx)` is a scalar grid indexed `[z][y][x]` (x fastest); a 4D
//! array of shape `(nz, ny, nx, 3)` is an RGB grid. NumPy files carry no
//! bounds: the grid fills the unit box `[0, 1]^3` until
//! [`DenseVolume::with_bounds`] maps it elsewhere.

use std::path::Path;

use crate::io::bytes::{read_file, ByteReader};
use crate::{DenseGrid, DenseRgbGrid, DenseVolume, VolumeError};

const MAGIC: &[u8] = b"\x93NUMPY";

/// Reads a `.npy` file of shape `(nz, ny, nx)` or `(nz, ny, nx, 3)` into a
/// grid over the unit box (see the module docs).
///
/// ```no_run
/// let g = niebla_volume::read_npy("density.npy")?
///     .with_bounds([-1.0, 0.0, -1.0], [1.0, 2.0, 1.0])?;
/// # Ok::<(), niebla_volume::VolumeError>(())
/// ```
pub fn read_npy(path: impl AsRef<Path>) -> Result<DenseVolume, VolumeError> {
    let path = path.as_ref();
    let data = read_file(path)?;
    parse_npy(&data, path)
}

/// Parses `.npy` bytes already in memory; `path` is only used in error
/// messages.
///
/// ```
/// let err = niebla_volume::parse_npy(b"\x93NUMPY\x01", std::path::Path::new("x.npy")).unwrap_err();
/// assert!(err.to_string().starts_with("x.npy: file ends early"));
/// ```
pub fn parse_npy(data: &[u8], path: &Path) -> Result<DenseVolume, VolumeError> {
    if !data.starts_with(MAGIC) {
        return Err(VolumeError::WrongFormat {
            path: path.to_path_buf(),
            expected: "a NumPy .npy",
            found: format!("first bytes {:02x?}", &data[..data.len().min(6)]),
        });
    }
    let mut r = ByteReader::new(data, MAGIC.len(), path);
    let major = r.u8("format version")?;
    let _minor = r.u8("format version")?;
    let header_len = match major {
        1 => r.u16("header length")? as usize,
        2 | 3 => r.u32("header length")? as usize,
        v => return Err(r.unsupported(format!("npy format version {v}"))),
    };
    let header_pos = r.pos();
    let header = r.bytes(header_len, "array header")?;
    let header = String::from_utf8_lossy(header).into_owned();
    let corrupt = |what: String| VolumeError::Corrupt { path: path.to_path_buf(), offset: header_pos as u64, what };

    let descr = dict_value(&header, "descr").ok_or_else(|| corrupt(format!("no 'descr' in {header:?}")))?;
    let descr = descr.trim_matches(|c| c == '\'' || c == '"');
    let elem = match descr {
        "<f4" => 4,
        "<f8" => 8,
        other => {
            return Err(
                r.unsupported(format!("dtype {other:?} (expected little-endian float32 '<f4' or float64 '<f8')"))
            )
        }
    };
    let fortran =
        dict_value(&header, "fortran_order").ok_or_else(|| corrupt(format!("no 'fortran_order' in {header:?}")))?;
    if fortran.trim() != "False" {
        return Err(r.unsupported("Fortran-order arrays (save with C order)"));
    }
    let shape = parse_shape(&header).ok_or_else(|| corrupt(format!("unreadable 'shape' in {header:?}")))?;
    let rgb = match shape.len() {
        3 => false,
        4 if shape[3] == 3 => true,
        _ => return Err(r.unsupported(format!("array shape {shape:?} (expected (nz, ny, nx) or (nz, ny, nx, 3))"))),
    };
    if shape[..3].contains(&0) {
        return Err(corrupt(format!("empty array shape {shape:?}")));
    }
    let count = shape.iter().try_fold(1u64, |acc, &n| acc.checked_mul(n as u64));
    let bytes = count.and_then(|c| c.checked_mul(elem as u64));
    let Some(bytes) = bytes.filter(|&b| b <= r.remaining() as u64) else {
        return Err(r.truncated(&format!("array data of shape {shape:?}")));
    };
    let raw = r.bytes(bytes as usize, "array data")?;
    let values: Vec<f32> = if elem == 4 {
        raw.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
    } else {
        raw.chunks_exact(8)
            .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]) as f32)
            .collect()
    };
    let dims = [shape[2], shape[1], shape[0]];
    let invalid = |e: VolumeError| corrupt(e.to_string());
    Ok(if rgb {
        let rgb = values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        DenseVolume::Rgb(DenseRgbGrid::new(dims, rgb, [0.0; 3], [1.0; 3]).map_err(invalid)?)
    } else {
        DenseVolume::Scalar(DenseGrid::new(dims, values, [0.0; 3], [1.0; 3]).map_err(invalid)?)
    })
}

/// The text after `'key':` up to the next top-level comma or closing brace.
fn dict_value<'a>(header: &'a str, key: &str) -> Option<&'a str> {
    let start = header.find(&format!("'{key}'")).or_else(|| header.find(&format!("\"{key}\"")))?;
    let rest = &header[start + key.len() + 2..];
    let rest = rest.trim_start().strip_prefix(':')?.trim_start();
    let mut depth = 0;
    for (i, c) in rest.char_indices() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            ',' | '}' if depth == 0 => return Some(rest[..i].trim()),
            _ => {}
        }
    }
    None
}

/// The integers of the `shape` tuple.
fn parse_shape(header: &str) -> Option<Vec<usize>> {
    let v = dict_value(header, "shape")?;
    let inner = v.strip_prefix('(')?.strip_suffix(')')?;
    inner.split(',').map(str::trim).filter(|s| !s.is_empty()).map(|s| s.trim_end_matches('L').parse().ok()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_fields_parse() {
        let h = "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 3, 2), }";
        assert_eq!(dict_value(h, "descr"), Some("'<f4'"));
        assert_eq!(dict_value(h, "fortran_order"), Some("False"));
        assert_eq!(parse_shape(h), Some(vec![4, 3, 2]));
        assert_eq!(parse_shape("{'shape': (5,), }"), Some(vec![5]));
        assert_eq!(parse_shape("{'shape': (5, x), }"), None);
    }
}
