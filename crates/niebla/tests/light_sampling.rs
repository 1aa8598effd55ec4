//! Light sampling: environment maps and area lights against their own pdfs
//! (chi-square) and against closed-form irradiance (Monte Carlo within 4
//! standard errors estimated from the same samples, fixed seeds).

use std::f64::consts::PI as PI64;
use std::path::PathBuf;

use glam::Mat3;
use niebla::color::Rgb;
use niebla::geometry::{Rectangle, Sphere, Transform};
use niebla::light::{AreaLight, AreaShape, EnvironmentMap, LightError};
use niebla::math::{Frame, Vec3};
use niebla::sampling::PixelSampler;

// ---------------------------------------------------------------------------
// Statistics helpers

/// Pearson chi-square of observed against expected counts, cells with
/// expected < 5 pooled into one (as Mitsuba 3's `ChiSquareTest`). Returns
/// (statistic, degrees of freedom).
fn chi2(observed: &[f64], expected: &[f64]) -> (f64, usize) {
    let (mut stat, mut cells, mut pooled_obs, mut pooled_exp) = (0.0, 0usize, 0.0, 0.0);
    for (o, e) in observed.iter().zip(expected) {
        if *e < 5.0 {
            pooled_obs += o;
            pooled_exp += e;
        } else {
            stat += (o - e).powi(2) / e;
            cells += 1;
        }
    }
    if pooled_exp > 0.0 {
        stat += (pooled_obs - pooled_exp).powi(2) / pooled_exp;
        cells += 1;
    }
    (stat, cells - 1)
}

/// Chi-square quantile at tail probability ~1e-4 (Wilson-Hilferty, z = 3.72).
fn chi2_bound(dof: usize) -> f64 {
    let k = dof as f64;
    let c = 2.0 / (9.0 * k);
    k * (1.0 - c + 3.72 * c.sqrt()).powi(3)
}

fn assert_chi2(name: &str, observed: &[f64], expected: &[f64]) {
    let (stat, dof) = chi2(observed, expected);
    eprintln!("{name}: chi2 = {stat:.1}, dof = {dof}, bound = {:.1}", chi2_bound(dof));
    assert!(stat < chi2_bound(dof), "{name}: chi2 = {stat} with {dof} dof (bound {})", chi2_bound(dof));
}

