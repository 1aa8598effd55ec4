//! Image textures: PNG (8 or 16 bits, gray, gray+alpha, RGB, RGBA, palette)
//! and JPEG decoded from sRGB to linear unless asked to keep the raw
//! values, OpenEXR read as linear; looked up with bilinear filtering and a
//! wrap mode. The image size is checked against a byte limit before any
//! pixel is decoded.

use std::path::{Path, PathBuf};

use crate::color::Rgb;
use crate::math::Vec2;

/// What happens to uv coordinates outside `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum WrapMode {
    /// The image tiles the plane (the default).
    #[default]
    Repeat,
    /// The image tiles the plane, every other copy mirrored.
    Mirror,
    /// The border pixels extend outward.
    Clamp,
}

/// How an image is looked up between texel centers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum FilterMode {
    /// Bilinear interpolation of the four nearest texel centers (the default).
    #[default]
    Bilinear,
    /// The texel containing the point.
    Nearest,
}

/// Why an image texture could not be loaded. Each message starts with the file.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// The file does not exist or cannot be read.
    #[error("{}: cannot read the texture: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The extension is none of `.png`, `.jpg`, `.jpeg`, `.exr`.
    #[error("{}: unknown texture format {extension:?}; expected .png, .jpg/.jpeg or .exr", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
        /// Its extension.
        extension: String,
    },
    /// The file could not be decoded.
    #[error("{}: not a readable {format} image: {message}", path.display())]
    Decode {
        /// The file.
        path: PathBuf,
        /// PNG, JPEG or EXR.
        format: &'static str,
        /// The decoder's message.
        message: String,
    },
    /// The decoded image would exceed the byte limit.
    #[error("{}: the {width} x {height} texture would need {} bytes, more than the {} left", path.display(), bytes, limit)]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Width in pixels.
        width: u64,
        /// Height in pixels.
        height: u64,
        /// Bytes the decoded texture needs.
        bytes: u64,
        /// Bytes allowed.
        limit: u64,
    },
}

/// A linear RGB image for texturing: row 0 is the top of the image.
#[derive(Clone, Debug)]
pub struct Bitmap {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, row by row from the top, linear Rec.709 RGB.
    pub pixels: Vec<Rgb>,
    /// Wrap mode of lookups.
    pub wrap: WrapMode,
}

/// Bytes per texel of a decoded texture.
pub const TEXEL_BYTES: u64 = 12;

