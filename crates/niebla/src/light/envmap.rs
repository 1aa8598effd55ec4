//! Image-based environment light: a latitude-longitude (equirectangular) map
//! of radiance at infinity, importance sampled in proportion to each pixel's
//! luminance times its solid angle.
//!
//! # Mapping (Mitsuba 3 `envmap` axes)
//! In the map's local frame a direction `d` has texture coordinates
//! `u = atan2(d.x, -d.z) / (2 pi)` (wrapped to [0, 1)) and
//! `v = acos(d.y) / pi`, and conversely, with `theta = pi v`, `phi = 2 pi u`,
//! `d = (sin(phi) sin(theta), cos(theta), -cos(phi) sin(theta))`
//! (Mitsuba 3, `src/emitters/envmap.cpp`, `uv_to_direction`). Hence:
//! - `v = 0` (row 0, the top of the image) is +y (up), `v = 1` (bottom) is -y;
//! - the image center (`u = 1/2`, `v = 1/2`) is +z; `u = 1/4` is +x,
//!   `u = 3/4` is -x, and the left/right edge (`u = 0`, the seam) is -z;
//! - `u` turns clockwise seen from above (+y): a viewer at the origin looking
//!   toward +z with +y up sees the image center unmirrored, `u` increasing to
//!   the right, as a photograph taken from the inside of the sphere.
//!
//! The `to_world` rotation takes these local directions to world space.
//! Column `i` of a `width`-pixel map covers `u` in `[i, i + 1) / width` and row
//! `j` of a `height`-pixel map covers `v` in `[j, j + 1) / height` (the common
//! equirectangular pixel grid of pbrt and OpenEXR). Mitsuba 3 shares the
//! axes and the columns but centers row `j` at `v = j / (height - 1)` (first
//! and last rows on the poles), so the two differ by at most half a row.
//!
//! # Lookup and sampling
//! [`EnvironmentMap::le`] is a nearest-pixel lookup: each pixel is a patch of
//! the sphere of constant radiance. Sampling picks a pixel from a
//! [`Distribution2D`] over pixels weighted by luminance times the pixel's
//! solid angle `(2 pi / width) (cos(theta_j) - cos(theta_{j+1}))` (the
//! integral of `sin(theta)`, the Jacobian of the lat-long map, over the row),
//! then a direction uniformly in solid angle inside the pixel (uniform `phi`
//! and `cos(theta)`). The density per steradian is therefore constant on each
//! pixel, `pmf(pixel) / solid_angle(pixel)`, finite at the poles, and
//! `le / pdf` is exactly proportional to `le / luminance(le)`: a gray map is
//! sampled with zero variance. pbrt-v4 instead interpolates `Le` bilinearly
//! and samples a piecewise-constant density in (u, v) divided by
//! `sin(theta)`; both are unbiased.

use std::path::{Path, PathBuf};

use glam::Mat3;

use crate::color::Rgb;
use crate::math::{safe_sqrt, Vec2, Vec3, PI};
use crate::sampling::Distribution2D;