/// Mean and standard error of the mean of `values`.
fn mean_and_standard_error(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Assert that a Monte Carlo mean is within 4 standard errors of `expected`
/// (plus 1e-6 relative, for zero-variance estimators).
fn assert_within_4_se(name: &str, values: &[f64], expected: f64) {
    let (mean, se) = mean_and_standard_error(values);
    let z = (mean - expected) / se.max(1e-300);
    eprintln!("{name}: estimate {mean:.6} +- {se:.2e} (n = {}), exact {expected:.6}, z = {z:.2}", values.len());
    assert!((mean - expected).abs() <= 4.0 * se + 1e-6 * expected.abs(), "{name}: {mean} vs {expected}, se {se}");
}

/// Histogram of unit directions in (cos theta, phi) cells around `frame.z`,
/// `cos theta` in `[cos_min, 1]`; directions outside the cone are counted in
/// an extra last cell.
struct ConeHistogram {
    frame: Frame,
    cos_min: f64,
    n_cos: usize,
    n_phi: usize,
}

impl ConeHistogram {
    fn cell(&self, w: Vec3) -> usize {
        let l = self.frame.to_local(w);
        let c = l.z as f64;
        if c < self.cos_min {
            return self.n_cos * self.n_phi;
        }
        let i = (((c - self.cos_min) / (1.0 - self.cos_min)) * self.n_cos as f64) as usize;
        let phi = (l.y as f64).atan2(l.x as f64).rem_euclid(2.0 * PI64);
        let j = (phi / (2.0 * PI64) * self.n_phi as f64) as usize;
        i.min(self.n_cos - 1) * self.n_phi + j.min(self.n_phi - 1)
    }

    fn observed(&self, directions: impl Iterator<Item = Vec3>) -> Vec<f64> {
        let mut counts = vec![0f64; self.n_cos * self.n_phi + 1];
        for w in directions {
            counts[self.cell(w)] += 1.0;
        }
        counts
    }

    /// Expected counts of `n` samples: the integral of `pdf` over each cell by
    /// a `sub x sub` midpoint rule in (cos theta, phi), where d omega =
    /// d cos d phi; the last cell gets the remainder of the probability.
    fn expected(&self, n: usize, sub: usize, pdf: impl Fn(Vec3) -> f32) -> Vec<f64> {
        let mut e = vec![0f64; self.n_cos * self.n_phi + 1];
        let d_cos = (1.0 - self.cos_min) / (self.n_cos * sub) as f64;
        let d_phi = 2.0 * PI64 / (self.n_phi * sub) as f64;
        for a in 0..self.n_cos * sub {
            let c = self.cos_min + (a as f64 + 0.5) * d_cos;
            let s = (1.0 - c * c).max(0.0).sqrt();
            for b in 0..self.n_phi * sub {
                let phi = (b as f64 + 0.5) * d_phi;
                let local = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
                let w = self.frame.to_world(local).normalize();
                e[(a / sub) * self.n_phi + b / sub] += pdf(w) as f64 * d_cos * d_phi * n as f64;
            }
        }
        let inside: f64 = e.iter().sum();
        e[self.n_cos * self.n_phi] = (n as f64 - inside).max(0.0);
        e
    }
}

// ---------------------------------------------------------------------------
// Environment maps

/// A colored test map with smooth variation, a hot spot and one black pixel.
fn test_map_pixels(width: usize, height: usize) -> Vec<Rgb> {
    (0..width * height)
        .map(|k| {
            let (x, y) = ((k % width) as f32, (k / width) as f32);
            let base = 1.0 + 0.5 * (0.9 * x).sin() + 0.3 * (1.3 * y).cos();
            let hot = if k == 2 * width + 5 { 20.0 } else { 0.0 };
            if k == width + 1 {
                Rgb::ZERO
            } else {
                Rgb::new(base + hot, 0.8 * base + 0.5 * hot, 1.2 * base)
            }
        })
        .collect()
}

fn test_rotation() -> Mat3 {
    Mat3::from_axis_angle(Vec3::new(1.0, 1.0, 0.3).normalize(), 0.7)
}

#[test]
fn envmap_axes_follow_mitsuba3_convention() {
    // 3 x 3 map: +z is the center pixel, +y the top row, -y the bottom row,
    // +x (u = 1/4) the left column, -x (u = 3/4) the right column.
    let pixels: Vec<Rgb> = (0..9).map(|k| Rgb::splat(k as f32 + 1.0)).collect();
    let env = EnvironmentMap::from_pixels(3, 3, pixels.clone(), 1.0, Mat3::IDENTITY).unwrap();
    assert_eq!(env.le(Vec3::Z), Rgb::splat(5.0));
    assert_eq!(env.pixel_of_direction(Vec3::Y).1, 0);
    assert_eq!(env.pixel_of_direction(-Vec3::Y).1, 2);
    assert_eq!(env.le(Vec3::X), Rgb::splat(4.0));
    assert_eq!(env.le(-Vec3::X), Rgb::splat(6.0));
    // to_world rotates the map: a quarter turn about +y takes +z to +x.
    let turned =
        EnvironmentMap::from_pixels(3, 3, pixels, 1.0, Mat3::from_rotation_y(std::f32::consts::FRAC_PI_2)).unwrap();
    assert_eq!(turned.le(Vec3::X), Rgb::splat(5.0));
}

#[test]
fn envmap_samples_follow_pdf_li_chi_square() {
    // 2e5 samples of an 8 x 6 rotated map binned in 10 x 14 (cos theta, phi)
    // cells of the map's local frame that do not align with the pixels.
    // Expected counts are exact: the pdf is constant on each pixel, a
    // rectangle in (cos theta, phi), so a cell's probability is the sum of
    // pixel pdf times overlap area.
    let (w, h) = (8usize, 6usize);
    let to_world = test_rotation();
    let env = EnvironmentMap::from_pixels(w, h, test_map_pixels(w, h), 1.0, to_world).unwrap();
    let (n, n_cos, n_phi) = (200_000usize, 10usize, 14usize);
    let to_local = to_world.transpose();
    let mut observed = vec![0f64; n_cos * n_phi];
    let mut rng = PixelSampler::from_key(201);
    let mut max_pdf_error = 0f32;
    for _ in 0..n {
        let s = env.sample_li(rng.next_2d()).expect("sample");
        max_pdf_error = max_pdf_error.max((s.pdf - env.pdf_li(s.wi)).abs() / s.pdf);
        assert_eq!(s.li, env.le(s.wi));
        let l = to_local * s.wi;
        let c = ((1.0 - l.y as f64) / 2.0 * n_cos as f64) as usize; // cos from +1 down to -1
        let phi = niebla::light::latlong_uv(l).x as f64;
        observed[c.min(n_cos - 1) * n_phi + ((phi * n_phi as f64) as usize).min(n_phi - 1)] += 1.0;
    }
    assert_eq!(max_pdf_error, 0.0, "sample pdf differs from pdf_li");
    let overlap = |a0: f64, a1: f64, b0: f64, b1: f64| (a1.min(b1) - a0.max(b0)).max(0.0);
    let mut expected = vec![0f64; n_cos * n_phi];
    for (k, e) in expected.iter_mut().enumerate() {
        let (ci, pj) = ((k / n_phi) as f64, (k % n_phi) as f64);
        // Cell in "1 - cos" in [0, 2] and u in [0, 1].
        let (c0, c1) = (2.0 * ci / n_cos as f64, 2.0 * (ci + 1.0) / n_cos as f64);
        let (u0, u1) = (pj / n_phi as f64, (pj + 1.0) / n_phi as f64);
        for y in 0..h {
            let (r0, r1) = (1.0 - (PI64 * y as f64 / h as f64).cos(), 1.0 - (PI64 * (y + 1) as f64 / h as f64).cos());
            for x in 0..w {
                let area = overlap(c0, c1, r0, r1) * overlap(u0, u1, x as f64 / w as f64, (x + 1) as f64 / w as f64);
                // d omega = d cos * 2 pi d u.
                *e += area * 2.0 * PI64 * env.pdf_li(env.pixel_direction(x, y)) as f64 * n as f64;
            }
        }
    }
    assert!((expected.iter().sum::<f64>() / n as f64 - 1.0).abs() < 1e-5, "pdf_li does not integrate to 1");
    assert_chi2("envmap directions", &observed, &expected);
}

#[test]
fn envmap_irradiance_estimate_matches_pixel_quadrature() {
    // E(n) = integral of L(w) max(0, w . n) d omega, per channel. Reference:
    // per pixel, a 24 x 24 midpoint rule in (cos theta, phi) of the cosine
    // (relative error ~1e-5, far below the Monte Carlo standard error).
    let (w, h) = (16usize, 8usize);
    let to_world = test_rotation();
    let env = EnvironmentMap::from_pixels(w, h, test_map_pixels(w, h), 1.5, to_world).unwrap();
    let normal = Vec3::new(0.2, 0.9, -0.4).normalize();
    let sub = 24;
    let mut reference = [0f64; 3];
    for y in 0..h {
        let (c0, c1) = ((PI64 * y as f64 / h as f64).cos(), (PI64 * (y + 1) as f64 / h as f64).cos());
        for x in 0..w {
            let l = env.pixel(x, y);
            let mut cos_integral = 0.0;
            for a in 0..sub {
                let c = c0 + (c1 - c0) * (a as f64 + 0.5) / sub as f64;
                for b in 0..sub {
                    let phi = 2.0 * PI64 * (x as f64 + (b as f64 + 0.5) / sub as f64) / w as f64;
                    let s = (1.0 - c * c).sqrt();
                    let local = Vec3::new((phi.sin() * s) as f32, c as f32, (-phi.cos() * s) as f32);
                    let wd = to_world * local;
                    cos_integral +=
                        (wd.dot(normal).max(0.0) as f64) * (c0 - c1) / sub as f64 * 2.0 * PI64 / (w * sub) as f64;
                }
            }
            for (ch, r) in reference.iter_mut().enumerate() {
                *r += l[ch] as f64 * cos_integral;
            }
        }
    }
    let n = 100_000;
    let mut rng = PixelSampler::from_key(202);
    let samples: Vec<_> = (0..n).map(|_| env.sample_li(rng.next_2d()).unwrap()).collect();
    for (ch, name) in ["R", "G", "B"].iter().enumerate() {
        let values: Vec<f64> =
            samples.iter().map(|s| s.li[ch] as f64 * s.wi.dot(normal).max(0.0) as f64 / s.pdf as f64).collect();
        assert_within_4_se(&format!("envmap irradiance {name}"), &values, reference[ch]);
    }
}

#[test]
fn gray_envmap_le_over_pdf_is_its_radiance_integral() {
    // Sampling proportional to luminance times solid angle: for a gray map
    // le / pdf is the same for every sample (zero variance).
    let (w, h) = (12usize, 7usize);
    let pixels: Vec<Rgb> = test_map_pixels(w, h).iter().map(|p| Rgb::splat(p.g() + 0.1)).collect();
    let env = EnvironmentMap::from_pixels(w, h, pixels, 0.5, Mat3::IDENTITY).unwrap();
    let total = env.radiance_integral().g();
    let mut rng = PixelSampler::from_key(203);
    for _ in 0..20_000 {
        let s = env.sample_li(rng.next_2d()).unwrap();
        let ratio = s.li.g() / s.pdf;
        assert!((ratio - total).abs() < 1e-4 * total, "le/pdf = {ratio}, integral = {total}");
    }
    // Power through a bounding sphere: pi r^2 times the radiance integral.
    assert!((env.power_estimate(2.0).g() - std::f32::consts::PI * 4.0 * total).abs() < 1e-3 * total);
}

#[test]
fn single_bright_pixel_attracts_the_samples() {
    let (w, h, bright) = (16usize, 8usize, (11usize, 2usize));
    let mut pixels = vec![Rgb::ZERO; w * h];
    pixels[bright.1 * w + bright.0] = Rgb::splat(100.0);
    let env = EnvironmentMap::from_pixels(w, h, pixels.clone(), 1.0, test_rotation()).unwrap();
    let center = env.pixel_direction(bright.0, bright.1);
    // Angular half-diagonal of the pixel: 2 pi / 16 wide, pi / 8 tall.
    let max_angle = 0.5 * ((2.0 * std::f32::consts::PI / 16.0).powi(2) + (std::f32::consts::PI / 8.0).powi(2)).sqrt();
    let mut rng = PixelSampler::from_key(204);
    for _ in 0..10_000 {
        let s = env.sample_li(rng.next_2d()).unwrap();
        assert_eq!(env.pixel_of_direction(s.wi), bright);
        assert!(s.wi.dot(center) >= max_angle.cos() - 1e-5);
    }
    // With a dim background the bright pixel gets its share of luminance x
    // solid angle; the count is binomial, 5 standard deviations.
    for p in pixels.iter_mut().filter(|p| p.is_black()) {
        *p = Rgb::splat(0.5);
    }
    let env = EnvironmentMap::from_pixels(w, h, pixels, 1.0, Mat3::IDENTITY).unwrap();
    let share = {
        let b = 100.0 * env.pixel_solid_angle(bright.1) as f64;
        b / (b + 0.5 * (4.0 * PI64 - env.pixel_solid_angle(bright.1) as f64))
    };
    let n = 50_000;
    let hits = (0..n).filter(|_| env.pixel_of_direction(env.sample_li(rng.next_2d()).unwrap().wi) == bright).count();
    let sd = (n as f64 * share * (1.0 - share)).sqrt();
    eprintln!("bright pixel: {hits} of {n} samples, expected {:.0} +- {sd:.0}", n as f64 * share);
    assert!((hits as f64 - n as f64 * share).abs() < 5.0 * sd);
}

fn tmp_path(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("light_sampling");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn write_rgb_exr(path: &std::path::Path, width: usize, height: usize, pixel: impl Fn(usize, usize) -> [f32; 3] + Sync) {
    use exr::prelude::*;
    let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
        let p = pixel(pos.x(), pos.y());
        (p[0], p[1], p[2])
    });
    Image::from_channels((width, height), channels).write().to_file(path).unwrap();
}

