//! `niebla._niebla.Scene`: a scene description kept as JSON, parsed and
//! built by the renderer's own scene code.
//!
//! Describe, then build (as the scene files are read). The description is held as a
//! `serde_json::Value` so that edits from Python (a density from a numpy
//! array or a VDB file) are edits of the same JSON a scene file holds, and
//! every edit is checked by re-parsing that JSON with
//! [`parse_scene_str`]: errors name the same JSON paths as errors in a file.
//! A density from an array is too large to travel through JSON text: the
//! JSON holds a `constant` placeholder with the array's `bounds`, and the
//! array replaces the placeholder in the parsed description (which is then
//! validated again) before the build.
//!
//! The scene is always built: construction and every edit build it (with
//! the GIL released), so a bad file or array fails where it is given, not at
//! the next render. Renders share the built scene through an `Arc`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use niebla::integrator::{registry, IntegratorSettings};
use niebla::progressive::Budget;
use niebla::scene::{
    build_scene, parse_scene_str, BoundsDesc, BuiltScene, DensitySourceDesc, InlineGridDesc, MediumDesc, SceneDesc,
    SceneError as RustSceneError,
};
use numpy::{PyArray3, PyArray4, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use serde_json::{json, Value};

use crate::image::image_to_array;
use crate::render::{render_blocking, RenderRequest};
use crate::scene_error;

/// A density given as an array: values at cell centers of `bounds`,
/// `[z][y][x]` with x fastest.
#[derive(Clone, Debug)]
struct ArrayDensity {
    data: Arc<Vec<f32>>,
    /// `[nx, ny, nz]`.
    dims: [u32; 3],
    bounds: BoundsDesc,
}

/// A scene ready to render. Build it with `Scene.from_file` or
/// `Scene.from_json` (the Python package adds `Scene.from_dict`).
#[pyclass(name = "Scene", module = "niebla._niebla")]
pub struct PyScene {
    /// The JSON description; array densities appear as `constant` placeholders.
    value: Value,
    /// Name of the description in messages: the file as given, or `<dict>`.
    source: String,
    /// Folder that relative file names in the description resolve against.
    base_dir: PathBuf,
    /// Densities set from arrays, by medium name.
    arrays: BTreeMap<String, ArrayDensity>,
    /// The parsed and validated description, arrays applied.
    desc: SceneDesc,
    /// The scene built from `desc`.
    built: Arc<BuiltScene>,
}

impl PyScene {
    /// Builds `desc` with the GIL released; its warnings (such as a medium
    /// nothing refers to) are raised as Python `UserWarning`s.
    fn build(py: Python<'_>, desc: &SceneDesc, source: &str, base_dir: &Path) -> PyResult<Arc<BuiltScene>> {
        let built = py.allow_threads(|| build_scene(desc, source, base_dir)).map_err(|e| scene_error(py, &e))?;
        for warning in &built.warnings {
            let text = std::ffi::CString::new(warning.replace('\0', " ")).expect("NUL bytes were replaced");
            PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyUserWarning>(), &text, 1)?;
        }
        Ok(Arc::new(built))
    }

    /// Parses `value` (JSON), puts the array densities in, validates.
    fn parse(&self, value: &Value, arrays: &BTreeMap<String, ArrayDensity>) -> Result<SceneDesc, RustSceneError> {
        let mut desc = parse_scene_str(&value.to_string(), &self.source)?;
        if !arrays.is_empty() {
            for (name, array) in arrays {
                if let Some(MediumDesc::Grid(grid)) = desc.media.get_mut(name) {
                    grid.density = DensitySourceDesc::Grid(InlineGridDesc {
                        data: array.data.to_vec(),
                        dims: array.dims,
                        bounds: array.bounds,
                    });
                }
            }
            desc.validate(&self.source)?;
        }
        Ok(desc)
    }

    /// Applies an edit of the description: re-parses, rebuilds and only then
    /// keeps the edit, so a failed edit leaves the scene as it was.
    fn apply(&mut self, py: Python<'_>, value: Value, arrays: BTreeMap<String, ArrayDensity>) -> PyResult<()> {
        let desc = self.parse(&value, &arrays).map_err(|e| scene_error(py, &e))?;
        let built = PyScene::build(py, &desc, &self.source, &self.base_dir)?;
        (self.value, self.arrays, self.desc, self.built) = (value, arrays, desc, built);
        Ok(())
    }

    /// The JSON object of medium `name`, or a SceneError naming the media.
    fn medium_value(&mut self, py: Python<'_>, name: &str) -> PyResult<Value> {
        match self.value.get("media").and_then(|m| m.get(name)) {
            Some(m) => Ok(m.clone()),
            None => {
                let known: Vec<&str> = self.desc.media.keys().map(String::as_str).collect();
                let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
                let e = RustSceneError::new(
                    &self.source,
                    format!("media.{name}"),
                    format!("unknown medium \"{name}\"; known media: {known}"),
                );
                Err(scene_error(py, &e))
            }
        }
    }

    /// `value` with medium `name`'s density replaced by `density` (a JSON
    /// density source); a homogeneous medium becomes a grid medium.
    fn with_density(&self, name: &str, mut medium: Value, density: Value) -> Value {
        if let Value::Object(object) = &mut medium {
            object.insert("type".into(), json!("grid"));
            object.insert("density".into(), density);
        }
        let mut value = self.value.clone();
        value["media"][name] = medium;
        value
    }

    /// The JSON description with array densities written out as inline grids.
    fn full_value(&self) -> Value {
        let mut value = self.value.clone();
        for (name, array) in &self.arrays {
            value["media"][name]["density"] = json!({
                "type": "grid",
                "dims": array.dims,
                "bounds": {"min": array.bounds.min, "max": array.bounds.max},
                "data": array.data.as_slice(),
            });
        }
        value
    }

    /// The integrator settings of JSON `integrator` (a scene file's
    /// `render.integrator` object), read by the integrator registry: errors
    /// name `render.integrator...` paths as they would in a file.
    fn integrator_from_json(&self, py: Python<'_>, integrator: &str) -> PyResult<IntegratorSettings> {
        let at = |path: &str, message: String| {
            let path =
                if path.is_empty() { "render.integrator".to_string() } else { format!("render.integrator.{path}") };
            scene_error(py, &RustSceneError::new(&self.source, path, message))
        };
        let value: Value = serde_json::from_str(integrator).map_err(|e| at("", format!("invalid JSON: {e}")))?;
        let Value::Object(object) = value else {
            return Err(at("", "expected an integrator object with a \"type\" field".to_string()));
        };
        registry::parse(&object).map_err(|e| at(&e.path, e.message))
    }
}