/// Why a light could not be built. Messages name the source (a file path or
/// `<pixels>` for in-memory data) and what was wrong with it.
///
/// ```
/// use niebla::light::{EnvironmentMap, LightError};
/// let e = EnvironmentMap::from_exr("no/such/sky.exr", 1.0, glam::Mat3::IDENTITY).unwrap_err();
/// assert!(matches!(e, LightError::Missing { .. }));
/// assert_eq!(e.to_string(), "no/such/sky.exr: environment map file not found");
/// ```
#[derive(Debug, thiserror::Error)]
pub enum LightError {
    /// The file does not exist.
    #[error("{}: environment map file not found", path.display())]
    Missing {
        /// The requested file.
        path: PathBuf,
    },
    /// The file exists but could not be read.
    #[error("{}: could not read environment map: {source}", path.display())]
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
    /// The image has no pixels.
    #[error("{source_name}: environment map has zero size ({width} x {height})")]
    ZeroSize {
        /// File path or `<pixels>`.
        source_name: String,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
    },
    /// The pixel buffer does not hold `width * height` pixels.
    #[error("{source_name}: {count} pixels given for a {width} x {height} environment map")]
    PixelCount {
        /// File path or `<pixels>`.
        source_name: String,
        /// Width in pixels.
        width: usize,
        /// Height in pixels.
        height: usize,
        /// Pixels given.
        count: usize,
    },
    /// A pixel is NaN, infinite or negative (radiance must be finite and >= 0).
    #[error("{source_name}: pixel (x {x}, y {y}) channel {channel} = {value}: radiance must be finite and >= 0")]
    InvalidPixel {
        /// File path or `<pixels>`.
        source_name: String,
        /// Column (0 = left).
        x: usize,
        /// Row (0 = top).
        y: usize,
        /// `R`, `G` or `B`.
        channel: char,
        /// The offending value.
        value: f32,
    },
    /// A scale or radiance parameter that is not finite and non-negative.
    #[error("{source_name}: {name} = {value} must be finite and >= 0")]
    InvalidParameter {
        /// File path, `<pixels>` or the light's kind.
        source_name: String,
        /// Parameter name (`scale`, `radiance`, `radius`, ...).
        name: &'static str,
        /// The value given.
        value: f32,
    },
    /// `to_world` is not a rotation (orthonormal with determinant +1, to 1e-4).
    #[error("{source_name}: to_world is not a rotation (orthonormal, determinant +1): {matrix:?}")]
    NotARotation {
        /// File path or `<pixels>`.
        source_name: String,
        /// The matrix given, columns.
        matrix: [[f32; 3]; 3],
    },
}

/// A direction sampled toward an environment map.
#[derive(Clone, Copy, Debug)]
pub struct EnvironmentSample {
    /// Unit direction from the receiver toward the environment (world).
    pub wi: Vec3,
    /// Radiance seen looking along `wi` (it travels along `-wi` to the
    /// receiver), scaled, W/(sr m^2); equal to [`EnvironmentMap::le`] of `wi`.
    pub li: Rgb,
    /// Density of `wi` per steradian (> 0), equal to [`EnvironmentMap::pdf_li`].
    pub pdf: f32,
}

/// A lat-long environment of radiance (W/(sr m^2), linear RGB) at infinity,
/// importance sampled by luminance times solid angle. See the module docs for
/// the mapping from image to directions (Mitsuba 3's axes).
///
/// ```
/// use niebla::color::Rgb;
/// use niebla::light::EnvironmentMap;
/// use niebla::math::Vec3;
/// // 4 x 2 map: the top row (upper hemisphere) is bright.
/// let mut pixels = vec![Rgb::splat(1.0); 8];
/// pixels[..4].fill(Rgb::splat(3.0));
/// let env = EnvironmentMap::from_pixels(4, 2, pixels, 2.0, glam::Mat3::IDENTITY).unwrap();
/// assert_eq!(env.le(Vec3::Y), Rgb::splat(6.0));
/// assert_eq!(env.le(-Vec3::Y), Rgb::splat(2.0));
/// ```
#[derive(Clone, Debug)]
pub struct EnvironmentMap {
    width: usize,
    height: usize,
    /// Unscaled radiance, row-major, row 0 at the top (+y).
    pixels: Vec<Rgb>,
    /// Multiplies every pixel.
    scale: f32,
    /// Map-local to world rotation.
    to_world: Mat3,
    /// World to map-local (transpose of `to_world`).
    to_local: Mat3,
    /// `cos(theta)` at the row edges, `height + 1` entries from 1 down to -1.
    row_cos: Vec<f32>,
    /// Pixel choice in (u, v), weights luminance times solid angle.
    distribution: Distribution2D,
}

impl EnvironmentMap {
    /// Read a lat-long map from an OpenEXR file (R, G, B channels of the first
    /// layer that has them, any sample type; alpha and other channels are
    /// ignored). Pixel values are linear radiance, W/(sr m^2), multiplied by
    /// `scale`; `to_world` rotates map-local directions to world space.
    pub fn from_exr(path: impl AsRef<Path>, scale: f32, to_world: Mat3) -> Result<EnvironmentMap, LightError> {
        let path = path.as_ref();
        let (width, height, pixels) = read_exr_rgb(path)?;
        EnvironmentMap::build(path.display().to_string(), width, height, pixels, scale, to_world)
    }