#[test]
fn envmap_exr_round_trip() {
    let (w, h) = (6usize, 3usize);
    let value = |x: usize, y: usize| [x as f32 * 0.5 + 0.25, y as f32 * 2.0, 1e-3 * (x + 10 * y) as f32];
    let path = tmp_path("round_trip.exr");
    write_rgb_exr(&path, w, h, value);
    let env = EnvironmentMap::from_exr(&path, 2.0, Mat3::IDENTITY).unwrap();
    assert_eq!((env.width(), env.height()), (w, h));
    for y in 0..h {
        for x in 0..w {
            let v = value(x, y);
            assert_eq!(env.pixel(x, y), Rgb::new(v[0], v[1], v[2]) * 2.0, "pixel ({x}, {y})");
        }
    }
}

#[test]
fn envmap_errors_name_the_file_and_the_problem() {
    // Missing file.
    let missing = tmp_path("does_not_exist.exr");
    let e = EnvironmentMap::from_exr(&missing, 1.0, Mat3::IDENTITY).unwrap_err();
    assert!(matches!(e, LightError::Missing { .. }) && e.to_string().contains("does_not_exist.exr"), "{e}");
    // Not an EXR.
    let text = tmp_path("not_an_image.exr");
    std::fs::write(&text, "this is not an image").unwrap();
    let e = EnvironmentMap::from_exr(&text, 1.0, Mat3::IDENTITY).unwrap_err();
    assert!(matches!(e, LightError::NotExr { .. }) && e.to_string().contains("not_an_image.exr"), "{e}");
    // A luminance-only EXR.
    let gray = tmp_path("luminance_only.exr");
    {
        use exr::prelude::*;
        let channels = SpecificChannels::build().with_channel("Y").with_pixel_fn(|_pos| (0.5f32,));
        Image::from_channels((4, 2), channels).write().to_file(&gray).unwrap();
    }
    let e = EnvironmentMap::from_exr(&gray, 1.0, Mat3::IDENTITY).unwrap_err();
    assert!(matches!(e, LightError::NoRgbChannels { .. }) && e.to_string().contains("found: Y"), "{e}");
    // A NaN pixel in a file: the message has the file, pixel and channel.
    let nan = tmp_path("nan_pixel.exr");
    write_rgb_exr(&nan, 4, 2, |x, y| if (x, y) == (3, 1) { [0.0, f32::NAN, 0.0] } else { [1.0; 3] });
    let e = EnvironmentMap::from_exr(&nan, 1.0, Mat3::IDENTITY).unwrap_err();
    let message = e.to_string();
    assert!(matches!(e, LightError::InvalidPixel { x: 3, y: 1, channel: 'G', .. }), "{message}");
    assert!(message.contains("nan_pixel.exr") && message.contains("(x 3, y 1) channel G"), "{message}");
    // In-memory pixels: negative, infinite, zero size, wrong count, bad scale, not a rotation.
    let from = |w, h, p: Vec<Rgb>, scale, m| EnvironmentMap::from_pixels(w, h, p, scale, m).unwrap_err();
    let mut p = vec![Rgb::ONE; 8];
    p[5] = Rgb::new(1.0, 1.0, -0.5);
    assert!(matches!(from(4, 2, p, 1.0, Mat3::IDENTITY), LightError::InvalidPixel { x: 1, y: 1, channel: 'B', .. }));
    let mut p = vec![Rgb::ONE; 8];
    p[0] = Rgb::new(f32::INFINITY, 1.0, 1.0);
    assert!(matches!(from(4, 2, p, 1.0, Mat3::IDENTITY), LightError::InvalidPixel { x: 0, y: 0, channel: 'R', .. }));
    assert!(matches!(from(0, 4, vec![], 1.0, Mat3::IDENTITY), LightError::ZeroSize { width: 0, height: 4, .. }));
    assert!(matches!(from(4, 2, vec![Rgb::ONE; 7], 1.0, Mat3::IDENTITY), LightError::PixelCount { count: 7, .. }));
    assert!(matches!(
        from(4, 2, vec![Rgb::ONE; 8], -1.0, Mat3::IDENTITY),
        LightError::InvalidParameter { name: "scale", .. }
    ));
    let mirror = Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0));
    assert!(matches!(from(4, 2, vec![Rgb::ONE; 8], 1.0, mirror), LightError::NotARotation { .. }));
    eprintln!("{}", from(0, 4, vec![], 1.0, Mat3::IDENTITY));
}

