//! `niebla._niebla`: the native half of the `niebla` Python package (PyO3).
//!
//! The Python package (`python/niebla/__init__.py`) wraps this module: it
//! turns dicts into JSON text, picks a default progress bar and documents the
//! public API. Everything that touches the renderer is here:
//!
//! - [`scene::PyScene`]: a scene read from a file or from JSON text with the
//!   same parser as the `niebla` command (so errors carry the same JSON
//!   paths), whose media densities can be replaced by numpy arrays or VDB
//!   grids;
//! - [`render`]: a progressive render on a worker thread with the GIL
//!   released, progress callbacks and Ctrl-C handled on the calling thread;
//! - [`image`]: images as `(H, W, 3)` float32 arrays, EXR and PNG files;
//! - [`sums`]: exact per-pixel sums of sample ranges as int64 word arrays
//!   that add up with numpy's `+`, and their checkpoint EXRs.
//!
//! Errors from the renderer arrive as Python exceptions carrying the
//! renderer's message: [`SceneError`] (a `ValueError`, with `file`, `path`
//! and `message` attributes) and [`RenderError`] (a `RuntimeError`).

mod image;
mod layers;
mod render;
mod scene;
mod sums;
mod view;

use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

create_exception!(
    niebla,
    SceneError,
    PyValueError,
    "A mistake in a scene description. `str(e)` is the renderer's message \
     `\"{file}: {path}: {message}\"`; the attributes `file`, `path` (the JSON path \
     of the offending value, e.g. `media.fog.sigma_s[2]`, empty for whole-file \
     errors) and `message` hold its parts."
);
create_exception!(
    niebla,
    RenderError,
    PyRuntimeError,
    "A render that could not run (for example its thread pool could not start)."
);

/// Converts a renderer scene error into a Python [`SceneError`] with the
/// same message and its parts as attributes.
pub(crate) fn scene_error(py: Python<'_>, e: &niebla::scene::SceneError) -> PyErr {
    let err = SceneError::new_err(e.to_string());
    let value = err.value(py);
    for (name, text) in [("file", &e.file), ("path", &e.path), ("message", &e.message)] {
        if let Err(set) = value.setattr(name, text) {
            return set;
        }
    }
    err
}

/// The extension module.
#[pymodule]
fn _niebla(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("RenderError", py.get_type::<RenderError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    // The names the scene parser accepts (Python passes integrators through it).
    m.add("INTEGRATORS", niebla::integrator::registry::NAMES.to_vec())?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<view::PyViewer>()?;
    m.add_function(wrap_pyfunction!(image::write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(image::write_png, m)?)?;
    m.add_function(wrap_pyfunction!(image::read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(layers::read_exr_layers, m)?)?;
    m.add_function(wrap_pyfunction!(layers::denoise, m)?)?;
    m.add_function(wrap_pyfunction!(image::relative_mse, m)?)?;
    m.add_function(wrap_pyfunction!(sums::sums_to_image, m)?)?;
    m.add_function(wrap_pyfunction!(sums::write_sums_exr, m)?)?;
    m.add_function(wrap_pyfunction!(sums::read_sums_exr, m)?)?;
    Ok(())
}