#[pymethods]
impl PyScene {
    /// Load a scene file: niebla JSON (version 1), or a Mitsuba 3 XML scene
    /// (extension `.xml`, converted as `niebla convert` does, with `defines`
    /// for its `<default>` parameters; what it accepts without effect is
    /// raised as `UserWarning`s). Relative paths in it resolve against the
    /// file's folder. Raises SceneError with the file, the JSON path (or XML
    /// line) and the message the `niebla` command gives. With `frame`, the
    /// scene of that frame of a sequence, as `niebla render --frames`
    /// renders it: keyframed camera and lights at that frame, frame patterns
    /// of file names (`smoke.####.vdb`, `{frame:04}`) replaced.
    #[staticmethod]
    #[pyo3(signature = (path, defines = BTreeMap::new(), frame = None))]
    fn from_file(
        py: Python<'_>,
        path: PathBuf,
        defines: BTreeMap<String, String>,
        frame: Option<u32>,
    ) -> PyResult<PyScene> {
        let source = path.display().to_string();
        let defines: Vec<(String, String)> = defines.into_iter().collect();
        let read = niebla::scene::read_scene_source_frame(&path, &defines, frame).map_err(|e| scene_error(py, &e))?;
        for note in &read.notes {
            let text = std::ffi::CString::new(note.replace('\0', " ")).expect("NUL bytes were replaced");
            PyErr::warn(py, &py.get_type::<pyo3::exceptions::PyUserWarning>(), &text, 1)?;
        }
        let value: Value = serde_json::from_str(&read.text)
            .map_err(|e| scene_error(py, &RustSceneError::new(&source, "", format!("invalid JSON: {e}"))))?;
        let base_dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        let built = PyScene::build(py, &read.desc, &source, &base_dir)?;
        Ok(PyScene { value, source, base_dir, arrays: BTreeMap::new(), desc: read.desc, built })
    }