// ---------------------------------------------------------------------------
// Area lights

fn sphere_light(center: Vec3, radius: f32, l: f32, two_sided: bool) -> AreaLight {
    AreaLight::new(AreaShape::Sphere(Sphere::new(center, radius)), Rgb::splat(l), two_sided).unwrap()
}

/// A rectangle light of half-sides (a_x, a_y), parallel to the xy plane at
/// height `h`, emitting downward (front side -z), with a rotation about z.
fn ceiling_rectangle(a_x: f32, a_y: f32, h: f32, l: f32, two_sided: bool) -> AreaLight {
    // rotate_x = 180 degrees turns local +z into world -z.
    let t = Transform::from_components(Vec3::new(a_x, a_y, 1.0), Vec3::new(180.0, 0.0, 0.0), Vec3::new(0.0, 0.0, h))
        .unwrap();
    let r = Rectangle::new(t);
    assert!((r.normal + Vec3::Z).length() < 1e-5);
    AreaLight::new(AreaShape::Rectangle(r), Rgb::splat(l), two_sided).unwrap()
}

/// Irradiance at a point below one corner of a parallel rectangle of sides
/// `x`, `y` at height `h` and radiance `l` (form factor of a differential
/// element to a parallel corner rectangle, times pi L):
/// `E = L/2 [ X/sqrt(X^2+h^2) atan(Y/sqrt(X^2+h^2)) + Y/sqrt(Y^2+h^2) atan(X/sqrt(Y^2+h^2)) ]`.
fn corner_rectangle_irradiance(x: f64, y: f64, h: f64, l: f64) -> f64 {
    let (rx, ry) = ((x * x + h * h).sqrt(), (y * y + h * h).sqrt());
    0.5 * l * (x / rx * (y / rx).atan() + y / ry * (x / ry).atan())
}