/// The sRGB transfer curve's inverse (IEC 61966-2-1).
#[inline]
pub fn srgb_to_linear(x: f32) -> f32 {
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

impl Bitmap {
    /// Reads `path` (by extension: PNG, JPEG or EXR). 8- and 16-bit images
    /// are decoded from sRGB unless `raw` (then values / max); EXR is linear.
    /// Alpha is dropped. Refuses, before decoding pixels, an image whose
    /// decoded size (`TEXEL_BYTES` per pixel) exceeds `limit` bytes.
    pub fn read(path: &Path, raw: bool, wrap: WrapMode, limit: u64) -> Result<Bitmap, TextureError> {
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
        let io = |source| TextureError::Io { path: path.to_path_buf(), source };
        let check = |width: u64, height: u64| {
            let bytes = width.saturating_mul(height).saturating_mul(TEXEL_BYTES);
            if bytes > limit {
                Err(TextureError::TooLarge { path: path.to_path_buf(), width, height, bytes, limit })
            } else {
                Ok(())
            }
        };
        let decode =
            |format: &'static str, message: String| TextureError::Decode { path: path.to_path_buf(), format, message };
        let (width, height, pixels) = match ext.as_str() {
            "png" => {
                let file = std::fs::File::open(path).map_err(io)?;
                let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
                decoder.set_transformations(png::Transformations::EXPAND);
                let mut reader = decoder.read_info().map_err(|e| decode("PNG", e.to_string()))?;
                let (w, h) = (reader.info().width, reader.info().height);
                check(w as u64, h as u64)?;
                let mut buf = vec![0u8; reader.output_buffer_size()];
                let frame = reader.next_frame(&mut buf).map_err(|e| decode("PNG", e.to_string()))?;
                let channels = frame.color_type.samples();
                let sixteen = frame.bit_depth == png::BitDepth::Sixteen;
                let bytes = &buf[..frame.buffer_size()];
                let sample = |i: usize| -> f32 {
                    if sixteen {
                        u16::from_be_bytes([bytes[2 * i], bytes[2 * i + 1]]) as f32 / 65535.0
                    } else {
                        bytes[i] as f32 / 255.0
                    }
                };
                let pixels = (0..(w as usize * h as usize))
                    .map(|p| {
                        let base = p * channels;
                        let rgb = if channels >= 3 {
                            [sample(base), sample(base + 1), sample(base + 2)]
                        } else {
                            [sample(base); 3]
                        };
                        to_linear(rgb, raw)
                    })
                    .collect();
                (w, h, pixels)
            }
            "jpg" | "jpeg" => {
                let bytes = std::fs::read(path).map_err(io)?;
                let mut decoder = zune_jpeg::JpegDecoder::new(&bytes[..]);
                decoder.decode_headers().map_err(|e| decode("JPEG", format!("{e:?}")))?;
                let (w, h) = decoder.dimensions().ok_or_else(|| decode("JPEG", "no image size".into()))?;
                check(w as u64, h as u64)?;
                let data = decoder.decode().map_err(|e| decode("JPEG", format!("{e:?}")))?;
                let n = w * h;
                let channels = data.len().checked_div(n).unwrap_or(3);
                if channels == 0 || data.len() < n * channels {
                    return Err(decode("JPEG", "fewer samples than pixels".into()));
                }
                let pixels = (0..n)
                    .map(|p| {
                        let s = |k: usize| data[p * channels + k.min(channels - 1)] as f32 / 255.0;
                        to_linear([s(0), s(1), s(2)], raw)
                    })
                    .collect();
                (w as u32, h as u32, pixels)
            }
            "exr" => {
                if let Ok(meta) = exr::meta::MetaData::read_from_file(path, false) {
                    if let Some(header) = meta.headers.first() {
                        check(header.layer_size.width() as u64, header.layer_size.height() as u64)?;
                    }
                }
                let image = crate::film::read_exr(path).map_err(|e| decode("EXR", e.to_string()))?.image;
                (image.width, image.height, image.pixels)
            }
            _ => return Err(TextureError::UnknownFormat { path: path.to_path_buf(), extension: ext }),
        };
        if width == 0 || height == 0 {
            return Err(decode("image", "it has no pixels".into()));
        }
        Ok(Bitmap { width, height, pixels, wrap })
    }

    /// Bytes held by the pixels.
    pub fn memory_bytes(&self) -> usize {
        self.pixels.len() * TEXEL_BYTES as usize
    }

    /// Texel `(x, y)` (column, row from the top) after wrapping.
    #[inline]
    fn texel(&self, x: i64, y: i64) -> Rgb {
        let wrap = |i: i64, n: i64| -> i64 {
            match self.wrap {
                WrapMode::Repeat => i.rem_euclid(n),
                WrapMode::Clamp => i.clamp(0, n - 1),
                WrapMode::Mirror => {
                    let m = i.rem_euclid(2 * n);
                    if m < n {
                        m
                    } else {
                        2 * n - 1 - m
                    }
                }
            }
        };
        let (w, h) = (self.width as i64, self.height as i64);
        self.pixels[(wrap(y, h) * w + wrap(x, w)) as usize]
    }

    /// Color at `uv` with `filter`. Texel centers lie at
    /// `((i + 1/2) / width, 1 - (j + 1/2) / height)` for column `i`, row `j`
    /// from the top (`v` grows upward); a nearest lookup takes the texel
    /// whose cell `[i / width, (i + 1) / width) x (1 - (j + 1) / height, 1 - j / height]`
    /// holds `uv`.
    #[inline]
    pub fn eval(&self, uv: Vec2, filter: FilterMode) -> Rgb {
        if !uv.is_finite() {
            return Rgb::ZERO;
        }
        let x = uv.x * self.width as f32;
        let y = (1.0 - uv.y) * self.height as f32;
        match filter {
            FilterMode::Nearest => self.texel(x.floor() as i64, y.floor() as i64),
            FilterMode::Bilinear => {
                let (x, y) = (x - 0.5, y - 0.5);
                let (x0, y0) = (x.floor(), y.floor());
                let (fx, fy) = (x - x0, y - y0);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let top = self.texel(x0, y0) * (1.0 - fx) + self.texel(x0 + 1, y0) * fx;
                let bottom = self.texel(x0, y0 + 1) * (1.0 - fx) + self.texel(x0 + 1, y0 + 1) * fx;
                top * (1.0 - fy) + bottom * fy
            }
        }
    }
}

fn to_linear(rgb: [f32; 3], raw: bool) -> Rgb {
    if raw {
        Rgb::new(rgb[0], rgb[1], rgb[2])
    } else {
        Rgb::new(srgb_to_linear(rgb[0]), srgb_to_linear(rgb[1]), srgb_to_linear(rgb[2]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_by_two(wrap: WrapMode) -> Bitmap {
        // Row 0 (top): 0, 1; row 1 (bottom): 2, 3.
        Bitmap { width: 2, height: 2, pixels: (0..4).map(|i| Rgb::splat(i as f32)).collect(), wrap }
    }

    #[test]
    fn bilinear_lookup_hits_texel_centers_and_interpolates() {
        let b = two_by_two(WrapMode::Clamp);
        // v grows upward: the bottom-left texel center is (0.25, 0.25).
        assert_eq!(b.eval(Vec2::new(0.25, 0.25), FilterMode::Bilinear), Rgb::splat(2.0));
        assert_eq!(b.eval(Vec2::new(0.75, 0.75), FilterMode::Bilinear), Rgb::splat(1.0));
        assert_eq!(b.eval(Vec2::new(0.5, 0.5), FilterMode::Bilinear), Rgb::splat(1.5));
        // Clamped beyond the border.
        assert_eq!(b.eval(Vec2::new(-3.0, 0.25), FilterMode::Bilinear), Rgb::splat(2.0));
        // Repeat: u = 1.25 is u = 0.25.
        let r = two_by_two(WrapMode::Repeat);
        assert_eq!(r.eval(Vec2::new(1.25, 0.25), FilterMode::Bilinear), Rgb::splat(2.0));
        // Mirror: u = 1.25 is u = 0.75.
        let m = two_by_two(WrapMode::Mirror);
        assert_eq!(m.eval(Vec2::new(1.25, 0.25), FilterMode::Bilinear), Rgb::splat(3.0));
    }

    #[test]
    fn nearest_lookup_takes_the_texel_holding_the_point() {
        let b = two_by_two(WrapMode::Repeat);
        let near = |u: f32, v: f32| b.eval(Vec2::new(u, v), FilterMode::Nearest).r();
        // Texel centers give the values written (row 0 is the top, v = 1).
        assert_eq!([near(0.25, 0.75), near(0.75, 0.75), near(0.25, 0.25), near(0.75, 0.25)], [0.0, 1.0, 2.0, 3.0]);
        // Anywhere inside a texel's cell gives that texel, not a blend.
        assert_eq!(near(0.01, 0.99), 0.0);
        assert_eq!(near(0.49, 0.51), 0.0);
        assert_eq!(near(0.51, 0.49), 3.0);
        // Repeat wraps the cell index.
        assert_eq!(near(1.6, 0.75), 1.0);
    }

    /// Mitsuba 3.9.1's `bitmap` (scalar_rgb) evaluated on the same 2x2 image
    /// at uv points `(u, v_m)`, where Mitsuba's `v_m = 0` is the image's top:
    /// niebla looks up `(u, 1 - v_m)`.
    #[test]
    fn lookups_match_mitsuba_bitmap_values() {
        let points = [(0.25, 0.25), (0.75, 0.75), (0.25, 0.75), (0.5, 0.5), (1.25, 0.25), (-0.25, 0.25), (1.6, 0.25)];
        let more = [(0.1, 0.1), (2.3, 0.25)];
        #[rustfmt::skip]
        let table: [(WrapMode, FilterMode, [f32; 9]); 6] = [
            (WrapMode::Repeat, FilterMode::Bilinear, [0.0, 3.0, 2.0, 1.5, 0.0, 1.0, 0.7, 0.9, 0.1]),
            (WrapMode::Repeat, FilterMode::Nearest, [0.0, 3.0, 2.0, 3.0, 0.0, 1.0, 1.0, 0.0, 0.0]),
            (WrapMode::Mirror, FilterMode::Bilinear, [0.0, 3.0, 2.0, 1.5, 1.0, 0.0, 0.3, 0.0, 0.1]),
            (WrapMode::Mirror, FilterMode::Nearest, [0.0, 3.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0, 0.0]),
            (WrapMode::Clamp, FilterMode::Bilinear, [0.0, 3.0, 2.0, 1.5, 1.0, 0.0, 1.0, 0.0, 1.0]),
            (WrapMode::Clamp, FilterMode::Nearest, [0.0, 3.0, 2.0, 3.0, 1.0, 0.0, 1.0, 0.0, 1.0]),
        ];
        for (wrap, filter, want) in table {
            let b = two_by_two(wrap);
            for (&(u, v), w) in points.iter().chain(more.iter()).zip(want) {
                let got = b.eval(Vec2::new(u, 1.0 - v), filter).r();
                assert!((got - w).abs() < 1e-5, "{wrap:?} {filter:?} at ({u}, {v}): {got} vs Mitsuba's {w}");
            }
        }
    }

    #[test]
    fn srgb_decoding_matches_the_standard() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        // 0.5 in sRGB is 0.2140 linear (IEC 61966-2-1).
        assert!((srgb_to_linear(0.5) - 0.21404).abs() < 1e-4);
        // Inverse of the encoder used for PNG output.
        for i in 0..=20 {
            let x = i as f32 / 20.0;
            assert!((srgb_to_linear(crate::color::linear_to_srgb(x)) - x).abs() < 1e-5);
        }
    }
}
