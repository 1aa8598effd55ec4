//! `Scene.view()`: the live viewer of `niebla view` (the `niebla-view`
//! crate) serving a scene from Python; the server runs on threads of its
//! own until `Viewer.stop()` or the viewer object is collected.

use std::path::Path;
use std::sync::Mutex;

use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;

/// A running viewer: open `url` in a browser (a notebook shows a link).
#[pyclass(name = "Viewer", module = "niebla")]
pub struct PyViewer {
    url: String,
    server: Mutex<Option<niebla_view::ViewServer>>,
}

/// Start a viewer of `value` (a scene as JSON, validated again here).
pub fn start(
    value: serde_json::Value,
    label: &str,
    base: &Path,
    host: &str,
    port: u16,
    threads: Option<usize>,
) -> PyResult<PyViewer> {
    let host = host.parse().map_err(|_| PyValueError::new_err(format!("host: {host:?} is not an IP address")))?;
    let inline = niebla_view::InlineScene { value, label: label.to_string(), base: base.to_path_buf() };
    let config =
        niebla_view::ViewConfig { host, port, threads, watch: false, inline: Some(inline), ..Default::default() };
    let server = niebla_view::ViewServer::start(&config).map_err(|e| match e {
        niebla_view::ViewError::Scene(m) => PyValueError::new_err(m),
        niebla_view::ViewError::Bind(m) => PyOSError::new_err(m),
    })?;
    Ok(PyViewer { url: server.url().to_string(), server: Mutex::new(Some(server)) })
}

impl PyViewer {
    /// The page's address.
    pub fn url_string(&self) -> String {
        self.url.clone()
    }
}

#[pymethods]
impl PyViewer {
    /// The page's address (with its access token).
    #[getter]
    fn url(&self) -> &str {
        &self.url
    }

    /// Whether the viewer still serves.
    #[getter]
    fn running(&self) -> bool {
        self.server.lock().map(|s| s.is_some()).unwrap_or(false)
    }

    /// Stop serving and rendering (idempotent).
    fn stop(&self, py: Python<'_>) {
        let server = self.server.lock().ok().and_then(|mut s| s.take());
        if let Some(server) = server {
            py.allow_threads(|| server.stop());
        }
    }

    fn __enter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    fn __exit__(&self, py: Python<'_>, _a: PyObject, _b: PyObject, _c: PyObject) {
        self.stop(py);
    }

    fn __repr__(&self) -> String {
        format!("<niebla.Viewer {}>", self.url)
    }

    /// A link for notebooks.
    fn _repr_html_(&self) -> String {
        format!("<a href=\"{0}\" target=\"_blank\">niebla view: {0}</a>", self.url)
    }
}

impl Drop for PyViewer {
    fn drop(&mut self) {
        if let Some(server) = self.server.get_mut().ok().and_then(|s| s.take()) {
            server.stop();
        }
    }
}