    /// A map from `width * height` pixels in row-major order, row 0 at the top
    /// (+y), column 0 at `u = 0` (-z); see the module docs for the mapping.
    pub fn from_pixels(
        width: usize,
        height: usize,
        pixels: Vec<Rgb>,
        scale: f32,
        to_world: Mat3,
    ) -> Result<EnvironmentMap, LightError> {
        EnvironmentMap::build("<pixels>".to_string(), width, height, pixels, scale, to_world)
    }

    fn build(
        source_name: String,
        width: usize,
        height: usize,
        pixels: Vec<Rgb>,
        scale: f32,
        to_world: Mat3,
    ) -> Result<EnvironmentMap, LightError> {
        // Validate: size, pixel count, pixel values, scale, rotation.
        if width == 0 || height == 0 {
            return Err(LightError::ZeroSize { source_name, width, height });
        }
        if pixels.len() != width * height {
            return Err(LightError::PixelCount { source_name, width, height, count: pixels.len() });
        }
        for (k, p) in pixels.iter().enumerate() {
            for (c, channel) in ['R', 'G', 'B'].into_iter().enumerate() {
                let value = p.0[c];
                if !value.is_finite() || value < 0.0 {
                    return Err(LightError::InvalidPixel { source_name, x: k % width, y: k / width, channel, value });
                }
            }
        }
        if !scale.is_finite() || scale < 0.0 {
            return Err(LightError::InvalidParameter { source_name, name: "scale", value: scale });
        }
        if !is_rotation(to_world) {
            return Err(LightError::NotARotation { source_name, matrix: to_world.to_cols_array_2d() });
        }

        // Row edges in cos(theta), computed in f64 so that thin polar rows keep
        // their (small, positive) solid angle.
        let row_cos: Vec<f32> =
            (0..=height).map(|j| (std::f64::consts::PI * j as f64 / height as f64).cos() as f32).collect();
        let weights: Vec<f32> = pixels
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let j = k / width;
                p.luminance() * (row_cos[j] - row_cos[j + 1])
            })
            .collect();
        let distribution = Distribution2D::new(&weights, width, height);
        Ok(EnvironmentMap {
            width,
            height,
            pixels,
            scale,
            to_world,
            to_local: to_world.transpose(),
            row_cos,
            distribution,
        })
    }

    /// Width in pixels (along `u`, azimuth).
    #[inline]
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels (along `v`, polar angle from +y).
    #[inline]
    pub fn height(&self) -> usize {
        self.height
    }

    /// The radiance multiplier.
    #[inline]
    pub fn scale(&self) -> f32 {
        self.scale
    }

    /// The map-local to world rotation.
    #[inline]
    pub fn to_world(&self) -> Mat3 {
        self.to_world
    }

    /// Scaled radiance of pixel `(x, y)` (column, row from the top), W/(sr m^2).
    #[inline]
    pub fn pixel(&self, x: usize, y: usize) -> Rgb {
        self.pixels[y * self.width + x] * self.scale
    }

    /// Solid angle of a pixel of row `y`, steradians.
    #[inline]
    pub fn pixel_solid_angle(&self, y: usize) -> f32 {
        2.0 * PI / self.width as f32 * (self.row_cos[y] - self.row_cos[y + 1])
    }

    /// World direction through the center of pixel `(x, y)` (its center in
    /// `u` and in `cos(theta)`).
    pub fn pixel_direction(&self, x: usize, y: usize) -> Vec3 {
        let phi = 2.0 * PI * (x as f32 + 0.5) / self.width as f32;
        let cos_theta = 0.5 * (self.row_cos[y] + self.row_cos[y + 1]);
        (self.to_world * local_direction(phi, cos_theta)).normalize()
    }

    /// Pixel `(x, y)` that world direction `w` falls in.
    #[inline]
    pub fn pixel_of_direction(&self, w: Vec3) -> (usize, usize) {
        let uv = latlong_uv(self.to_local * w);
        self.distribution.cell(uv)
    }

    /// Radiance arriving from the environment along world direction `d`
    /// (unit, pointing from the receiver toward the environment), scaled,
    /// W/(sr m^2). Nearest-pixel lookup.
    #[inline]
    pub fn le(&self, d: Vec3) -> Rgb {
        let (x, y) = self.pixel_of_direction(d);
        self.pixel(x, y)
    }

    /// Sample a world direction toward the environment from `u` in [0, 1)^2
    /// with density proportional to luminance (see the module docs). `None`
    /// only when rounding puts the direction in a pixel of zero probability.
    pub fn sample_li(&self, u: Vec2) -> Option<EnvironmentSample> {
        // Pick a pixel, keeping the point's position inside it (uniform).
        let (uv, _pdf_uv) = self.distribution.sample(u);
        let (_, y) = self.distribution.cell(uv);
        let frac_v = (uv.y * self.height as f32 - y as f32).clamp(0.0, 1.0);
        // Uniform in solid angle inside the pixel: uniform phi and cos(theta).
        let phi = 2.0 * PI * uv.x;
        let cos_theta = self.row_cos[y] + frac_v * (self.row_cos[y + 1] - self.row_cos[y]);
        let wi = (self.to_world * local_direction(phi, cos_theta)).normalize();
        // Value and density of the pixel the direction lies in, so that
        // `pdf == pdf_li(wi)` and `li == le(wi)` exactly.
        let (x, y) = self.pixel_of_direction(wi);
        let pdf = self.pixel_pdf(x, y);
        if !(pdf > 0.0) {
            return None;
        }
        Some(EnvironmentSample { wi, li: self.pixel(x, y), pdf })
    }

    /// Density per steradian with which [`EnvironmentMap::sample_li`] returns
    /// world direction `wi`.
    #[inline]
    pub fn pdf_li(&self, wi: Vec3) -> f32 {
        let (x, y) = self.pixel_of_direction(wi);
        self.pixel_pdf(x, y)
    }

    /// `pmf(pixel) / solid_angle(pixel)`, per steradian.
    #[inline]
    fn pixel_pdf(&self, x: usize, y: usize) -> f32 {
        let omega = self.pixel_solid_angle(y);
        if omega > 0.0 {
            self.distribution.pmf(x, y) / omega
        } else {
            0.0
        }
    }

    /// Integral of the scaled radiance over the sphere of directions,
    /// `sum over pixels of L_pixel Omega_pixel`, W/m^2 (summed in f64). A gray
    /// map's `le / pdf` equals this value for every sample.
    pub fn radiance_integral(&self) -> Rgb {
        let mut sum = [0f64; 3];
        for (k, p) in self.pixels.iter().enumerate() {
            let omega = self.pixel_solid_angle(k / self.width) as f64;
            for (total, value) in sum.iter_mut().zip(p.0) {
                *total += value as f64 * omega;
            }
        }
        Rgb(sum.map(|s| (s * self.scale as f64) as f32))
    }

    /// Power (W, per channel) that the environment sends into a sphere of
    /// `scene_radius` bounding the scene: each direction's radiance crosses a
    /// disk of area `pi r^2`, so `Phi = pi r^2 * integral of L over the sphere`
    /// (pbrt-v4 `ImageInfiniteLight::Phi`). Used to choose lights by power.
    pub fn power_estimate(&self, scene_radius: f32) -> Rgb {
        self.radiance_integral() * (PI * scene_radius * scene_radius)
    }
}

