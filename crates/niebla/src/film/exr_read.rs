//! The one EXR reader of niebla: the R, G, B channels of the first layer
//! that has them, as linear float radiance, with the layer's text
//! attributes. Checkpoints, environment maps, `niebla compare`'s reference
//! images and the Python package all read through [`read_exr`].

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::color::Rgb;

/// An EXR image as read: its RGB pixels (row 0 at the top) and the text
/// attributes of its layer (custom header attributes such as a checkpoint's).
#[derive(Clone, Debug, PartialEq)]
pub struct ExrImage {
    /// The pixels; the alpha channel, if any, is dropped.
    pub image: super::Image,
    /// The layer's text attributes by name.
    pub text_attributes: BTreeMap<String, String>,
}

/// Why an EXR file could not be read. Each message starts with the file.
#[derive(Debug, thiserror::Error)]
pub enum ExrReadError {
    /// The file does not exist.
    #[error("{}: file not found", path.display())]
    Missing {
        /// The requested file.
        path: PathBuf,
    },
    /// The file exists but could not be read.
    #[error("{}: could not read the file: {source}", path.display())]
    Io {
        /// The requested file.
        path: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The file is not a readable OpenEXR image.
    #[error("{}: not an OpenEXR file (or a corrupt one): {message}", path.display())]
    NotExr {
        /// The requested file.
        path: PathBuf,
        /// Decoder message.
        message: String,
    },
    /// No layer of the EXR has all of the channels R, G and B.
    #[error("{}: no layer has R, G and B channels (found: {found})", path.display())]
    NoRgbChannels {
        /// The requested file.
        path: PathBuf,
        /// The channel names present, comma separated.
        found: String,
    },
    /// The first layer has no pixels.
    #[error("{}: the image has zero size ({width} x {height})", path.display())]
    ZeroSize {
        /// The requested file.
        path: PathBuf,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
    },
}

impl ExrReadError {
    /// What is wrong, without the file name (for messages that name the
    /// file themselves).
    pub fn reason(&self) -> String {
        let full = self.to_string();
        let path = match self {
            ExrReadError::Missing { path }
            | ExrReadError::Io { path, .. }
            | ExrReadError::NotExr { path, .. }
            | ExrReadError::NoRgbChannels { path, .. }
            | ExrReadError::ZeroSize { path, .. } => path.display().to_string(),
        };
        full.strip_prefix(&format!("{path}: ")).map(str::to_string).unwrap_or(full)
    }
}

/// Reads the R, G, B channels of the first layer of the EXR `path` that has
/// them (any pixel type, converted to f32) and that layer's text attributes.
/// The headers are checked before any pixel buffer is allocated.
///
/// ```
/// use niebla::film::{read_exr, write_exr, ExrReadError, Image};
/// let path = std::env::temp_dir().join(format!("niebla-read-exr-doc-{}.exr", std::process::id()));
/// let mut image = Image::new(2, 1);
/// image.pixels[1] = niebla::color::Rgb::new(0.25, 2.0, 1e-3);
/// write_exr(&image, &path)?;
/// assert_eq!(read_exr(&path)?.image, image);
/// # std::fs::remove_file(&path).unwrap();
/// assert!(matches!(read_exr("no/such.exr".as_ref()), Err(ExrReadError::Missing { .. })));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_exr(path: &Path) -> Result<ExrImage, ExrReadError> {
    use exr::prelude::*;

    let bytes = std::fs::read(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => ExrReadError::Missing { path: path.to_path_buf() },
        _ => ExrReadError::Io { path: path.to_path_buf(), source },
    })?;
    let not_exr = |e: exr::error::Error| ExrReadError::NotExr { path: path.to_path_buf(), message: e.to_string() };
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(&bytes), false).map_err(not_exr)?;
    let has_rgb = |h: &exr::meta::header::Header| {
        ["R", "G", "B"].iter().all(|name| h.channels.list.iter().any(|c| c.name.eq(name)))
    };
    let Some(header) = meta.headers.iter().find(|h| has_rgb(h)) else {
        let found: Vec<String> =
            meta.headers.iter().flat_map(|h| h.channels.list.iter().map(|c| c.name.to_string())).collect();
        return Err(ExrReadError::NoRgbChannels { path: path.to_path_buf(), found: found.join(", ") });
    };
    let (width, height) = (header.layer_size.width(), header.layer_size.height());
    if width == 0 || height == 0 {
        return Err(ExrReadError::ZeroSize { path: path.to_path_buf(), width, height });
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution, _channels: &RgbaChannels| {
                (resolution.width(), vec![Rgb::ZERO; resolution.width() * resolution.height()])
            },
            |(width, pixels): &mut (usize, Vec<Rgb>), position, (r, g, b, _a): (f32, f32, f32, f32)| {
                pixels[position.y() * *width + position.x()] = Rgb::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(&bytes))
        .map_err(not_exr)?;
    let size = image.layer_data.size;
    let text_attributes = image
        .layer_data
        .attributes
        .other
        .iter()
        .filter_map(|(name, value)| match value {
            AttributeValue::Text(t) => Some((name.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    let (_, pixels) = image.layer_data.channel_data.pixels;
    let image = super::Image { width: size.width() as u32, height: size.height() as u32, pixels };
    Ok(ExrImage { image, text_attributes })
}