/// Brute force: E = L h^2 integral of (x^2 + y^2 + h^2)^-2 over the
/// rectangle [x0, x1] x [y0, y1] (receiver at the origin facing +z).
fn rectangle_irradiance_quadrature(x0: f64, x1: f64, y0: f64, y1: f64, h: f64, l: f64) -> f64 {
    let m = 1000;
    let (dx, dy) = ((x1 - x0) / m as f64, (y1 - y0) / m as f64);
    let mut sum = 0.0;
    for i in 0..m {
        let x = x0 + (i as f64 + 0.5) * dx;
        for j in 0..m {
            let y = y0 + (j as f64 + 0.5) * dy;
            sum += 1.0 / (x * x + y * y + h * h).powi(2);
        }
    }
    l * h * h * sum * dx * dy
}

/// Irradiance estimates `li cos / pdf` at `p` with normal `n`, plus the check
/// that every sample's pdf equals `pdf_li` of its direction.
fn irradiance_samples(light: &AreaLight, p: Vec3, n: Vec3, count: usize, key: u64) -> Vec<f64> {
    let mut rng = PixelSampler::from_key(key);
    (0..count)
        .map(|_| match light.sample_li(p, rng.next_2d()) {
            Some(s) => {
                let pdf = light.pdf_li(p, s.wi);
                assert!((pdf - s.pdf).abs() <= 1e-4 * s.pdf, "pdf_li {pdf} vs sample pdf {}", s.pdf);
                assert!(((s.p - p).length() - s.distance).abs() < 1e-4 * s.distance);
                s.li.g() as f64 * s.wi.dot(n).max(0.0) as f64 / s.pdf as f64
            }
            None => 0.0,
        })
        .collect()
}

