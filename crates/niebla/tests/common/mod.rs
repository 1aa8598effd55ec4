//! Helpers shared by the integration tests: scenes built directly from runtime
//! types, reference CSV reading, and Monte Carlo statistics.
#![allow(dead_code)]

use niebla::camera::PerspectiveCamera;
use niebla::color::Rgb;
use niebla::light::Light;
use niebla::math::Vec3;
use niebla::medium::{HomogeneousMedium, Medium, MediumId};
use niebla::phase::PhaseFunction;
use niebla::scene::{Scene, SceneObject};

/// Rows of a reference CSV (comment lines start with '#', then a header).
pub fn read_reference_csv(name: &str) -> Vec<std::collections::HashMap<String, String>> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/reference").join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty());
    let header: Vec<String> = lines.next().unwrap().split(',').map(|s| s.trim().to_string()).collect();
    lines.map(|l| header.iter().cloned().zip(l.split(',').map(|s| s.trim().to_string())).collect()).collect()
}

/// A parsed float field (`inf` allowed).
pub fn field(row: &std::collections::HashMap<String, String>, key: &str) -> f64 {
    let v = &row[key];
    if v == "inf" {
        f64::INFINITY
    } else {
        v.parse().unwrap_or_else(|_| panic!("{key} = {v}"))
    }
}

/// A homogeneous medium from sigma_a, sigma_s (gray), emission and phase.
/// Runtime types do not validate, so tests may build the non-physical
/// `sigma_a < 0` needed for "attenuation neglected" reference rows.
pub fn homogeneous(sigma_a: f32, sigma_s: f32, l_ve: Rgb, phase: PhaseFunction) -> Medium {
    Medium::Homogeneous(HomogeneousMedium { sigma_a: Rgb::splat(sigma_a), sigma_s: Rgb::splat(sigma_s), l_ve, phase })
}

/// A scene made of its parts, with bounds from the camera, shapes and lights.
pub fn scene(
    camera: PerspectiveCamera,
    objects: Vec<SceneObject>,
    media: Vec<Medium>,
    lights: Vec<Light>,
    ambient: Option<MediumId>,
) -> Scene {
    let mut lo = camera.position;
    let mut hi = camera.position;
    for o in &objects {
        let (a, b) = o.shape.bounds();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    for l in &lights {
        if let Some(p) = l.point_position() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    let names = (0..media.len()).map(|i| format!("m{i}")).collect();
    let mut s = Scene {
        camera,
        objects,
        media,
        medium_names: names,
        lights,
        ambient_medium: ambient,
        camera_medium: None,
        bounds: (lo, hi),
        accel: Default::default(),
        transparent_background: false,
    };
    s.camera_medium = s.medium_at(s.camera.position);
    s
}

/// A camera at the origin looking along +x.
pub fn camera_along_x(width: u32, height: u32, fov_y: f32) -> PerspectiveCamera {
    PerspectiveCamera::look_at(Vec3::ZERO, Vec3::X, Vec3::Y, fov_y, width, height).unwrap()
}

/// Running mean and standard error of a scalar estimator.
#[derive(Default, Clone, Copy, Debug)]
pub struct Stats {
    n: u64,
    sum: f64,
    sum2: f64,
}

impl Stats {
    pub fn add(&mut self, x: f64) {
        self.n += 1;
        self.sum += x;
        self.sum2 += x * x;
    }
    pub fn mean(&self) -> f64 {
        self.sum / self.n as f64
    }
    /// Standard error of the mean.
    pub fn standard_error(&self) -> f64 {
        let m = self.mean();
        ((self.sum2 / self.n as f64 - m * m).max(0.0) / self.n as f64).sqrt()
    }
}

/// Mean and standard error, per channel, of the mean over the `size` x
/// `size` block at pixel `(x0, y0)` of each render (the renders are
/// independent batches, so their block means are independent samples).
pub fn block_stats(images: &[niebla::film::Image], x0: u32, y0: u32, size: u32) -> [(f64, f64); 3] {
    let n = images.len() as f64;
    std::array::from_fn(|c| {
        let values: Vec<f64> = images
            .iter()
            .map(|im| {
                let mut s = 0.0;
                for y in y0..y0 + size {
                    for x in x0..x0 + size {
                        s += im.pixels[(y * im.width + x) as usize][c] as f64;
                    }
                }
                s / f64::from(size * size)
            })
            .collect();
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
        (mean, (var / n).sqrt())
    })
}

/// Mean and standard error of the mean of independent samples.
pub fn mean_se(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Irradiance at `x` (receiver normal `n_r`) from triangles of radiance 1
/// that emit on the side of their interpolated vertex normals, by the
/// midpoint rule over `m x m` sub-triangles of equal area per triangle
/// (`b1 = t sqrt(s)`, `b2 = 1 - sqrt(s)` at the midpoints `(s, t)` of the
/// unit square). Each triangle is its corners `[a, b, c]` and their vertex
/// normals, its geometric normal `(b - a) x (c - a)`, which every vertex
/// normal must lean toward. Returns the irradiance with the geometric
/// normal's cosine in the area-to-solid-angle conversion (the physical
/// value) and with the interpolated normal's.
pub fn smooth_mesh_irradiance(
    triangles: &[([glam::DVec3; 3], [glam::DVec3; 3])],
    x: glam::DVec3,
    n_r: glam::DVec3,
    m: usize,
) -> (f64, f64) {
    let (mut geometric, mut shading) = (0.0, 0.0);
    for &([a, b, c], [na, nb, nc]) in triangles {
        let cross = (b - a).cross(c - a);
        let (area, ng) = (0.5 * cross.length(), cross.normalize());
        let (mut sum_g, mut sum_s) = (0.0, 0.0);
        for i in 0..m {
            for j in 0..m {
                let (s, t) = ((i as f64 + 0.5) / m as f64, (j as f64 + 0.5) / m as f64);
                let (b1, b2) = (t * s.sqrt(), 1.0 - s.sqrt());
                let b0 = 1.0 - b1 - b2;
                let p = a * b0 + b * b1 + c * b2;
                let ns = (na * b0 + nb * b1 + nc * b2).normalize();
                assert!(ns.dot(ng) > 0.0, "a vertex normal on the other side of its triangle");
                let d = p - x;
                let r2 = d.length_squared();
                let w = d / r2.sqrt();
                let cos_r = n_r.dot(w);
                // Emits toward the receiver only on its normal's side.
                if ns.dot(-w) > 0.0 && cos_r > 0.0 {
                    sum_g += cos_r * ng.dot(w).abs() / r2;
                    sum_s += cos_r * ns.dot(w).abs() / r2;
                }
            }
        }
        geometric += sum_g * area / (m * m) as f64;
        shading += sum_s * area / (m * m) as f64;
    }
    (geometric, shading)
}
