//! Every integrator gives finite pixels on adversarial but valid scenes:
//! asymmetry at the edge of what the validator accepts (|g| just below 1,
//! and 0.999), albedo exactly 0 and 1, extinctions of 1e6 and 1e-12
//! (directly and through a grid's `scale`), lights on and inside medium
//! boundaries, rays grazing box faces, and cameras exactly on a boundary.
//!
//! In debug builds the render loop and the accumulator also assert
//! finiteness per sample; this test checks the images in any build (a
//! release build drops non-finite samples, so a dropped sample shows here
//! only as an assertion failure in debug builds).

use std::path::Path;

use niebla::integrator::IntegratorSettings;
use niebla::progressive::Accumulator;
use niebla::render::{render_sums, RenderOptions};
use niebla::scene::{build_scene, parse_scene_str, BuiltScene};

/// The largest f32 below 1: the validator's open interval (-1, 1) admits it.
const G_MAX: f32 = 0.99999994;

/// One integrator per name in `IntegratorSettings::NAMES` with its file
/// defaults, plus `single` in each of its samplings and with delta tracking.
/// Names whose defaults do not parse are reported and skipped (so a newly
/// added integrator with required parameters does not break this test
/// silently: the message names it).
fn all_integrators() -> Vec<(String, IntegratorSettings)> {
    // Cheaper than the defaults where an integrator has a costly setup
    // (photon maps, lattices); tried first, the defaults if they do not parse.
    let cheap = |name: &str| match name {
        "photon" | "ppm" | "ppb" => r#", "photons": 2000"#,
        "hegeman" => r#", "resolution": 8"#,
        _ => "",
    };
    let mut descs: Vec<(String, String)> = IntegratorSettings::NAMES
        .iter()
        .map(|n| (format!(r#"{{"type": "{n}"{}}}"#, cheap(n)), format!(r#"{{"type": "{n}"}}"#)))
        .collect();
    let mut add = |d: &str| descs.push((d.to_string(), d.to_string()));
    for sampling in ["march", "equiangular", "mis"] {
        add(&format!(r#"{{"type": "single", "sampling": "{sampling}"}}"#));
    }
    add(r#"{"type": "single", "sampling": "mis", "transmittance": "delta"}"#);
    add(r#"{"type": "emission", "transmittance": "ratio"}"#);
    add(r#"{"type": "photon", "photons": 2000, "query": "beam"}"#);
    let mut out = Vec::new();
    for (d, fallback) in descs {
        let parse = |d: &str| {
            let text = scene_text(r#""m": {"sigma_t": 1, "albedo": 0.5}"#, "", "", [0.0, 0.0, 5.0], d);
            parse_scene_str(&text, "integrators.json")
        };
        match parse(&d).or_else(|_| parse(&fallback)) {
            Ok(desc) => out.push((d, niebla::scene::integrator_settings(&desc.render.integrator))),
            Err(e) => eprintln!("skipping integrator {d}: its defaults do not parse: {e}"),
        }
    }
    assert!(out.len() >= 9, "expected at least emission, single x 3, volpath, analytic: {out:?}");
    out
}

/// A scene: media `media`, extra shapes and lights (JSON fragments that
/// follow the defaults), a camera at `eye` looking at the origin.
fn scene_text(media: &str, shapes: &str, lights: &str, eye: [f32; 3], integrator: &str) -> String {
    let comma = |s: &str| if s.is_empty() { String::new() } else { format!(", {s}") };
    format!(
        r#"{{"version": 1,
            "camera": {{"type": "perspective", "position": [{}, {}, {}], "target": [0, 0, 0.01],
                       "fov_y": 60, "width": 10, "height": 8}},
            "render": {{"integrator": {integrator}, "spp": 4, "seed": 7}},
            "media": {{{media}}},
            "shapes": [{{"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "interior": "m"}},
                       {{"type": "rectangle", "to_world": {{"scale": 4, "rotate_x": -90, "translate": [0, -1, 0]}},
                         "bsdf": {{"type": "diffuse", "reflectance": 0.5}}}}{}],
            "lights": [{{"type": "point", "position": [0.3, 0.5, 0.2], "intensity": 5}},
                       {{"type": "spot", "position": [0, 3, 0], "target": [0, 0, 0], "intensity": 20,
                         "cutoff_angle": 30, "beam_width": 20}},
                       {{"type": "directional", "direction": [0.3, -1, 0.2], "irradiance": 1}},
                       {{"type": "constant", "radiance": 0.1}}{}]}}"#,
        eye[0],
        eye[1],
        eye[2],
        comma(shapes),
        comma(lights)
    )
}

fn build(text: &str, name: &str) -> BuiltScene {
    let desc = parse_scene_str(text, name).unwrap_or_else(|e| panic!("{name}: {e}\n{text}"));
    build_scene(&desc, name, Path::new(".")).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Adversarial cases: (name, media, shapes, lights, eye).
fn cases() -> Vec<(String, String, String, String, [f32; 3])> {
    let mut cases = Vec::new();
    let mut add = |name: String, media: String, shapes: &str, lights: &str, eye: [f32; 3]| {
        cases.push((name, media, shapes.to_string(), lights.to_string(), eye));
    };
    let eye = [0.0, 0.2, 4.0];
    // Phase functions at the edges of their parameter ranges.
    for g in [G_MAX, -G_MAX, 0.999, -0.999] {
        for phase in [
            format!(r#"{{"type": "hg", "g": {g}}}"#),
            format!(r#"{{"type": "schlick", "g": {g}}}"#),
            format!(r#"{{"type": "cornette_shanks", "g": {g}}}"#),
            format!(r#"{{"type": "double_hg", "g1": {g}, "g2": {}, "w": 0.5}}"#, -g),
        ] {
            let media = format!(r#""m": {{"sigma_t": 2, "albedo": 0.9, "phase": {phase}}}"#);
            add(format!("phase {phase}"), media, "", "", eye);
        }
    }
    // Albedo exactly 0 and 1, with and without emission.
    for albedo in [0.0, 1.0] {
        add(format!("albedo {albedo}"), format!(r#""m": {{"sigma_t": 3, "albedo": {albedo}}}"#), "", "", eye);
        add(
            format!("albedo {albedo}, emitting"),
            format!(r#""m": {{"sigma_t": 3, "albedo": {albedo}, "emission": {{"L_ve": 2}}}}"#),
            "",
            "",
            eye,
        );
    }
    // Extinction of 1e6 and 1e-12, homogeneous and as a grid's scale.
    for sigma_t in [1e6, 1e-12] {
        add(format!("sigma_t {sigma_t}"), format!(r#""m": {{"sigma_t": {sigma_t}, "albedo": 0.8}}"#), "", "", eye);
        add(
            format!("sigma_t {sigma_t} rgb"),
            format!(r#""m": {{"sigma_a": [{sigma_t}, 0, 1], "sigma_s": [0, {sigma_t}, 0.5]}}"#),
            "",
            "",
            eye,
        );
        let grid = format!(
            r#""m": {{"type": "grid", "sigma_t": 1, "albedo": 0.7, "scale": {sigma_t},
                     "density": {{"type": "grid", "dims": [2, 2, 2], "data": [0, 1, 2, 0, 1, 0, 3, 1],
                                  "bounds": {{"min": [-1, -1, -1], "max": [1, 1, 1]}}}}}}"#
        );
        add(format!("grid scale {sigma_t}"), grid, "", "", eye);
    }
    // Lights on the medium's boundary, inside it, and at a corner.
    let on_face = r#"{"type": "point", "position": [1, 0, 0], "intensity": 3}"#;
    let at_corner = r#"{"type": "point", "position": [1, 1, 1], "intensity": 3}"#;
    let spot_inside = r#"{"type": "spot", "position": [0, 0.99, 0], "target": [0, -1, 0], "intensity": 4,
                          "cutoff_angle": 45, "beam_width": 10}"#;
    let area_on_face = r#"{"type": "area", "shape": {"type": "rectangle",
                           "to_world": {"scale": 0.5, "rotate_x": 90, "translate": [0, 1, 0]}}, "radiance": 5}"#;
    let sphere_light = r#"{"type": "area", "shape": {"type": "sphere", "center": [0, 0, 0], "radius": 0.2},
                           "radiance": 5}"#;
    for (name, light) in [
        ("on a face", on_face),
        ("at a corner", at_corner),
        ("spot inside", spot_inside),
        ("area on a face", area_on_face),
        ("sphere inside", sphere_light),
    ] {
        let media = r#""m": {"sigma_t": 1.5, "albedo": 0.9, "phase": {"type": "hg", "g": 0.5}}"#;
        add(format!("light {name}"), media.into(), "", light, eye);
    }
    // Rays grazing the box's faces: the eye in the plane of the faces x = 1
    // and y = 1, looking along them.
    let media = r#""m": {"sigma_t": 2, "albedo": 0.95}"#;
    add("grazing x = 1".into(), media.into(), "", "", [1.0, 0.0, 4.0]);
    add("grazing edge".into(), media.into(), "", "", [1.0, 1.0, 4.0]);
    // Cameras exactly on a boundary: on the box face z = 1, on its corner,
    // and on a sphere bounding a second medium.
    let two = r#""m": {"sigma_t": 2, "albedo": 0.95}, "n": {"sigma_t": 5, "albedo": 0.5, "emission": {"L_ve": 1}}"#;
    let sphere = r#"{"type": "sphere", "center": [0, 0, 0.5], "radius": 0.5, "interior": "n"}"#;
    add("camera on a face".into(), media.into(), "", "", [0.0, 0.0, 1.0]);
    add("camera on a corner".into(), media.into(), "", "", [1.0, 1.0, 1.0]);
    add("camera on a sphere".into(), two.into(), sphere, "", [0.0, 0.0, 1.0]);
    // Glass and metal surfaces inside the medium.
    let glass = r#"{"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "bsdf": {"type": "dielectric"}}"#;
    add("glass in fog".into(), media.into(), glass, "", eye);
    cases
}

#[test]
fn every_integrator_gives_finite_pixels_on_adversarial_scenes() {
    let integrators = all_integrators();
    let mut failures = Vec::new();
    for (name, media, shapes, lights, eye) in cases() {
        let text = scene_text(&media, &shapes, &lights, eye, r#"{"type": "volpath"}"#);
        let built = build(&text, &name);
        for (integrator_name, settings) in &integrators {
            let started = std::time::Instant::now();
            let options =
                RenderOptions { spp: 4, seed: 7, first_sample: 0, threads: None, sampler: Default::default() };
            let sums = render_sums(&built.scene, settings, &options, &|_, _| {}, None).unwrap();
            let image = sums.mean(4);
            // Through the progressive accumulator as well (its sums' mean).
            let mut acc = Accumulator::new(image.width, image.height);
            acc.add(&sums, 4);
            acc.add(&sums, 4);
            let bad = image.pixels.iter().chain(&acc.image().pixels).position(|p| !p.is_finite());
            if started.elapsed().as_secs_f64() > 5.0 {
                eprintln!("slow: {name} with {integrator_name} took {:.1} s", started.elapsed().as_secs_f64());
            }
            if let Some(i) = bad {
                failures.push(format!("{name} with {integrator_name}: pixel {i} is {:?}", image.pixels[i]));
            }
        }
    }
    assert!(failures.is_empty(), "non-finite pixels:\n{}", failures.join("\n"));
}
