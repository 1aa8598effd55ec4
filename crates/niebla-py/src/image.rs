//! Images between the renderer and numpy: `(H, W, 3)` float32 arrays of
//! linear Rec.709 radiance, row 0 at the top (the renderer's
//! [`Image`] layout, `pixels[y * width + x]`). EXR and PNG files are written
//! by the renderer's own writers, so a file written from Python is byte for
//! byte the file the `niebla` command writes for the same image.

use std::path::{Path, PathBuf};

use niebla::color::Rgb;
use niebla::film::Image;
use numpy::ndarray::Array3;
use numpy::{IntoPyArray, PyArray3, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;

/// The image as a new `(H, W, 3)` float32 array.
pub(crate) fn image_to_array<'py>(py: Python<'py>, image: &Image) -> Bound<'py, PyArray3<f32>> {
    let data: Vec<f32> = image.pixels.iter().flat_map(|p| p.0).collect();
    let shape = (image.height as usize, image.width as usize, 3);
    Array3::from_shape_vec(shape, data).expect("an image holds width * height pixels").into_pyarray(py)
}

/// An `(H, W, 3)` float32 or float64 array (any strides) as an image;
/// float64 values are rounded to float32.
pub(crate) fn array_to_image(array: &Bound<'_, PyAny>) -> PyResult<Image> {
    fn convert<T: numpy::Element + Copy + Into<f64>>(a: PyReadonlyArray3<'_, T>) -> PyResult<Image> {
        let shape = a.shape();
        let (h, w) = (shape[0], shape[1]);
        if shape[2] != 3 || h == 0 || w == 0 || h > u32::MAX as usize || w > u32::MAX as usize {
            return Err(PyValueError::new_err(format!(
                "an image must have shape (H, W, 3) with H, W >= 1, got {shape:?}"
            )));
        }
        let view = a.as_array();
        let mut pixels = Vec::with_capacity(h * w);
        for row in view.outer_iter() {
            for px in row.outer_iter() {
                let c = |i: usize| px[i].into() as f32;
                pixels.push(Rgb::new(c(0), c(1), c(2)));
            }
        }
        Ok(Image { width: w as u32, height: h as u32, pixels })
    }
    if let Ok(a) = array.extract::<PyReadonlyArray3<'_, f32>>() {
        return convert(a);
    }
    if let Ok(a) = array.extract::<PyReadonlyArray3<'_, f64>>() {
        return convert(a);
    }
    Err(PyValueError::new_err("an image must be a numpy array of shape (H, W, 3) with dtype float32 or float64"))
}

/// Write `image` ((H, W, 3) float32 or float64, linear radiance) to an
/// OpenEXR file: linear float32 RGB, unclamped, ZIP compressed. The file is
/// written to a temporary name and renamed into place.
#[pyfunction]
pub(crate) fn write_exr(py: Python<'_>, image: &Bound<'_, PyAny>, path: PathBuf) -> PyResult<()> {
    let image = array_to_image(image)?;
    py.allow_threads(|| niebla::film::write_exr(&image, &path)).map_err(|e| PyOSError::new_err(e.to_string()))
}

/// Write `image` to an 8-bit sRGB PNG: the radiance times `2**exposure`
/// (`exposure` in stops), the sRGB curve, clamped to [0, 1].
#[pyfunction]
#[pyo3(signature = (image, path, exposure = 0.0))]
pub(crate) fn write_png(py: Python<'_>, image: &Bound<'_, PyAny>, path: PathBuf, exposure: f32) -> PyResult<()> {
    if !exposure.is_finite() {
        return Err(PyValueError::new_err("exposure: must be a finite number of stops"));
    }
    let image = array_to_image(image)?;
    py.allow_threads(|| niebla::film::write_png(&image, &path, exposure)).map_err(|e| PyOSError::new_err(e.to_string()))
}

/// Read the RGB channels of an OpenEXR file's first layer into a new
/// (H, W, 3) float32 array (row 0 at the top).
#[pyfunction]
pub(crate) fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let image = py.allow_threads(|| read_exr_image(&path)).map_err(PyOSError::new_err)?;
    Ok(image_to_array(py, &image))
}

/// Reads an EXR file's first RGB(A) layer (through `niebla::film::read_exr`).
pub(crate) fn read_exr_image(path: &Path) -> Result<Image, String> {
    niebla::film::read_exr(path).map(|read| read.image).map_err(|e| e.to_string())
}

/// niebla's relative mean squared error of `image` against `reference`
/// (both (H, W, 3)): the mean over pixels and channels of
/// `(x - r)**2 / (r**2 + eps)` with `eps = (0.01 * mean(reference))**2`.
/// Dimensionless.
#[pyfunction]
pub(crate) fn relative_mse(image: &Bound<'_, PyAny>, reference: &Bound<'_, PyAny>) -> PyResult<f64> {
    let (a, b) = (array_to_image(image)?, array_to_image(reference)?);
    if (a.width, a.height) != (b.width, b.height) {
        return Err(PyValueError::new_err(format!(
            "image is {}x{} but the reference is {}x{} (width x height)",
            a.width, a.height, b.width, b.height
        )));
    }
    Ok(a.relative_mse(&b))
}
