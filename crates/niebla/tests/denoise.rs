//! Denoising with Intel Open Image Denoise: a missing library is a clear
//! error, and the denoised image of a low-spp render is closer to a
//! high-spp reference than the raw one. The library is loaded from
//! `NIEBLA_OIDN_LIBRARY` (scripts/test.sh installs it from PyPI's `pyoidn`
//! and sets `NIEBLA_REQUIRE_OIDN=1`, so there the test cannot skip).

use niebla::aov::{Aov, AovSet};
use niebla::denoise::{DenoiseError, Denoiser};
use niebla::integrator::{registry, PreparedIntegrator};
use niebla::render::RenderOptions;
use niebla::sampling::SamplerKind;
use niebla::scene::{build_scene, parse_scene_str};

#[test]
fn a_missing_library_is_a_clear_error() {
    let err = Denoiser::load_from(std::path::Path::new("/nonexistent/libOpenImageDenoise.so.2")).unwrap_err();
    assert!(matches!(err, DenoiseError::Missing { .. }), "{err}");
    let message = err.to_string();
    assert!(
        message.contains("/nonexistent/libOpenImageDenoise.so.2") && message.contains("pip install pyoidn"),
        "{message}"
    );
}

/// The OIDN library, or `None` (test skipped) when it is not installed and
/// not required.
fn denoiser() -> Option<Denoiser> {
    match Denoiser::load() {
        Ok(d) => Some(d),
        Err(e) if std::env::var_os("NIEBLA_REQUIRE_OIDN").is_some() => panic!("{e}"),
        Err(e) => {
            eprintln!("skipped: {e}");
            None
        }
    }
}

#[test]
fn denoising_lowers_the_error_against_a_high_spp_reference() {
    let Some(denoiser) = denoiser() else {
        return;
    };
    let text = r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 0.6, 0], "width": 64, "height": 48},
        "media": {"fog": {"type": "homogeneous", "sigma_t": 2, "albedo": 0.9, "phase": {"type": "hg", "g": 0.3}}},
        "shapes": [{"type": "sphere", "center": [0, 0.7, 0], "radius": 0.7, "interior": "fog"},
                   {"type": "rectangle", "to_world": {"scale": 4, "rotate_x": -90}, "bsdf": {"type": "diffuse", "reflectance": 0.6}}],
        "lights": [{"type": "point", "position": [1, 2.5, 1], "intensity": 8}, {"type": "constant", "radiance": 0.3}]}"#;
    let desc = parse_scene_str(text, "denoise.json").unwrap();
    let built = build_scene(&desc, "denoise.json", std::path::Path::new(".")).unwrap();
    let scene = &built.scene;
    let volpath = registry::defaults("volpath").unwrap();
    let prepared = PreparedIntegrator::new(scene, &volpath);
    let render = |spp: u32, seed: u64| {
        let options = RenderOptions { spp, seed, first_sample: 0, threads: None, sampler: SamplerKind::Sobol };
        let set = AovSet::EMPTY.with(Aov::Albedo).with(Aov::Normal);
        let (sums, layers) = prepared.render_aov_sums(scene, &options, set, &|_, _| {}, None).unwrap();
        (sums.mean(spp as u64), layers.layers(&sums, spp as u64))
    };
    let (reference, _) = render(1024, 1);
    let (raw, layers) = render(4, 2);
    let (raw_4x, _) = render(16, 3);
    let n = raw.pixels.len();
    let albedo: Vec<_> = (0..n).map(|i| layers.get(Aov::Albedo).unwrap().rgb(i)).collect();
    let normal: Vec<[f32; 3]> = (0..n).map(|i| layers.get(Aov::Normal).unwrap().vec3(i).to_array()).collect();
    let denoised = denoiser.denoise(&raw, Some(&albedo), Some(&normal)).unwrap();
    let color_only = denoiser.denoise(&raw, None, None).unwrap();
    let (e_raw, e_den, e_col, e_4x) = (
        raw.relative_mse(&reference),
        denoised.relative_mse(&reference),
        color_only.relative_mse(&reference),
        raw_4x.relative_mse(&reference),
    );
    eprintln!("relative MSE vs 1024 spp: raw 4 spp {e_raw:.4e}, raw 16 spp {e_4x:.4e}, denoised 4 spp with albedo+normal {e_den:.4e}, color only {e_col:.4e}");
    // The reference's own noise adds the same to every error measured here.
    assert!(e_den < 0.5 * e_raw, "denoised {e_den} not below half the raw {e_raw}");
    assert!(denoised.pixels.iter().all(|p| p.is_finite()));
}

/// The figures of the report (run by hand, about a minute per scene on two
/// cores): on the bench scenes whose data needs no download (fog_spot,
/// fog_point, milk_cube) at 128 x 128, the relative MSE against a 512 spp
/// reference of raw renders at 4, 16 and 64 spp and of denoised renders at
/// 4 and 16 spp, with their times.
/// `NIEBLA_OIDN_LIBRARY=... cargo test -p niebla --test denoise -- --ignored --nocapture`
#[test]
#[ignore]
fn denoise_figures_on_bench_scenes() {
    let denoiser = Denoiser::load().unwrap_or_else(|e| panic!("{e}"));
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../bench/scenes");
    for name in ["fog_spot", "fog_point", "milk_cube"] {
        let path = dir.join(format!("{name}.json"));
        let text = std::fs::read_to_string(&path).unwrap();
        let mut desc = parse_scene_str(&text, &path.display().to_string()).unwrap();
        let niebla::scene::CameraDesc::Perspective(camera) = &mut desc.camera;
        (camera.width, camera.height) = (128, 128);
        let built = build_scene(&desc, name, &dir).unwrap();
        let (scene, settings) = (&built.scene, built.settings.integrator);
        let prepared = PreparedIntegrator::new(scene, &settings);
        let set = AovSet::EMPTY.with(Aov::Albedo).with(Aov::Normal);
        let render = |spp: u32, seed: u64| {
            let options = RenderOptions { spp, seed, first_sample: 0, threads: None, sampler: SamplerKind::Sobol };
            let start = std::time::Instant::now();
            let (sums, layers) = prepared.render_aov_sums(scene, &options, set, &|_, _| {}, None).unwrap();
            (sums.mean(spp as u64), layers.layers(&sums, spp as u64), start.elapsed().as_secs_f64())
        };
        let (reference, _, t_ref) = render(512, 1);
        let mut line = format!("{name}: reference 512 spp {t_ref:.1} s;");
        for spp in [4, 16, 64] {
            let (raw, layers, t) = render(spp, 2);
            line += &format!(" raw {spp} spp {:.3e} ({t:.2} s)", raw.relative_mse(&reference));
            if spp <= 16 {
                let n = raw.pixels.len();
                let albedo: Vec<_> = (0..n).map(|i| layers.get(Aov::Albedo).unwrap().rgb(i)).collect();
                let normal: Vec<[f32; 3]> =
                    (0..n).map(|i| layers.get(Aov::Normal).unwrap().vec3(i).to_array()).collect();
                let start = std::time::Instant::now();
                let denoised = denoiser.denoise(&raw, Some(&albedo), Some(&normal)).unwrap();
                let td = start.elapsed().as_secs_f64();
                line += &format!(", denoised {:.3e} (+{td:.2} s);", denoised.relative_mse(&reference));
            }
        }
        eprintln!("{line}");
    }
}
