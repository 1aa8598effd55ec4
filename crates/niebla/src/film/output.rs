use std::io::Write;
use std::path::{Path, PathBuf};

use super::Image;
use crate::color::rgb_to_srgb8;

/// Failure to write an image file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The extension is neither `.exr` nor `.png`.
    #[error("{path}: unsupported image extension (expected .exr or .png)")]
    UnsupportedExtension {
        /// The requested file.
        path: PathBuf,
    },
    /// Encoding the image failed.
    #[error("{path}: could not encode image: {message}")]
    Encode {
        /// The requested file.
        path: PathBuf,
        /// Encoder message.
        message: String,
    },
    /// The file system refused.
    #[error("{path}: could not write: {source}")]
    Io {
        /// The requested file.
        path: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
}

/// Write `bytes` to `path` through a temporary file in the same folder that is
/// synced and renamed into place: readers see the old file or the new one,
/// never a truncated one.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let io = |source| OutputError::Io { path: path.to_path_buf(), source };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "image".into());
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// Encode `image` as an OpenEXR file (linear RGB, float32, unclamped, ZIP
/// compressed) and write it atomically.
pub fn write_exr(image: &Image, path: &Path) -> Result<(), OutputError> {
    write_exr_with_attributes(image, path, &[])
}

/// [`write_exr`] with extra text attributes `(name, value)` in the layer
/// header (read back with [`super::read_checkpoint`] or any EXR tool).
/// The pixels are stored exactly (float32, lossless ZIP).
pub fn write_exr_with_attributes(image: &Image, path: &Path, attributes: &[(&str, String)]) -> Result<(), OutputError> {
    use exr::prelude::*;
    let encode = |message: String| OutputError::Encode { path: path.to_path_buf(), message };
    let (w, h) = (image.width as usize, image.height as usize);
    let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
        let p = image.pixels[pos.y() * w + pos.x()];
        (p[0], p[1], p[2])
    });
    let mut layer_attributes = LayerAttributes::default();
    for (name, value) in attributes {
        let name = Text::new_or_none(name).ok_or_else(|| encode(format!("attribute name {name:?} is not ASCII")))?;
        let value =
            Text::new_or_none(value).ok_or_else(|| encode(format!("attribute value {value:?} is not ASCII")))?;
        layer_attributes.other.insert(name, AttributeValue::Text(value));
    }
    let layer = Layer::new((w, h), layer_attributes, Encoding::SMALL_LOSSLESS, channels);
    let mut bytes = Vec::new();
    exr::image::Image::from_layer(layer)
        .write()
        .non_parallel()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .map_err(|e| OutputError::Encode { path: path.to_path_buf(), message: e.to_string() })?;
    write_atomically(path, &bytes)
}

/// Encode `image` as an 8-bit sRGB PNG (times `2^exposure`, sRGB curve,
/// clamped) and write it atomically.
pub fn write_png(image: &Image, path: &Path, exposure: f32) -> Result<(), OutputError> {
    let mut data = Vec::with_capacity(image.pixels.len() * 3);
    for p in &image.pixels {
        data.extend_from_slice(&rgb_to_srgb8(*p, exposure));
    }
    write_srgb8_png(path, image.width, image.height, png::ColorType::Rgb, &data)
}

/// Encode 8-bit sRGB pixel bytes (`color`: RGB or RGBA, rows from the top)
/// as a PNG tagged sRGB and write it atomically to `path`.
pub(crate) fn write_srgb8_png(
    path: &Path,
    width: u32,
    height: u32,
    color: png::ColorType,
    data: &[u8],
) -> Result<(), OutputError> {
    let mut bytes = Vec::new();
    {
        let encode = |e: png::EncodingError| OutputError::Encode { path: path.to_path_buf(), message: e.to_string() };
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(color);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        let mut writer = encoder.write_header().map_err(encode)?;
        writer.write_image_data(data).map_err(encode)?;
        writer.finish().map_err(encode)?;
    }
    write_atomically(path, &bytes)
}

/// Write `image` to `path`, choosing the format by extension (`.exr` or `.png`).
pub fn write_image(image: &Image, path: &Path, exposure: f32) -> Result<(), OutputError> {
    match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
        Some("exr") => write_exr(image, path),
        Some("png") => write_png(image, path, exposure),
        _ => Err(OutputError::UnsupportedExtension { path: path.to_path_buf() }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_neither_temporary_nor_partial_file() {
        let dir = std::env::temp_dir().join(format!("niebla_output_test_{}", std::process::id()));
        std::fs::create_dir_all(dir.join("taken.exr")).unwrap();
        // Renaming a file over a folder fails after the temporary is written.
        let err = write_atomically(&dir.join("taken.exr"), b"bytes").unwrap_err();
        assert!(matches!(err, OutputError::Io { .. }), "{err}");
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["taken.exr"]);
        // A successful write replaces the file whole.
        let path = dir.join("image.png");
        write_atomically(&path, b"old").unwrap();
        write_atomically(&path, b"new contents").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new contents");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
