//! Frames as they travel to the page: the linear RGB radiance of every
//! pixel as IEEE half floats (binary16, little endian, R G B per pixel, row
//! 0 at the top), and the estimated relative error of a progressive image.

use niebla::film::Image;

/// One image the page shows, with what the status line reports.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Increases by one with every frame of a slot.
    pub id: u64,
    /// Scene version (edit count) the frame renders.
    pub version: u64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel accumulated.
    pub spp: u64,
    /// Seconds since the render of this version started (precomputation included).
    pub elapsed: f64,
    /// Pixel samples per second over the whole render so far.
    pub samples_per_second: f64,
    /// Estimated relative RMS error of the image ([`relative_error_estimate`]), when known.
    pub relative_error: Option<f64>,
    /// Rendered at reduced resolution while the page drags a control.
    pub interactive: bool,
    /// The integrator's `type`.
    pub integrator: String,
    /// The image (linear RGB radiance), kept at full precision for saving.
    pub image: std::sync::Arc<Image>,
    /// Where the time between the edit and this frame went on the server.
    pub timing: FrameTiming,
}

/// The server's share of a frame's latency, in seconds per stage, for the
/// `X-Niebla-Timing` header (the page adds its own stages; the benchmark
/// prints both). The stages before `pass` are those of the job's first
/// pass; later passes of the same job report only their own pass.
#[derive(Clone, Debug)]
pub struct FrameTiming {
    /// When the edit reached the server (`None`: no edit, e.g. the initial scene).
    pub edited_at: Option<std::time::Instant>,
    /// Validating the edit (the scene parser) before it became the job.
    pub validate: f64,
    /// From the new job to the render slot taking it up (the slot was busy or asleep).
    pub queue: f64,
    /// Reading the scene JSON into a description (and the preview size).
    pub parse: f64,
    /// Scene rebuild and integrator update or precomputation.
    pub prepare: f64,
    /// Rendering the pass.
    pub pass: f64,
    /// Taking the mean image and the error estimate.
    pub image: f64,
    /// When the frame was published (the wait for the page's request starts).
    pub published: std::time::Instant,
}

impl FrameTiming {
    /// The header value: `stage=milliseconds` pairs separated by `;`, with
    /// `wait` (published to taken by a request), `encode` (the half floats)
    /// and `server` (edit arrival to the encoded reply, when known) added.
    pub fn header(&self, wait: f64, encode: f64, server: Option<f64>) -> String {
        let mut stages = vec![
            ("validate", self.validate),
            ("queue", self.queue),
            ("parse", self.parse),
            ("prepare", self.prepare),
            ("pass", self.pass),
            ("image", self.image),
            ("wait", wait),
            ("encode", encode),
        ];
        if let Some(server) = server {
            stages.push(("server", server));
        }
        stages.iter().map(|(name, s)| format!("{name}={:.3}", s * 1e3)).collect::<Vec<_>>().join(";")
    }
}

/// `image` as half floats: 6 bytes per pixel (R, G, B as binary16, little
/// endian), rows from the top. Values beyond the half range become
/// infinities, as `half::f16::from_f32` rounds them.
pub fn encode_half(image: &Image) -> Vec<u8> {
    let mut out = Vec::with_capacity(image.pixels.len() * 6);
    for p in &image.pixels {
        for c in 0..3 {
            out.extend_from_slice(&half::f16::from_f32(p[c]).to_le_bytes());
        }
    }
    out
}

/// Decode [`encode_half`]'s bytes back to f32 values (R, G, B per pixel).
pub fn decode_half(bytes: &[u8]) -> Vec<f32> {
    bytes.chunks_exact(2).map(|b| half::f16::from_le_bytes([b[0], b[1]]).to_f32()).collect()
}

/// Estimated relative RMS error of the mean `current` of `2n` samples per
/// pixel given `previous`, the mean of its first `n`: the two halves `A`
/// (= `previous`) and `B` are independent estimates of variance
/// `2 sigma^2 / (2n)` each, `current = (A + B) / 2`, so `A - current = (A - B) / 2`
/// and `E[(A - current)^2] = sigma^2 / (2n)`, the variance of `current`.
/// Returns `sqrt(sum (A - current)^2 / sum current^2)` over pixels and
/// channels, or `None` when the image is black or not finite.
pub fn relative_error_estimate(previous: &Image, current: &Image) -> Option<f64> {
    if previous.pixels.len() != current.pixels.len() {
        return None;
    }
    let (mut diff, mut norm) = (0.0f64, 0.0f64);
    for (a, m) in previous.pixels.iter().zip(&current.pixels) {
        for c in 0..3 {
            let (a, m) = (a[c] as f64, m[c] as f64);
            diff += (a - m) * (a - m);
            norm += m * m;
        }
    }
    let ratio = (diff / norm).sqrt();
    (norm > 0.0 && ratio.is_finite()).then_some(ratio)
}

#[cfg(test)]
mod tests {
    use super::*;
    use niebla::color::Rgb;

    #[test]
    fn halves_round_trip_within_half_precision() {
        let mut image = Image::new(2, 1);
        image.pixels[0] = Rgb([0.1, 1.0, 65504.0]);
        image.pixels[1] = Rgb([3.0e-5, -2.5, 1.0e6]);
        let bytes = encode_half(&image);
        assert_eq!(bytes.len(), 12);
        let back = decode_half(&bytes);
        for (i, v) in back.iter().enumerate() {
            let want = image.pixels[i / 3][i % 3];
            if want.abs() > 65504.0 {
                assert!(v.is_infinite());
            } else {
                // binary16: 11 significant bits (relative rounding 2^-11); subnormals below 6.1e-5 step by 2^-24.
                assert!((v - want).abs() <= want.abs() * 2f32.powi(-11) + 2f32.powi(-25), "{v} vs {want}");
            }
        }
    }

    #[test]
    fn error_estimate_is_the_half_difference() {
        // Pixel values a (first half) and b (second half): the mean m = (a + b) / 2,
        // the estimate |a - m| / |m| = |a - b| / (a + b).
        let mut a = Image::new(1, 1);
        a.pixels[0] = Rgb([1.0, 1.0, 1.0]);
        let mut m = Image::new(1, 1);
        m.pixels[0] = Rgb([2.0, 2.0, 2.0]);
        assert!((relative_error_estimate(&a, &m).unwrap() - 0.5).abs() < 1e-12);
        assert_eq!(relative_error_estimate(&a, &Image::new(1, 1)), None);
    }
}