#[test]
fn sphere_light_irradiance_matches_cap_formula() {
    // A sphere fully above the receiver's horizon: E = pi L (R/d)^2 cos(beta)
    // for a normal at angle beta to the center (Nusselt; beta = 0 is the cap
    // formula pi L sin^2(theta_max)). 1e5 samples each.
    let (r, d, l) = (1.0f32, 3.0f32, 2.5f32);
    let center = Vec3::new(0.3, -0.2, 0.5);
    let p = center - Vec3::new(0.0, 0.0, d);
    let light = sphere_light(center, r, l, false);
    for beta_deg in [0.0f32, 40.0] {
        let beta = beta_deg.to_radians();
        let n = Vec3::new(beta.sin(), 0.0, beta.cos());
        let exact = PI64 * l as f64 * (r as f64 / d as f64).powi(2) * (beta as f64).cos();
        let values = irradiance_samples(&light, p, n, 100_000, 301 + beta_deg as u64);
        assert_within_4_se(&format!("sphere cap irradiance, beta = {beta_deg} deg"), &values, exact);
    }
    // A distant sphere (small-cone branch, theta_max = 0.57 deg).
    let far = sphere_light(Vec3::new(0.0, 0.0, 100.0), 1.0, l, false);
    let values = irradiance_samples(&far, Vec3::ZERO, Vec3::Z, 20_000, 303);
    assert_within_4_se("distant sphere irradiance", &values, PI64 * l as f64 * 1e-4);
}

#[test]
fn inside_a_two_sided_sphere_irradiance_is_pi_l() {
    // Inside a sphere emitting L inward every hemisphere sees radiance L:
    // E = pi L for any point and normal. Area sampling, 1e5 samples.
    let l = 1.7f32;
    let light = sphere_light(Vec3::new(1.0, 2.0, 3.0), 2.0, l, true);
    let p = Vec3::new(1.5, 1.3, 3.6);
    let n = Vec3::new(-0.3, 0.8, 0.5).normalize();
    let values = irradiance_samples(&light, p, n, 100_000, 311);
    assert_within_4_se("inside two-sided sphere", &values, PI64 * l as f64);
    // One-sided: the inside is the back side, nothing arrives.
    let one_sided = AreaLight { two_sided: false, ..light };
    assert!(irradiance_samples(&one_sided, p, n, 1000, 312).iter().all(|v| *v == 0.0));
}

#[test]
fn corner_rectangle_formula_matches_quadrature() {
    for (x, y, h) in [(1.0, 1.0, 1.5), (0.6, 1.4, 0.7), (2.0, 0.3, 1.0)] {
        let closed = corner_rectangle_irradiance(x, y, h, 1.0);
        let brute = rectangle_irradiance_quadrature(0.0, x, 0.0, y, h, 1.0);
        eprintln!("corner rectangle {x} x {y} at h = {h}: closed form {closed:.8}, quadrature {brute:.8}");
        assert!((closed - brute).abs() < 1e-6 * closed, "{closed} vs {brute}");
    }
}