    /// A scene from JSON text with the schema of a scene file. `source` names
    /// it in error messages; relative paths resolve against `base_dir`.
    #[staticmethod]
    #[pyo3(signature = (text, source = "<json>".to_string(), base_dir = PathBuf::from(".")))]
    fn from_json(py: Python<'_>, text: &str, source: String, base_dir: PathBuf) -> PyResult<PyScene> {
        let desc = parse_scene_str(text, &source).map_err(|e| scene_error(py, &e))?;
        let value: Value = serde_json::from_str(text)
            .map_err(|e| scene_error(py, &RustSceneError::new(&source, "", format!("invalid JSON: {e}"))))?;
        let built = PyScene::build(py, &desc, &source, &base_dir)?;
        Ok(PyScene { value, source, base_dir, arrays: BTreeMap::new(), desc, built })
    }

    /// The scene description as JSON text; densities set from arrays are
    /// written as inline `grid` sources, so `from_json(to_json())` gives the
    /// same scene.
    fn to_json(&self) -> String {
        self.full_value().to_string()
    }

    /// Serve a live, editable view of the scene to the browser (what
    /// `niebla view` does) and return the running `Viewer`; its `url`
    /// (printed) holds the access token. Saved files go to `base_dir`.
    #[pyo3(signature = (port = 0, host = "127.0.0.1", open = false, threads = None))]
    fn view(&self, port: u16, host: &str, open: bool, threads: Option<usize>) -> PyResult<crate::view::PyViewer> {
        if threads == Some(0) {
            return Err(PyValueError::new_err("threads: must be at least 1"));
        }
        let viewer = crate::view::start(self.full_value(), &self.source, &self.base_dir, host, port, threads)?;
        if open {
            Python::with_gil(|py| -> PyResult<()> {
                py.import("webbrowser")?.call_method1("open", (viewer.url_string(),))?;
                Ok(())
            })?;
        }
        Ok(viewer)
    }

    /// Name of the description in messages (the file, or `<dict>`).
    #[getter]
    fn source(&self) -> &str {
        &self.source
    }

    /// Folder that relative file names resolve against.
    #[getter]
    fn base_dir(&self) -> PathBuf {
        self.base_dir.clone()
    }

