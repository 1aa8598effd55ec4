//! Checkpoints: the EXR a progressive render rewrites after every pass,
//! carrying in its header what is needed to continue it exactly.
//!
//! Header attributes (EXR text attributes of the layer):
//! - `nieblaCheckpoint`: the format version, `1`;
//! - `nieblaSpp`: samples per pixel accumulated in the pixels;
//! - `nieblaSeed`: the sampler seed (decimal, all 64 bits);
//! - `nieblaSceneHash`: [`scene_hash`] of the scene file's text;
//! - `nieblaIntegrator`: the integrator settings (`{:?}` of
//!   [`crate::integrator::IntegratorSettings`]).
//!
//! The pixels are the f32 mean of those samples, stored losslessly. The
//! progressive accumulator works on exactly this f32 mean (see
//! `progressive.rs`), so continuing from a checkpoint repeats the
//! arithmetic of a render that was never stopped, bit for bit.

use std::path::{Path, PathBuf};

use super::{write_exr_with_attributes, Image, OutputError};

const VERSION: &str = "1";

/// How a checkpoint image was rendered.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CheckpointInfo {
    /// Samples per pixel accumulated (the next pass starts at this sample
    /// index).
    pub spp: u64,
    /// Sampler seed.
    pub seed: u64,
    /// [`scene_hash`] of the scene text.
    pub scene_hash: String,
    /// The integrator settings, as `format!("{:?}", settings)`.
    pub integrator: String,
}

/// Why a checkpoint cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The file is missing, not an EXR, or has no RGB layer.
    #[error("{path}: cannot read the checkpoint: {message}")]
    Read {
        /// The file.
        path: PathBuf,
        /// The decoder's message.
        message: String,
    },
    /// The EXR lacks an attribute or has a malformed one.
    #[error("{path}: not a niebla checkpoint: {message}")]
    NotCheckpoint {
        /// The file.
        path: PathBuf,
        /// What is missing or wrong.
        message: String,
    },
}

/// A 64-bit FNV-1a hash of the scene file's bytes as 16 hex digits: the
/// checkpoint's proof that `--resume` renders the same scene. (Files the
/// scene refers to, such as grids, are not hashed.)
///
/// ```
/// assert_eq!(niebla::film::scene_hash(b""), "cbf29ce484222325");
/// assert_ne!(niebla::film::scene_hash(b"{}"), niebla::film::scene_hash(b"{ }"));
/// ```
pub fn scene_hash(text: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in text {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// Writes `image` (the f32 mean of `info.spp` samples per pixel) to the EXR
/// `path` with `info` in its header, through a temporary file and a rename.
pub fn write_checkpoint(image: &Image, info: &CheckpointInfo, path: &Path) -> Result<(), OutputError> {
    let attributes = [
        ("nieblaCheckpoint", VERSION.to_string()),
        ("nieblaSpp", info.spp.to_string()),
        ("nieblaSeed", info.seed.to_string()),
        ("nieblaSceneHash", info.scene_hash.clone()),
        ("nieblaIntegrator", info.integrator.clone()),
    ];
    write_exr_with_attributes(image, path, &attributes)
}

/// Reads a checkpoint written by [`write_checkpoint`]: its image and how it
/// was rendered.
///
/// ```
/// use niebla::film::{read_checkpoint, write_checkpoint, CheckpointInfo, Image};
/// let path = std::env::temp_dir().join(format!("niebla_doc_checkpoint_{}.exr", std::process::id()));
/// let mut image = Image::new(3, 2);
/// image.pixels[4] = niebla::color::Rgb::new(0.1, 1e-30, 7.0);
/// let info = CheckpointInfo { spp: 8, seed: u64::MAX, scene_hash: "00ff".into(), integrator: "VolPath".into() };
/// write_checkpoint(&image, &info, &path)?;
/// let (read, read_info) = read_checkpoint(&path)?;
/// assert_eq!((read, read_info), (image, info));
/// # std::fs::remove_file(&path).unwrap();
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_checkpoint(path: &Path) -> Result<(Image, CheckpointInfo), CheckpointError> {
    let read =
        super::read_exr(path).map_err(|e| CheckpointError::Read { path: path.to_path_buf(), message: e.reason() })?;
    let text = |name: &str| -> std::result::Result<String, CheckpointError> {
        read.text_attributes.get(name).cloned().ok_or_else(|| CheckpointError::NotCheckpoint {
            path: path.to_path_buf(),
            message: format!("the header has no text attribute {name} (was it written by `niebla render`?)"),
        })
    };
    let number = |name: &str| -> std::result::Result<u64, CheckpointError> {
        let t = text(name)?;
        t.parse().map_err(|_| CheckpointError::NotCheckpoint {
            path: path.to_path_buf(),
            message: format!("attribute {name} = {t:?} is not a whole number"),
        })
    };
    let version = text("nieblaCheckpoint")?;
    if version != VERSION {
        return Err(CheckpointError::NotCheckpoint {
            path: path.to_path_buf(),
            message: format!("checkpoint format version {version:?} (this niebla reads {VERSION})"),
        });
    }
    let info = CheckpointInfo {
        spp: number("nieblaSpp")?,
        seed: number("nieblaSeed")?,
        scene_hash: text("nieblaSceneHash")?,
        integrator: text("nieblaIntegrator")?,
    };
    Ok((read.image, info))
}
