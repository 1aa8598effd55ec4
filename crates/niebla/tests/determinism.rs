//! The same scene, seed and spp give a bit-identical image with 1, 2 and 8
//! threads, for every integrator and both samplers (the random numbers of sample `s` of pixel
//! `(x, y)` depend only on (seed, x, y, s)); integrators documented as depending on the
//! thread count (photon maps built in parallel) are bit-identical at a fixed
//! thread count instead.

use std::path::Path;

use niebla::film::Image;
use niebla::integrator::IntegratorSettings;
use niebla::render::{render, RenderOptions};
use niebla::sampling::SamplerKind;
use niebla::scene::{build_scene, integrator_settings, parse_scene_str, BuiltScene, DEFAULT_SCENE};

/// Integrators whose images may change with the thread count (their docs say
/// so); they must still repeat exactly at a fixed thread count.
const THREAD_COUNT_DEPENDENT: &[&str] = &["photon", "ppm"];

/// Every integrator name with its scene-file defaults, and `single` in each
/// sampling. Names whose defaults do not parse yet are reported and skipped.
fn all_integrators() -> Vec<(String, IntegratorSettings)> {
    let mut descs: Vec<(String, String)> =
        IntegratorSettings::NAMES.iter().map(|n| (n.to_string(), format!(r#"{{"type": "{n}"}}"#))).collect();
    for sampling in ["march", "equiangular", "mis"] {
        descs.push(("single".into(), format!(r#"{{"type": "single", "sampling": "{sampling}"}}"#)));
    }
    descs.push(("single".into(), r#"{"type": "single", "sampling": "mis", "transmittance": "delta"}"#.into()));
    let mut out = Vec::new();
    for (name, d) in descs {
        let line = r#"{"type": "single", "sampling": "mis"}"#;
        assert!(DEFAULT_SCENE.contains(line), "the default scene's integrator line changed");
        let text = DEFAULT_SCENE.replacen(line, &d, 1);
        match parse_scene_str(&text, "integrators.json") {
            Ok(desc) => out.push((name, integrator_settings(&desc.render.integrator))),
            Err(e) => eprintln!("skipping integrator {d}: its defaults do not parse: {e}"),
        }
    }
    assert!(out.len() >= 8, "expected at least emission, single x 4, volpath, analytic: {out:?}");
    out
}

/// The default scene, a grid medium (trackers, majorant DDA) lit by a spot
/// light, and bench/scenes/fog_point.json (a point lamp in fog next to
/// diffuse objects: `volpath`'s lamp guide and its directions toward the
/// lit objects), all at a size that is not a multiple of the tile size.
fn scenes() -> Vec<(&'static str, BuiltScene)> {
    let grid = r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0.5, 0.6, 3], "target": [0.5, 0.5, 0.5], "width": 8, "height": 8},
        "media": {"cloud": {"type": "grid", "sigma_t": 6, "albedo": 0.9, "phase": {"type": "hg", "g": 0.3},
                            "density": {"type": "procedural", "shape": "cloud", "resolution": 24, "seed": 3}}},
        "shapes": [{"type": "box", "min": [0, 0, 0], "max": [1, 1, 1], "interior": "cloud"}],
        "lights": [{"type": "spot", "position": [0.5, 3, 0.5], "target": [0.5, 0, 0.5], "intensity": 30,
                    "cutoff_angle": 30, "beam_width": 20},
                   {"type": "constant", "radiance": 0.1}]}"#;
    let mut out = Vec::new();
    let fog_point = include_str!("../../../bench/scenes/fog_point.json");
    for (name, text) in [("default", DEFAULT_SCENE), ("grid", grid), ("fog_point", fog_point)] {
        let desc = parse_scene_str(text, name).unwrap();
        let mut built = build_scene(&desc, name, Path::new(".")).unwrap();
        built.scene.camera.width = 37; // not a multiple of the tile size
        built.scene.camera.height = 21;
        out.push((name, built));
    }
    out
}

fn bits(image: &Image) -> Vec<[u32; 3]> {
    image.pixels.iter().map(|p| p.0.map(f32::to_bits)).collect()
}

#[test]
fn image_is_bit_identical_for_any_thread_count() {
    let integrators = all_integrators();
    for (scene_name, built) in scenes() {
        for ((name, settings), sampler) in integrators.iter().flat_map(|i| SamplerKind::ALL.map(|s| (i, s))) {
            let run = |threads: usize, seed: u64| {
                let options = RenderOptions { spp: 3, seed, first_sample: 0, threads: Some(threads), sampler };
                render(&built.scene, settings, &options, &|_, _| {}, None).unwrap()
            };
            let reference = run(1, 42);
            let others: &[usize] = if THREAD_COUNT_DEPENDENT.contains(&name.as_str()) { &[1] } else { &[2, 8] };
            for &threads in others {
                assert!(
                    bits(&run(threads, 42)) == bits(&reference),
                    "{scene_name} scene, {settings:?}, {sampler:?}: {threads} threads differ from 1 thread"
                );
            }
            // A different seed changes the image (the seed is really used),
            // where the integrator is random at all in this scene.
            if reference.mean().max_channel() > 0.0 && !matches!(settings, IntegratorSettings::Analytic) {
                assert_ne!(
                    bits(&run(2, 43)),
                    bits(&reference),
                    "{scene_name} scene, {settings:?}, {sampler:?}: seed unused"
                );
            }
        }
    }
}