    /// Image width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.built.scene.camera.width
    }

    /// Image height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.built.scene.camera.height
    }

    /// Samples per pixel the scene asks for (`render.spp`).
    #[getter]
    fn spp(&self) -> u32 {
        self.built.settings.spp
    }

    /// Sampler seed the scene asks for (`render.seed`).
    #[getter]
    fn seed(&self) -> u64 {
        self.built.settings.seed
    }

    /// PNG exposure in stops the scene asks for (`render.exposure`).
    #[getter]
    fn exposure(&self) -> f32 {
        self.built.settings.exposure
    }

    /// Name of the scene's integrator (`render.integrator.type`).
    #[getter]
    fn integrator(&self) -> &'static str {
        self.built.settings.integrator.name()
    }

    /// Names of the media, sorted.
    #[getter]
    fn media(&self) -> Vec<String> {
        self.desc.media.keys().cloned().collect()
    }

    /// Replace medium `medium`'s density by `density`, an array of shape
    /// (nz, ny, nx) indexed [z][y][x] (float32 or float64, finite, >= 0),
    /// whose values sit at the cell centers of the box `bounds` = (min, max)
    /// in the medium's own space (the medium's `to_world` places it). A
    /// homogeneous medium becomes a grid medium with the same coefficients
    /// per unit density.
    #[pyo3(signature = (medium, density, bounds))]
    fn set_density(
        &mut self,
        py: Python<'_>,
        medium: &str,
        density: &Bound<'_, PyAny>,
        bounds: ([f32; 3], [f32; 3]),
    ) -> PyResult<()> {
        let (data, dims) = density_values(density)?;
        let object = self.medium_value(py, medium)?;
        let bounds = BoundsDesc { min: bounds.0, max: bounds.1 };
        let placeholder = json!({"type": "constant", "value": 1.0, "bounds": {"min": bounds.min, "max": bounds.max}});
        let value = self.with_density(medium, object, placeholder);
        let mut arrays = self.arrays.clone();
        arrays.insert(medium.to_string(), ArrayDensity { data: Arc::new(data), dims, bounds });
        self.apply(py, value, arrays)
    }

    /// Replace medium `medium`'s density by float grid `grid` of OpenVDB file
    /// `file` (a relative name resolves against `base_dir`). The grid keeps
    /// its own index-to-world map; the medium's `to_world` composes after it.
    #[pyo3(signature = (medium, file, grid = "density".to_string()))]
    fn set_density_vdb(&mut self, py: Python<'_>, medium: &str, file: PathBuf, grid: String) -> PyResult<()> {
        let object = self.medium_value(py, medium)?;
        let source = json!({"type": "vdb", "file": file.to_string_lossy(), "grid": grid});
        let value = self.with_density(medium, object, source);
        let mut arrays = self.arrays.clone();
        arrays.remove(medium);
        self.apply(py, value, arrays)
    }

    /// Render the scene progressively (passes of 1, 1, 2, 4, ... samples per
    /// pixel, as the `niebla` command does, so the same scene, seed and spp
    /// give a bit-identical image). Returns (image, spp, seconds) with the
    /// image an (H, W, 3) float32 array of linear radiance.
    ///
    /// `integrator` is JSON text of a `render.integrator` object (None: the
    /// scene's); `spp` or `time` (seconds) bound the render; `progress(done,
    /// total)` is called on this thread about every 50 ms (pixel samples for
    /// a sample budget, milliseconds for a time budget). The GIL is released
    /// while rendering; Ctrl-C or an exception in `progress` stops the render
    /// and is raised.
    #[pyo3(signature = (integrator = None, spp = None, seed = None, time = None, threads = None, progress = None))]
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    fn render<'py>(
        &self,
        py: Python<'py>,
        integrator: Option<&str>,
        spp: Option<u32>,
        seed: Option<u64>,
        time: Option<f64>,
        threads: Option<usize>,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<(Bound<'py, PyArray3<f32>>, u64, f64)> {
        let settings = match integrator {
            Some(text) => self.integrator_from_json(py, text)?,
            None => self.built.settings.integrator,
        };
        let budget = match (spp, time) {
            (Some(_), Some(_)) => return Err(PyValueError::new_err("give spp or time, not both")),
            (_, Some(t)) if !(t.is_finite() && t > 0.0 && t < 1e7) => {
                return Err(PyValueError::new_err(format!("time: expected a positive number of seconds, got {t}")))
            }
            (_, Some(t)) => Budget::Time(Duration::from_secs_f64(t)),
            (Some(0), None) => return Err(PyValueError::new_err("spp: must be at least 1")),
            (Some(n), None) => Budget::Samples(n),
            (None, None) => Budget::Samples(self.built.settings.spp),
        };
        if threads == Some(0) {
            return Err(PyValueError::new_err("threads: must be at least 1"));
        }
        let (seed, sampler) = (seed.unwrap_or(self.built.settings.seed), self.built.settings.sampler);
        let aovs = niebla::aov::AovSet::EMPTY;
        let request = RenderRequest { settings, seed, budget, threads, first_sample: 0, sampler, aovs };
        let done = render_blocking(py, Arc::clone(&self.built), request, progress.as_ref())?;
        Ok((image_to_array(py, &done.image), done.spp, done.seconds))
    }

    /// Render the scene with layers (`aovs`: comma-separated names or
    /// `all`, see `niebla render --aovs`; alpha is added when the scene's
    /// film is transparent); returns `(layers, spp, seconds)` with `layers`
    /// a dict: `beauty` (H, W, 3), `alpha` and `depth` (H, W), the others
    /// (H, W, 3), all float32, equal to the channels the command writes.
    /// The other arguments are those of `render`.
    #[pyo3(signature = (aovs, integrator = None, spp = None, seed = None, threads = None, progress = None))]
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    fn render_layers<'py>(
        &self,
        py: Python<'py>,
        aovs: &str,
        integrator: Option<&str>,
        spp: Option<u32>,
        seed: Option<u64>,
        threads: Option<usize>,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<(Bound<'py, pyo3::types::PyDict>, u64, f64)> {
        let settings = match integrator {
            Some(text) => self.integrator_from_json(py, text)?,
            None => self.built.settings.integrator,
        };
        let mut set = niebla::aov::AovSet::parse_list(aovs).map_err(|e| PyValueError::new_err(format!("aovs: {e}")))?;
        if self.built.scene.transparent_background {
            set = set.with(niebla::aov::Aov::Alpha);
        }
        if set.is_empty() {
            return Err(PyValueError::new_err("aovs: name at least one layer"));
        }
        if let Some(reason) = niebla::aov::unsupported_reason(set, &settings) {
            return Err(PyValueError::new_err(format!("aovs: {reason}")));
        }
        let spp = spp.unwrap_or(self.built.settings.spp);
        if spp == 0 {
            return Err(PyValueError::new_err("spp: must be at least 1"));
        }
        if threads == Some(0) {
            return Err(PyValueError::new_err("threads: must be at least 1"));
        }
        let (seed, sampler) = (seed.unwrap_or(self.built.settings.seed), self.built.settings.sampler);
        let budget = Budget::Samples(spp);
        let request = RenderRequest { settings, seed, budget, threads, first_sample: 0, sampler, aovs: set };
        let done = render_blocking(py, Arc::clone(&self.built), request, progress.as_ref())?;
        let layers = done.layers.as_ref().expect("a render with layers returns them");
        let dict = crate::layers::layers_dict(py, &done.image, layers)?;
        Ok((dict, done.spp, done.seconds))
    }

    /// The stable key of the integrator settings `integrator` (JSON text of
    /// a `render.integrator` object; None: the scene's) with the scene's
    /// sampler, as checkpoints record it.
    #[pyo3(signature = (integrator = None))]
    fn integrator_key(&self, py: Python<'_>, integrator: Option<&str>) -> PyResult<String> {
        let settings = match integrator {
            Some(text) => self.integrator_from_json(py, text)?,
            None => self.built.settings.integrator,
        };
        Ok(niebla::render::recorded_key(&settings, self.built.settings.sampler))
    }

    /// Render samples `first_sample .. first_sample + spp` of every pixel;
    /// returns `(words, spp, seconds, integrator_key)` with `words` the exact
    /// per-pixel sums as an (H, W, 3, 4) int64 array of 32-bit words
    /// (`crate::sums`): arrays of disjoint sample ranges add up with `+`
    /// to the sums of their union. The GIL is released while rendering, as
    /// in `render`.
    #[pyo3(signature = (integrator = None, first_sample = 0, spp = None, seed = None, threads = None, progress = None))]
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    fn render_sums<'py>(
        &self,
        py: Python<'py>,
        integrator: Option<&str>,
        first_sample: u64,
        spp: Option<u32>,
        seed: Option<u64>,
        threads: Option<usize>,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<(Bound<'py, PyArray4<i64>>, u64, f64, String)> {
        let settings = match integrator {
            Some(text) => self.integrator_from_json(py, text)?,
            None => self.built.settings.integrator,
        };
        let spp = spp.unwrap_or(self.built.settings.spp);
        if spp == 0 {
            return Err(PyValueError::new_err("spp: must be at least 1"));
        }
        if threads == Some(0) {
            return Err(PyValueError::new_err("threads: must be at least 1"));
        }
        let (seed, sampler) = (seed.unwrap_or(self.built.settings.seed), self.built.settings.sampler);
        let aovs = niebla::aov::AovSet::EMPTY;
        let request =
            RenderRequest { settings, seed, budget: Budget::Samples(spp), threads, first_sample, sampler, aovs };
        let done = render_blocking(py, Arc::clone(&self.built), request, progress.as_ref())?;
        // The key the command line records in its checkpoints (integrator and sampler).
        let key = niebla::render::recorded_key(&settings, sampler);
        Ok((crate::sums::sums_to_words(py, &done.sums), done.spp, done.seconds, key))
    }

    fn __repr__(&self) -> String {
        format!(
            "<niebla.Scene {} {}x{}, media [{}], integrator {}>",
            self.source,
            self.width(),
            self.height(),
            self.media().join(", "),
            self.integrator()
        )
    }
}