#[test]
fn rectangle_light_irradiance_matches_closed_form() {
    // Centered square of half-side a at height h: four corner rectangles,
    // E = 4 L a/sqrt(a^2+h^2) atan(a/sqrt(a^2+h^2)); and an off-center point
    // under a 2 x 1.2 rectangle, four unequal corner rectangles. 1e5 samples.
    let (a, h, l) = (1.0f64, 1.5f64, 2.0f64);
    let light = ceiling_rectangle(a as f32, a as f32, h as f32, l as f32, false);
    let ra = (a * a + h * h).sqrt();
    let exact = 4.0 * l * a / ra * (a / ra).atan();
    assert!((exact - 4.0 * corner_rectangle_irradiance(a, a, h, l)).abs() < 1e-12);
    let values = irradiance_samples(&light, Vec3::ZERO, Vec3::Z, 100_000, 321);
    assert_within_4_se("centered square irradiance", &values, exact);

    let (ax, ay, x0, y0) = (1.0f64, 0.6f64, 0.4f64, -0.3f64);
    let light = ceiling_rectangle(ax as f32, ay as f32, h as f32, l as f32, false);
    let exact = corner_rectangle_irradiance(ax - x0, ay - y0, h, l)
        + corner_rectangle_irradiance(ax + x0, ay - y0, h, l)
        + corner_rectangle_irradiance(ax - x0, ay + y0, h, l)
        + corner_rectangle_irradiance(ax + x0, ay + y0, h, l);
    let brute = rectangle_irradiance_quadrature(-ax - x0, ax - x0, -ay - y0, ay - y0, h, l);
    assert!((exact - brute).abs() < 1e-6 * exact, "{exact} vs {brute}");
    let p = Vec3::new(x0 as f32, y0 as f32, 0.0);
    let values = irradiance_samples(&light, p, Vec3::Z, 100_000, 322);
    assert_within_4_se("off-center rectangle irradiance", &values, exact);
}

#[test]
fn rectangle_back_side_emits_only_when_two_sided() {
    // Receiver above the ceiling light, facing down at it: one-sided sends
    // nothing; two-sided gives the same irradiance as the front.
    let (a, h, l) = (1.0f64, 1.5f64, 2.0f64);
    let p = Vec3::new(0.0, 0.0, 2.0 * h as f32);
    let one = ceiling_rectangle(a as f32, a as f32, h as f32, l as f32, false);
    let mut rng = PixelSampler::from_key(331);
    assert!((0..1000).all(|_| one.sample_li(p, rng.next_2d()).is_none()));
    let two = AreaLight { two_sided: true, ..one };
    let ra = (a * a + h * h).sqrt();
    let values = irradiance_samples(&two, p, -Vec3::Z, 50_000, 332);
    assert_within_4_se("two-sided rectangle from behind", &values, 4.0 * l * a / ra * (a / ra).atan());
}

#[test]
fn rectangle_directions_follow_pdf_li_chi_square() {
    // A tilted, sheared parallelogram seen from an off-axis point; 2e5
    // directions binned in 10 x 16 (cos, phi) cells of a cone around the
    // direction to its center that contains it; expected counts integrate
    // pdf_li by a 128 x 128 midpoint rule per cell (pdf_li jumps at the
    // light's edges; with 32 x 32 the quadrature error alone gave chi2 = 107
    // for 53 dof, with 128 x 128 it is below the sampling noise).
    let m = Mat3::from_cols(Vec3::new(0.8, 0.1, 0.0), Vec3::new(0.3, 0.5, 0.2), Vec3::new(0.0, 0.0, 1.0));
    let rot = Mat3::from_axis_angle(Vec3::new(1.0, 0.2, 0.0).normalize(), 2.5);
    let affine = glam::Affine3A::from_mat3_translation(rot * m, Vec3::new(0.4, -0.3, 1.2));
    let rect = Rectangle::new(Transform::new(affine).unwrap());
    let light = AreaLight::new(AreaShape::Rectangle(rect), Rgb::ONE, true).unwrap();
    let p = Vec3::new(1.1, 0.5, -0.2);
    let axis = (rect.transform.point_to_world(Vec3::ZERO) - p).normalize();
    let cos_min = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
        .iter()
        .map(|&(x, y)| (rect.transform.point_to_world(Vec3::new(x, y, 0.0)) - p).normalize().dot(axis))
        .fold(1.0f32, f32::min) as f64
        - 1e-3;
    let hist = ConeHistogram { frame: Frame::from_z(axis), cos_min, n_cos: 10, n_phi: 16 };
    let n = 200_000;
    let mut rng = PixelSampler::from_key(341);
    let samples: Vec<Vec3> = (0..n).map(|_| light.sample_li(p, rng.next_2d()).unwrap().wi).collect();
    let observed = hist.observed(samples.into_iter());
    let expected = hist.expected(n, 128, |w| light.pdf_li(p, w));
    assert!(expected[expected.len() - 1] < 0.01 * n as f64, "pdf_li does not integrate to ~1 over the cone");
    assert_chi2("rectangle directions", &observed, &expected);
}

