//! Where the `hegeman` integrator's error lives: relative MSE against a
//! `volpath` reference (as [`niebla::film::Image::relative_mse`]) split by
//! pixel class: camera rays that hit a surface (`floor`), that pass within
//! `NEAR` (m) of a point light before ending (`near light`), and the rest
//! (`medium`, rays that leave the scene). Each class's share is its
//! contribution to the whole image's relative MSE, so the shares add up to
//! it; `mean/ref` is the class's mean radiance over the reference's.
//!
//! `cargo run --release -p niebla --example hegeman_error_classes -- SCENE [WIDTH] [REF_SPP] [OUT_DIR]`
//!
//! The reference is cached as `OUT_DIR/reference-WIDTH-REF_SPP.exr` (default
//! OUT_DIR: the system temp folder); every method's image and its per-pixel
//! relative error are written beside it as EXRs and PNGs (error: red where
//! too bright, green where too dark). With `NOISE_FLOOR` set, a second
//! reference of another seed is measured too (the reference's own noise).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use niebla::film::{read_exr, write_exr, write_png, Image};
use niebla::integrator::hegeman::{Calibration, SurfaceScattering};
use niebla::integrator::{HegemanIntegrator, HegemanSettings, Integrator, IntegratorSettings, VolPathIntegrator};
use niebla::light::Light;
use niebla::math::{Vec2, Vec3};
use niebla::render::{render_with, RenderOptions};
use niebla::world::Scene;

/// Distance (m) from a point light within which a camera ray counts as "near" it.
const NEAR: f32 = 0.35;

fn render<I: Integrator>(scene: &Scene, integrator: &I, spp: u32, seed: u64) -> Image {
    let options = RenderOptions { spp, seed, first_sample: 0, threads: None, sampler: Default::default() };
    render_with(scene, integrator, &options, &|_, _| {}, None).expect("render without cancel flag")
}

/// 0 floor (surface hit), 1 near a point light, 2 the rest.
fn classes(scene: &Scene) -> Vec<usize> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let lights: Vec<Vec3> = scene
        .lights
        .iter()
        .filter_map(|l| match l {
            Light::Point(p) => Some(p.position),
            Light::Spot(s) => Some(s.position),
            _ => None,
        })
        .collect();
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let ray = scene.camera.generate_ray(x, y, Vec2::new(0.5, 0.5));
            let hit = scene.intersect(&ray, 1e-4, f32::INFINITY);
            let t_end = hit.as_ref().map_or(f32::INFINITY, |h| h.local.t);
            let near = lights.iter().any(|&p| {
                let t = (p - ray.o).dot(ray.d).clamp(0.0, t_end);
                (ray.at(t) - p).length() < NEAR
            });
            out.push(if near {
                1
            } else if hit.is_some() {
                0
            } else {
                2
            });
        }
    }
    out
}

fn report(name: &str, image: &Image, reference: &Image, class: &[usize], out: &Path) {
    let mean = reference.mean().average() as f64;
    let eps = (0.01 * mean).powi(2).max(f64::MIN_POSITIVE);
    let n = image.pixels.len() as f64 * 3.0;
    let mut share = [0f64; 3];
    let mut count = [0usize; 3];
    let mut sums = [[0f64; 2]; 3];
    let mut error = Image::new(image.width, image.height);
    for (i, ((a, b), &c)) in image.pixels.iter().zip(&reference.pixels).zip(class).enumerate() {
        let mut e = 0.0;
        for k in 0..3 {
            let (x, r) = (a[k] as f64, b[k] as f64);
            e += (x - r).powi(2) / (r * r + eps);
            sums[c][0] += x;
            sums[c][1] += r;
        }
        share[c] += e / n;
        count[c] += 1;
        let signed = if a.average() >= b.average() { e / 3.0 } else { -e / 3.0 };
        error.pixels[i] = niebla::color::Rgb::new(signed.max(0.0) as f32, (-signed).max(0.0) as f32, 0.0);
    }
    let total: f64 = share.iter().sum();
    print!("{name:<24} rel MSE {total:8.4} |");
    for (c, label) in ["floor", "near light", "medium"].iter().enumerate() {
        let ratio = if sums[c][1] > 0.0 { sums[c][0] / sums[c][1] } else { 0.0 };
        print!(" {label} {:5} px {:8.4} mean/ref {:6.3} |", count[c], share[c], ratio);
    }
    println!();
    let file = name.replace([' ', '(', ')'], "_");
    let _ = write_exr(image, &out.join(format!("{file}.exr")));
    let _ = write_exr(&error, &out.join(format!("{file}-error.exr")));
    let _ = write_png(image, &out.join(format!("{file}.png")), 2.0);
    let _ = write_png(&error, &out.join(format!("{file}-error.png")), 0.0);
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        eprintln!("usage: hegeman_error_classes SCENE [WIDTH] [REF_SPP] [OUT_DIR]");
        return ExitCode::from(2);
    };
    let width: u32 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(96);
    let reference_spp: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(256);
    let out = args.get(3).map_or_else(std::env::temp_dir, PathBuf::from);
    let built = match niebla::scene::load_scene(Path::new(path)) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    let mut scene = built.scene;
    let aspect = scene.camera.height as f64 / scene.camera.width as f64;
    scene.camera.width = width;
    scene.camera.height = ((width as f64 * aspect).round() as u32).max(1);
    let cached = out.join(format!(
        "reference-{}-{width}-{reference_spp}.exr",
        Path::new(path).file_stem().unwrap_or_default().to_string_lossy()
    ));
    let reference = match read_exr(&cached) {
        Ok(r) if (r.image.width, r.image.height) == (scene.camera.width, scene.camera.height) => r.image,
        _ => {
            let r = render(&scene, &VolPathIntegrator::new(256), reference_spp, 1_000_003);
            let _ = write_exr(&r, &cached);
            r
        }
    };
    let _ = write_png(&reference, &out.join("reference.png"), 2.0);
    let class = classes(&scene);
    if std::env::var_os("NOISE_FLOOR").is_some() {
        // A second reference of another seed: its error is the reference noise (twice its variance).
        let second = render(&scene, &VolPathIntegrator::new(256), reference_spp, 2_000_003);
        report("volpath (second seed)", &second, &reference, &class, &out);
    }
    let file_settings = match built.settings.integrator {
        IntegratorSettings::Hegeman(h) => h,
        _ => HegemanSettings::default(),
    };
    for (name, multiple, calibration, surface) in [
        ("hegeman", true, Calibration::None, SurfaceScattering::Cone),
        ("hegeman (line surfaces)", true, Calibration::None, SurfaceScattering::Line),
        ("hegeman (unlit surfaces)", true, Calibration::None, SurfaceScattering::Off),
        ("hegeman (mc_tables)", true, Calibration::McTables, SurfaceScattering::Cone),
        ("hegeman (mc_tables unlit)", true, Calibration::McTables, SurfaceScattering::Off),
        ("hegeman (mc_fluence)", true, Calibration::McFluence, SurfaceScattering::Cone),
        ("hegeman (single only)", false, Calibration::None, SurfaceScattering::Off),
    ] {
        let settings = HegemanSettings {
            multiple_scattering: multiple,
            calibration,
            surface_scattering: surface,
            ..file_settings
        };
        let integrator = HegemanIntegrator::new(&scene, settings);
        report(name, &render(&scene, &integrator, 16, 7), &reference, &class, &out);
    }
    ExitCode::SUCCESS
}