/// Map-local direction from azimuth `phi` (radians, from -z toward +x) and
/// `cos(theta)` to +y (Mitsuba 3's `uv_to_direction`).
#[inline]
fn local_direction(phi: f32, cos_theta: f32) -> Vec3 {
    let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
    let (sin_phi, cos_phi) = phi.sin_cos();
    Vec3::new(sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta)
}

/// Map-local unit direction from lat-long texture coordinates in [0, 1]^2:
/// `theta = pi v` from +y, `phi = 2 pi u` from -z toward +x.
///
/// ```
/// use niebla::light::{latlong_direction, latlong_uv};
/// use niebla::math::{Vec2, Vec3};
/// assert!((latlong_direction(Vec2::new(0.5, 0.5)) - Vec3::Z).length() < 1e-6);
/// assert!((latlong_direction(Vec2::new(0.25, 0.5)) - Vec3::X).length() < 1e-6);
/// assert!((latlong_uv(-Vec3::X) - Vec2::new(0.75, 0.5)).length() < 1e-6);
/// ```
#[inline]
pub fn latlong_direction(uv: Vec2) -> Vec3 {
    local_direction(2.0 * PI * uv.x, (PI * uv.y).cos())
}

/// Lat-long texture coordinates in [0, 1)x[0, 1] of a map-local unit
/// direction; inverse of [`latlong_direction`].
#[inline]
pub fn latlong_uv(d: Vec3) -> Vec2 {
    let mut u = d.x.atan2(-d.z) * (0.5 / PI);
    if u < 0.0 {
        u += 1.0;
    }
    if u >= 1.0 {
        u = 0.0;
    }
    Vec2::new(u, d.y.clamp(-1.0, 1.0).acos() / PI)
}

