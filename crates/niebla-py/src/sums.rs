//! Exact per-pixel sums between the renderer and numpy, for renders split
//! into sample ranges (`niebla.distributed`).
//!
//! numpy has no 128-bit integers, so the renderer's `i128` fixed-point sums
//! (`niebla::film::SampleSums`) travel as (H, W, 3, 4) int64 arrays of
//! 32-bit words: `sum = w0 + w1 2^32 + w2 2^64 + w3 2^96`, words 0..2
//! between 0 and 2^32 - 1 and word 3 signed. Adding two such arrays with
//! numpy's `+` adds the sums exactly without carrying (each word has 31
//! bits of headroom, room for 2^31 additions), in any order; the words are
//! turned back into `i128` here with carries.

use std::path::PathBuf;

use niebla::film::{read_checkpoint_full, write_checkpoint, CheckpointInfo, SampleSums};
use numpy::ndarray::Array4;
use numpy::{IntoPyArray, PyArray3, PyArray4, PyReadonlyArray4, PyUntypedArrayMethods};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;

/// The sums as a new (H, W, 3, 4) int64 array of words (module docs).
pub(crate) fn sums_to_words<'py>(py: Python<'py>, sums: &SampleSums) -> Bound<'py, PyArray4<i64>> {
    let mut data = Vec::with_capacity(sums.sums.len() * 12);
    for pixel in &sums.sums {
        for &s in pixel {
            let u = s as u128;
            data.extend([(u & 0xffff_ffff) as i64, (u >> 32 & 0xffff_ffff) as i64, (u >> 64 & 0xffff_ffff) as i64]);
            data.push((s >> 96) as i64);
        }
    }
    let shape = (sums.height as usize, sums.width as usize, 3, 4);
    Array4::from_shape_vec(shape, data).expect("sums hold width * height pixels").into_pyarray(py)
}

/// An (H, W, 3, 4) int64 array of words as sums (with carries).
fn words_to_sums(words: PyReadonlyArray4<'_, i64>) -> PyResult<SampleSums> {
    let shape = words.shape();
    let (h, w) = (shape[0], shape[1]);
    if shape[2] != 3 || shape[3] != 4 || h == 0 || w == 0 || h > u32::MAX as usize || w > u32::MAX as usize {
        return Err(PyValueError::new_err(format!("sums must have shape (H, W, 3, 4), got {shape:?}")));
    }
    let view = words.as_array();
    let mut sums = SampleSums::new(w as u32, h as u32);
    for y in 0..h {
        for x in 0..w {
            for c in 0..3 {
                let mut value = 0i128;
                for k in 0..4 {
                    value = value.wrapping_add((view[[y, x, c, k]] as i128).wrapping_shl(32 * k as u32));
                }
                sums.sums[y * w + x][c] = value;
            }
        }
    }
    Ok(sums)
}

/// The mean image (H, W, 3) float32 of sums `words` over `spp` samples per
/// pixel, computed as the renderer computes a pixel's mean, so it is bit for
/// bit the image of one render of those samples.
#[pyfunction]
pub(crate) fn sums_to_image<'py>(
    py: Python<'py>,
    words: PyReadonlyArray4<'_, i64>,
    spp: u64,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let sums = words_to_sums(words)?;
    Ok(crate::image::image_to_array(py, &sums.mean(spp)))
}

/// Writes sums `words` as a niebla checkpoint EXR (the mean in R, G, B, the
/// exact sums, `ranges` = [(first, end), ...] half-open sample ranges, the
/// seed, scene hash and integrator key in the header), atomically.
#[pyfunction]
pub(crate) fn write_sums_exr(
    words: PyReadonlyArray4<'_, i64>,
    path: PathBuf,
    ranges: Vec<(u64, u64)>,
    seed: u64,
    scene_hash: String,
    integrator: String,
) -> PyResult<()> {
    let sums = words_to_sums(words)?;
    let text = CheckpointInfo::ranges_text(&ranges);
    let Some(ranges) = CheckpointInfo::parse_ranges(&text) else {
        return Err(PyValueError::new_err(format!("ranges {text}: not increasing disjoint non-empty ranges")));
    };
    let spp = ranges.iter().map(|(a, b)| b - a).sum();
    let info = CheckpointInfo { spp, seed, scene_hash, integrator, ranges };
    write_checkpoint(&sums, &info, &path).map_err(|e| PyOSError::new_err(e.to_string()))
}

/// Reads a checkpoint EXR written by `write_sums_exr` or `niebla render`:
/// `(words, ranges, seed, scene_hash, integrator)`.
#[pyfunction]
#[allow(clippy::type_complexity)]
pub(crate) fn read_sums_exr(
    py: Python<'_>,
    path: PathBuf,
) -> PyResult<(Bound<'_, PyArray4<i64>>, Vec<(u64, u64)>, u64, String, String)> {
    let checkpoint = read_checkpoint_full(&path).map_err(|e| PyOSError::new_err(e.to_string()))?;
    let Some(sums) = checkpoint.sums else {
        return Err(PyValueError::new_err(format!(
            "{}: a checkpoint of format 1 (the mean alone) has no exact sums",
            path.display()
        )));
    };
    let info = checkpoint.info;
    Ok((sums_to_words(py, &sums), info.ranges, info.seed, info.scene_hash, info.integrator))
}
