//! Denoising with Intel Open Image Denoise (OIDN, Apache 2.0) on the CPU:
//! its "RT" filter (HDR color, optional albedo and normal features).
//!
//! The library is loaded at run time (`libloading`), so niebla builds and
//! runs without it; only a denoise request needs it. Where it is looked
//! for, in order: the file named by `NIEBLA_OIDN_LIBRARY`; the dynamic
//! loader's search path (`libOpenImageDenoise.so.2`). A fresh machine gets
//! it from PyPI: `pip install pyoidn` ships OIDN 2.5 with its CPU device
//! in `site-packages/pyoidn/oidn/lib/` (`scripts/test.sh` installs it into
//! `.venv-py` and sets the variable; the Python package finds it itself).

use std::ffi::{c_char, c_void, CStr, CString};
use std::path::{Path, PathBuf};

use crate::color::Rgb;
use crate::film::Image;

/// The environment variable naming the OIDN shared library.
pub const LIBRARY_VARIABLE: &str = "NIEBLA_OIDN_LIBRARY";

/// The library name the dynamic loader is asked for when the variable is unset.
pub const LIBRARY_NAME: &str = "libOpenImageDenoise.so.2";

/// Why an image could not be denoised.
#[derive(Debug, thiserror::Error)]
pub enum DenoiseError {
    /// The library is not installed (or not where it was said to be).
    #[error(
        "denoising needs Intel Open Image Denoise, which was not found ({tried}: {message}); install it with \
         `pip install pyoidn` and set {LIBRARY_VARIABLE} to site-packages/pyoidn/oidn/lib/libOpenImageDenoise.so.2, \
         or install libOpenImageDenoise.so.2 where the dynamic loader finds it"
    )]
    Missing {
        /// What was tried.
        tried: String,
        /// The loader's message.
        message: String,
    },
    /// The library reported an error.
    #[error("Open Image Denoise failed: {0}")]
    Failed(String),
    /// The feature images do not match the color image.
    #[error("{0}")]
    Size(String),
}

const DEVICE_TYPE_CPU: i32 = 1;
const FORMAT_FLOAT3: i32 = 3;

type Handle = *mut c_void;

/// `oidnSetSharedFilterImage(filter, name, data, format, width, height,
/// byteOffset, bytePixelStride, byteRowStride)`.
type SetSharedImage = unsafe extern "C" fn(Handle, *const c_char, *mut c_void, i32, usize, usize, usize, usize, usize);

/// The OIDN functions niebla calls (C API of OIDN 2).
struct Api {
    new_device: unsafe extern "C" fn(i32) -> Handle,
    commit_device: unsafe extern "C" fn(Handle),
    release_device: unsafe extern "C" fn(Handle),
    get_device_error: unsafe extern "C" fn(Handle, *mut *const c_char) -> i32,
    new_filter: unsafe extern "C" fn(Handle, *const c_char) -> Handle,
    set_shared_image: SetSharedImage,
    set_bool: unsafe extern "C" fn(Handle, *const c_char, bool),
    commit_filter: unsafe extern "C" fn(Handle),
    execute_filter: unsafe extern "C" fn(Handle),
    release_filter: unsafe extern "C" fn(Handle),
}

/// A loaded OIDN library.
pub struct Denoiser {
    api: Api,
    /// Where it was loaded from.
    pub source: String,
    // Keeps the functions above valid; dropped last.
    _library: libloading::Library,
}

impl std::fmt::Debug for Denoiser {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Denoiser").field("source", &self.source).finish_non_exhaustive()
    }
}

impl Denoiser {
    /// Loads OIDN from `NIEBLA_OIDN_LIBRARY`, else by name through the
    /// dynamic loader.
    pub fn load() -> Result<Denoiser, DenoiseError> {
        match std::env::var_os(LIBRARY_VARIABLE) {
            Some(path) if !path.is_empty() => Denoiser::load_from(Path::new(&path)),
            _ => Denoiser::load_from(Path::new(LIBRARY_NAME)),
        }
    }