/// True when `m` is orthonormal with determinant +1, to 1e-4.
fn is_rotation(m: Mat3) -> bool {
    let e = m.transpose() * m - Mat3::IDENTITY;
    let max_err = e.to_cols_array().iter().fold(0f32, |a, v| a.max(v.abs()));
    max_err < 1e-4 && (m.determinant() - 1.0).abs() < 1e-4
}

/// Read the R, G, B channels of the first layer of an EXR that has them
/// (through [`crate::film::read_exr`]), as (width, height, pixels).
fn read_exr_rgb(path: &Path) -> Result<(usize, usize, Vec<Rgb>), LightError> {
    use crate::film::ExrReadError;
    let read = crate::film::read_exr(path).map_err(|e| match e {
        ExrReadError::Missing { path } => LightError::Missing { path },
        ExrReadError::Io { path, source } => LightError::Io { path, source },
        ExrReadError::NotExr { path, message } => LightError::NotExr { path, message },
        ExrReadError::NoRgbChannels { path, found } => LightError::NoRgbChannels { path, found },
        ExrReadError::ZeroSize { path, width, height } => {
            LightError::ZeroSize { source_name: path.display().to_string(), width, height }
        }
    })?;
    let image = read.image;
    Ok((image.width as usize, image.height as usize, image.pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latlong_axes_follow_mitsuba3() {
        // Image center +z, u = 1/4 +x, u = 3/4 -x, seam -z, top +y, bottom -y.
        let cases = [
            (Vec2::new(0.5, 0.5), Vec3::Z),
            (Vec2::new(0.25, 0.5), Vec3::X),
            (Vec2::new(0.75, 0.5), -Vec3::X),
            (Vec2::new(0.0, 0.5), -Vec3::Z),
            (Vec2::new(0.3, 0.0), Vec3::Y),
            (Vec2::new(0.3, 1.0), -Vec3::Y),
        ];
        for (uv, d) in cases {
            assert!((latlong_direction(uv) - d).length() < 1e-6, "{uv} -> {}", latlong_direction(uv));
        }
        for uv in [Vec2::new(0.1, 0.2), Vec2::new(0.6, 0.7), Vec2::new(0.95, 0.45)] {
            assert!((latlong_uv(latlong_direction(uv)) - uv).length() < 1e-5);
        }
    }

    #[test]
    fn pixel_solid_angles_sum_to_four_pi() {
        let env = EnvironmentMap::from_pixels(7, 5, vec![Rgb::ONE; 35], 1.0, Mat3::IDENTITY).unwrap();
        let total: f64 = (0..5).map(|y| env.pixel_solid_angle(y) as f64 * 7.0).sum();
        assert!((total - 4.0 * std::f64::consts::PI).abs() < 1e-5);
        // A uniform map is sampled uniformly over the sphere.
        assert!((env.pdf_li(Vec3::new(0.3, -0.2, 0.9).normalize()) - 0.25 / PI).abs() < 1e-6);
    }
}
