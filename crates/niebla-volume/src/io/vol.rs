//! Mitsuba 3 grid volumes (`.vol`, binary "VOL" version 3).
//!
//! Layout (little-endian): bytes `V`, `O`, `L`, version byte 3; i32
//! encoding (1 = float32, the only one Mitsuba reads); i32 `nx`, `ny`,
//! `nz`; i32 channel count; six f32 for the bounding box (`xmin ymin zmin
//! xmax ymax zmax`); then `nx * ny * nz * channels` f32 values indexed
//! `((z * ny + y) * nx + x) * channels + c`.

use std::path::Path;

use crate::io::bytes::{read_file, ByteReader};
use crate::{DenseGrid, DenseRgbGrid, DenseVolume, VolumeError};

/// Reads a Mitsuba 3 `.vol` file with 1 (scalar) or 3 (RGB) channels; the
/// grid fills the bounding box stored in the file.
///
/// ```no_run
/// let v = niebla_volume::read_vol("smoke.vol")?;
/// let density = v.into_scalar().expect("one channel");
/// # Ok::<(), niebla_volume::VolumeError>(())
/// ```
pub fn read_vol(path: impl AsRef<Path>) -> Result<DenseVolume, VolumeError> {
    let path = path.as_ref();
    let data = read_file(path)?;
    parse_vol(&data, path)
}

/// Parses `.vol` bytes already in memory; `path` is only used in error
/// messages.
///
/// ```
/// let err = niebla_volume::parse_vol(b"VOL\x03", std::path::Path::new("x.vol")).unwrap_err();
/// assert!(err.to_string().starts_with("x.vol: file ends early"));
/// ```
pub fn parse_vol(data: &[u8], path: &Path) -> Result<DenseVolume, VolumeError> {
    if data.len() < 4 || &data[..3] != b"VOL" {
        return Err(VolumeError::WrongFormat {
            path: path.to_path_buf(),
            expected: "a Mitsuba VOL",
            found: format!("first bytes {:02x?}", &data[..data.len().min(4)]),
        });
    }
    let mut r = ByteReader::new(data, 3, path);
    let version = r.u8("version")?;
    if version != 3 {
        return Err(r.unsupported(format!("VOL version {version} (expected 3)")));
    }
    let encoding = r.i32("encoding")?;
    if encoding != 1 {
        return Err(r.unsupported(format!("VOL encoding {encoding} (only 1, float32, is read)")));
    }
    let dims_pos = r.pos();
    let dims = [r.i32("x resolution")?, r.i32("y resolution")?, r.i32("z resolution")?];
    let channels = r.i32("channel count")?;
    if dims.iter().any(|&n| n <= 0) {
        return Err(r.corrupt_at(dims_pos, format!("resolution {dims:?} is not positive")));
    }
    if channels != 1 && channels != 3 {
        return Err(r.unsupported(format!("{channels} channels (1 or 3 are read)")));
    }
    let mut bbox = [0f32; 6];
    for v in bbox.iter_mut() {
        *v = r.f32("bounding box")?;
    }
    let dims = dims.map(|n| n as usize);
    // Checked: three resolutions up to 2^31 overflow a u64 (found by fuzzing).
    let count = dims.iter().chain([&(channels as usize)]).try_fold(1u64, |acc, &n| acc.checked_mul(n as u64));
    let expected = count.and_then(|c| c.checked_mul(4)).filter(|&b| b <= r.remaining() as u64);
    let Some(expected) = expected else {
        let values = count.map_or_else(|| "more than 2^64".to_string(), |c| c.to_string());
        return Err(r.truncated(&format!("{values} float32 values ({}x{}x{}x{channels})", dims[0], dims[1], dims[2])));
    };
    let values: Vec<f32> = r
        .bytes(expected as usize, "values")?
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let (lo, hi) = ([bbox[0], bbox[1], bbox[2]], [bbox[3], bbox[4], bbox[5]]);
    let wrap = |e: VolumeError| VolumeError::Corrupt { path: path.to_path_buf(), offset: 24, what: e.to_string() };
    Ok(if channels == 1 {
        DenseVolume::Scalar(DenseGrid::new(dims, values, lo, hi).map_err(wrap)?)
    } else {
        let rgb = values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        DenseVolume::Rgb(DenseRgbGrid::new(dims, rgb, lo, hi).map_err(wrap)?)
    })
}