    /// Loads OIDN from the shared library `path` (a bare name goes through
    /// the dynamic loader's search path).
    pub fn load_from(path: &Path) -> Result<Denoiser, DenoiseError> {
        let tried = path.display().to_string();
        let missing = |message: String| DenoiseError::Missing { tried: tried.clone(), message };
        // SAFETY: loading runs the library's initializers; OIDN's are plain
        // C++ static constructors.
        let library = unsafe { libloading::Library::new(path) }.map_err(|e| missing(e.to_string()))?;
        // The first of `names` the library exports, as the function type
        // the field it is assigned to expects.
        macro_rules! function {
            ($($name:literal),+) => {{
                let mut found = None;
                for name in [$($name),+] {
                    // SAFETY: the field types are the signatures of OIDN 2's C API (oidn.h).
                    if let Ok(symbol) = unsafe { library.get(name.as_bytes()) } {
                        found = Some(*symbol);
                        break;
                    }
                }
                let first = [$($name),+][0];
                found.ok_or_else(|| missing(format!("the library has no function {first}")))?
            }};
        }
        let api = Api {
            new_device: function!("oidnNewDevice"),
            commit_device: function!("oidnCommitDevice"),
            release_device: function!("oidnReleaseDevice"),
            get_device_error: function!("oidnGetDeviceError"),
            new_filter: function!("oidnNewFilter"),
            set_shared_image: function!("oidnSetSharedFilterImage"),
            set_bool: function!("oidnSetFilterBool", "oidnSetFilter1b"),
            commit_filter: function!("oidnCommitFilter"),
            execute_filter: function!("oidnExecuteFilter"),
            release_filter: function!("oidnReleaseFilter"),
        };
        Ok(Denoiser { api, source: tried, _library: library })
    }

    /// Denoises `color` (linear HDR radiance) with OIDN's "RT" filter on
    /// the CPU, guided by the first-hit `albedo` and `normal` when given
    /// (the `aov` layers; a normal needs the albedo too, as OIDN requires).
    pub fn denoise(
        &self,
        color: &Image,
        albedo: Option<&[Rgb]>,
        normal: Option<&[[f32; 3]]>,
    ) -> Result<Image, DenoiseError> {
        let n = color.pixels.len();
        for (name, len) in [("albedo", albedo.map(<[_]>::len)), ("normal", normal.map(<[_]>::len))] {
            if let Some(len) = len.filter(|&l| l != n) {
                return Err(DenoiseError::Size(format!("the {name} image has {len} pixels, the color image {n}")));
            }
        }
        if normal.is_some() && albedo.is_none() {
            return Err(DenoiseError::Size("a normal image needs an albedo image too (OIDN's RT filter)".into()));
        }
        if n == 0 {
            return Ok(color.clone());
        }
        let mut input: Vec<f32> = color.pixels.iter().flat_map(|p| p.0).collect();
        let mut albedo: Option<Vec<f32>> = albedo.map(|a| a.iter().flat_map(|p| p.0).collect());
        let mut normal: Option<Vec<f32>> = normal.map(|v| v.iter().flatten().copied().collect());
        let mut output = vec![0f32; 3 * n];
        let (w, h) = (color.width as usize, color.height as usize);
        let api = &self.api;
        let name = |s: &str| CString::new(s).expect("no NUL in parameter names");
        // SAFETY: every buffer outlives the filter's execution and holds
        // 3 * w * h floats; handles are released before returning.
        unsafe {
            let device = (api.new_device)(DEVICE_TYPE_CPU);
            let error = |device: Handle| -> Option<String> {
                let mut message: *const c_char = std::ptr::null();
                let code = (api.get_device_error)(device, &mut message);
                (code != 0).then(|| {
                    if message.is_null() {
                        format!("error code {code}")
                    } else {
                        CStr::from_ptr(message).to_string_lossy().into_owned()
                    }
                })
            };
            if device.is_null() {
                return Err(DenoiseError::Failed(error(device).unwrap_or_else(|| "no CPU device".into())));
            }
            (api.commit_device)(device);
            let filter = (api.new_filter)(device, name("RT").as_ptr());
            let set = |label: &str, data: *mut f32| {
                (api.set_shared_image)(filter, name(label).as_ptr(), data.cast(), FORMAT_FLOAT3, w, h, 0, 0, 0)
            };
            set("color", input.as_mut_ptr());
            if let Some(a) = albedo.as_mut() {
                set("albedo", a.as_mut_ptr());
            }
            if let Some(v) = normal.as_mut() {
                set("normal", v.as_mut_ptr());
            }
            set("output", output.as_mut_ptr());
            (api.set_bool)(filter, name("hdr").as_ptr(), true);
            (api.commit_filter)(filter);
            (api.execute_filter)(filter);
            let failure = error(device);
            (api.release_filter)(filter);
            (api.release_device)(device);
            if let Some(message) = failure {
                return Err(DenoiseError::Failed(message));
            }
        }
        let pixels = output.chunks_exact(3).map(|c| Rgb::new(c[0], c[1], c[2])).collect();
        Ok(Image { width: color.width, height: color.height, pixels })
    }
}

/// The path of a denoised output beside `raw`: `shot.exr` -> `shot.denoised.exr`.
///
/// ```
/// use std::path::Path;
/// assert_eq!(niebla::denoise::denoised_path(Path::new("out/shot.exr")), Path::new("out/shot.denoised.exr"));
/// ```
pub fn denoised_path(raw: &Path) -> PathBuf {
    let stem = raw.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = raw.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    raw.with_file_name(format!("{stem}.denoised{ext}"))
}