#[test]
fn disk_directions_follow_pdf_li_chi_square() {
    // The same sheared placement as the rectangle's, for the unit disk (an
    // ellipse in the world): its directions lie in the cone around the
    // direction to its center that holds the circumscribed parallelogram.
    let m = Mat3::from_cols(Vec3::new(0.8, 0.1, 0.0), Vec3::new(0.3, 0.5, 0.2), Vec3::new(0.0, 0.0, 1.0));
    let rot = Mat3::from_axis_angle(Vec3::new(1.0, 0.2, 0.0).normalize(), 2.5);
    let affine = glam::Affine3A::from_mat3_translation(rot * m, Vec3::new(0.4, -0.3, 1.2));
    let disk = niebla::geometry::Disk::new(Transform::new(affine).unwrap());
    let light = AreaLight::new(AreaShape::Disk(disk), Rgb::ONE, true).unwrap();
    let p = Vec3::new(1.1, 0.5, -0.2);
    let axis = (light_center(&light) - p).normalize();
    let cos_min = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)]
        .iter()
        .map(|&(x, y)| (disk.transform.point_to_world(Vec3::new(x, y, 0.0)) - p).normalize().dot(axis))
        .fold(1.0f32, f32::min) as f64
        - 1e-3;
    let hist = ConeHistogram { frame: Frame::from_z(axis), cos_min, n_cos: 10, n_phi: 16 };
    let n = 200_000;
    let mut rng = PixelSampler::from_key(343);
    let samples: Vec<Vec3> = (0..n).map(|_| light.sample_li(p, rng.next_2d()).unwrap().wi).collect();
    let observed = hist.observed(samples.into_iter());
    let expected = hist.expected(n, 128, |w| light.pdf_li(p, w));
    assert!(expected[expected.len() - 1] < 0.01 * n as f64, "pdf_li does not integrate to ~1 over the cone");
    assert_chi2("disk directions", &observed, &expected);
}

#[test]
fn sphere_directions_follow_pdf_li_chi_square() {
    // Outside: uniform in the cone, 2e5 samples in 10 x 16 cells of the cone
    // itself (expected counts by quadrature of pdf_li, equal cells).
    let light = sphere_light(Vec3::new(0.2, 1.5, -0.4), 0.8, 1.0, false);
    let p = Vec3::new(-0.3, -0.4, 0.1);
    let to_center = light_center(&light) - p;
    let cos_max = (1.0 - (0.8 / to_center.length()).powi(2)).sqrt() as f64;
    let hist = ConeHistogram { frame: Frame::from_z(to_center.normalize()), cos_min: cos_max, n_cos: 10, n_phi: 16 };
    let n = 200_000;
    let mut rng = PixelSampler::from_key(351);
    let wis: Vec<Vec3> = (0..n).map(|_| light.sample_li(p, rng.next_2d()).unwrap().wi).collect();
    let expected = hist.expected(n, 16, |w| light.pdf_li(p, w));
    assert_chi2("sphere cone directions", &hist.observed(wis.into_iter()), &expected);

    // Inside a two-sided sphere: area sampling, directions over the whole
    // sphere of directions (cone with cos_min = -1).
    let light = sphere_light(Vec3::ZERO, 1.0, 1.0, true);
    let p = Vec3::new(0.5, 0.3, -0.2);
    let hist = ConeHistogram {
        frame: Frame::from_z(Vec3::new(0.3, -0.5, 0.8).normalize()),
        cos_min: -1.0,
        n_cos: 10,
        n_phi: 16,
    };
    let wis: Vec<Vec3> = (0..n).map(|_| light.sample_li(p, rng.next_2d()).unwrap().wi).collect();
    let expected = hist.expected(n, 16, |w| light.pdf_li(p, w));
    assert_chi2("sphere interior directions", &hist.observed(wis.into_iter()), &expected);
}

fn light_center(light: &AreaLight) -> Vec3 {
    match light.shape {
        AreaShape::Sphere(s) => s.center,
        AreaShape::Rectangle(r) => r.transform.point_to_world(Vec3::ZERO),
        AreaShape::Disk(d) => d.transform.point_to_world(Vec3::ZERO),
        AreaShape::Mesh(_) => unreachable!("these tests place no mesh lights (see mesh_lights.rs)"),
    }
}

#[test]
fn pdf_li_is_zero_for_directions_that_miss() {
    let sphere = sphere_light(Vec3::new(0.0, 0.0, 5.0), 1.0, 1.0, false);
    assert_eq!(sphere.pdf_li(Vec3::ZERO, Vec3::X), 0.0);
    assert_eq!(sphere.pdf_li(Vec3::ZERO, -Vec3::Z), 0.0);
    let rect = ceiling_rectangle(1.0, 1.0, 1.0, 1.0, false);
    assert_eq!(rect.pdf_li(Vec3::ZERO, Vec3::new(0.9, 0.0, 0.1).normalize()), 0.0);
    assert_eq!(rect.pdf_li(Vec3::ZERO, -Vec3::Z), 0.0);
    // Straight up at the center: pdf = h^2 / area.
    assert!((rect.pdf_li(Vec3::ZERO, Vec3::Z) - 0.25).abs() < 1e-6);
}
