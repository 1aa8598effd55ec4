//! Render layers (`niebla::aov`) between the renderer and numpy: a dict
//! `{"beauty": (H, W, 3), "alpha": (H, W), "depth": (H, W), NAME: (H, W, 3)}`
//! of float32 arrays, from a render or from an EXR written with layers.

use std::path::PathBuf;

use niebla::aov::AovImage;
use niebla::film::Image;
use numpy::ndarray::{Array2, Array3};
use numpy::IntoPyArray;
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::image::image_to_array;

/// The beauty and layers as a dict of float32 arrays (row 0 at the top).
pub(crate) fn layers_dict<'py>(py: Python<'py>, beauty: &Image, layers: &AovImage) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item("beauty", image_to_array(py, beauty))?;
    let (h, w) = (layers.height as usize, layers.width as usize);
    for layer in &layers.layers {
        let data = layer.data.clone();
        if layer.components == 1 {
            let a = Array2::from_shape_vec((h, w), data).expect("one value per pixel");
            dict.set_item(layer.aov.name(), a.into_pyarray(py))?;
        } else {
            let a = Array3::from_shape_vec((h, w, layer.components), data).expect("components per pixel");
            dict.set_item(layer.aov.name(), a.into_pyarray(py))?;
        }
    }
    Ok(dict)
}

/// Read the beauty and layers of an EXR written by `niebla render --aovs`
/// into the dict `Scene.render_layers` returns.
#[pyfunction]
pub(crate) fn read_exr_layers(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyDict>> {
    let (beauty, layers) = py.allow_threads(|| niebla::aov::read_aov_exr(&path)).map_err(PyOSError::new_err)?;
    layers_dict(py, &beauty, &layers)
}

/// Denoise `image` ((H, W, 3) float linear radiance) with Intel Open Image
/// Denoise on the CPU, guided by `albedo` and `normal` ((H, W, 3) each,
/// e.g. `render_layers`' layers), loading the OIDN library from `library`
/// (None: `NIEBLA_OIDN_LIBRARY`, else the dynamic loader's search path).
#[pyfunction]
#[pyo3(signature = (image, albedo = None, normal = None, library = None))]
pub(crate) fn denoise<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    albedo: Option<&Bound<'py, PyAny>>,
    normal: Option<&Bound<'py, PyAny>>,
    library: Option<PathBuf>,
) -> PyResult<Bound<'py, numpy::PyArray3<f32>>> {
    use niebla::denoise::Denoiser;
    use pyo3::exceptions::{PyRuntimeError, PyValueError};
    let color = crate::image::array_to_image(image)?;
    let albedo = albedo.map(crate::image::array_to_image).transpose()?;
    let normal = normal.map(crate::image::array_to_image).transpose()?;
    for (name, feature) in [("albedo", &albedo), ("normal", &normal)] {
        if let Some(f) = feature.as_ref().filter(|f| (f.width, f.height) != (color.width, color.height)) {
            return Err(PyValueError::new_err(format!(
                "{name}: shape ({}, {}, 3) differs from the image's ({}, {}, 3)",
                f.height, f.width, color.height, color.width
            )));
        }
    }
    let denoiser = match &library {
        Some(path) => Denoiser::load_from(path),
        None => Denoiser::load(),
    }
    .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    let normal: Option<Vec<[f32; 3]>> = normal.map(|n| n.pixels.iter().map(|p| p.0).collect());
    let result =
        py.allow_threads(|| denoiser.denoise(&color, albedo.as_ref().map(|a| a.pixels.as_slice()), normal.as_deref()));
    let denoised = result.map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(image_to_array(py, &denoised))
}