/// The values and `[nx, ny, nz]` of a (nz, ny, nx) float32 or float64 array.
fn density_values(density: &Bound<'_, PyAny>) -> PyResult<(Vec<f32>, [u32; 3])> {
    fn convert<T: numpy::Element + Copy + Into<f64>>(a: PyReadonlyArray3<'_, T>) -> PyResult<(Vec<f32>, [u32; 3])> {
        let shape = a.shape();
        if shape.iter().any(|&n| n == 0 || n > u32::MAX as usize) {
            return Err(PyValueError::new_err(format!(
                "density: every axis of the (nz, ny, nx) array must have at least one value, got shape {shape:?}"
            )));
        }
        let dims = [shape[2] as u32, shape[1] as u32, shape[0] as u32];
        // Iteration in logical order ([z][y][x], x fastest) whatever the strides.
        let data = a.as_array().iter().map(|&v| v.into() as f32).collect();
        Ok((data, dims))
    }
    if let Ok(a) = density.extract::<PyReadonlyArray3<'_, f32>>() {
        return convert(a);
    }
    if let Ok(a) = density.extract::<PyReadonlyArray3<'_, f64>>() {
        return convert(a);
    }
    Err(PyValueError::new_err("density: expected a numpy array of shape (nz, ny, nx) with dtype float32 or float64"))
}
