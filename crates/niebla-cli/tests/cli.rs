//! The `niebla` command as a user meets it: real child processes, real files.

use std::path::{Path, PathBuf};
use std::process::Command;

const TINY_SCENE: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 1, 0], "width": 24, "height": 16},
  "render": {"integrator": {"type": "single", "sampling": "mis"}, "spp": 2},
  "media": {"fog": {"sigma_a": 0.05, "sigma_s": 0.3}},
  "shapes": [{"type": "sphere", "center": [0, 1, 0], "radius": 1, "interior": "fog"}],
  "lights": [{"type": "point", "position": [1, 3, 1], "intensity": 10}, {"type": "constant", "radiance": 0.1}]
}"#;

fn niebla() -> Command {
    Command::new(env!("CARGO_BIN_EXE_niebla"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

#[test]
fn render_writes_exr_and_png_that_decode_to_the_scene_size() {
    let dir = temp_dir("cli_render");
    let scene = dir.join("tiny.json");
    std::fs::write(&scene, TINY_SCENE).unwrap();
    let out = niebla().current_dir(&dir).args(["render", "tiny.json", "--quiet"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("rendered 24x16 at 2 spp with single"), "{stdout}");
    assert_eq!(files_in(&dir), ["tiny.exr", "tiny.json", "tiny.png"]);

    let png = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(dir.join("tiny.png")).unwrap()));
    let reader = png.read_info().unwrap();
    assert_eq!((reader.info().width, reader.info().height), (24, 16));

    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        dir.join("tiny.exr"),
        |resolution, _| vec![[0f32; 3]; resolution.width() * resolution.height()],
        |pixels, pos, (r, g, b, _a): (f32, f32, f32, f32)| pixels[pos.y() * 24 + pos.x()] = [r, g, b],
    )
    .unwrap();
    let pixels = &image.layer_data.channel_data.pixels;
    assert_eq!(pixels.len(), 24 * 16);
    assert!(pixels.iter().all(|p| p.iter().all(|v| v.is_finite() && *v >= 0.0)));
    assert!(pixels.iter().any(|p| p[1] > 0.0));

    // Asking for one format writes only that one.
    let out = niebla().current_dir(&dir).args(["render", "tiny.json", "--quiet", "-o", "only.png"]).output().unwrap();
    assert!(out.status.success());
    assert_eq!(files_in(&dir), ["only.png", "tiny.exr", "tiny.json", "tiny.png"]);
}

#[test]
fn bad_inputs_fail_with_a_message_naming_file_and_field_and_leave_no_output() {
    let dir = temp_dir("cli_errors");
    std::fs::write(dir.join("bad.json"), TINY_SCENE.replace("\"sigma_s\": 0.3", "\"sigma_s\": [0.3, 0.3, -1]"))
        .unwrap();
    std::fs::write(dir.join("typo.json"), TINY_SCENE.replace("\"radius\"", "\"raduis\"")).unwrap();
    std::fs::write(dir.join("broken.json"), "{\"version\": 1, \"camera\": ").unwrap();
    let cases: [(&[&str], &str); 7] = [
        (&["render", "missing.json"], "missing.json: scene file not found"),
        (&["render", "bad.json"], "bad.json: media.fog.sigma_s[2]"),
        (&["render", "typo.json"], "typo.json: shapes[0].raduis"),
        (&["render", "broken.json"], "broken.json"),
        (&["render", "bad.json", "-o", "x.tiff"], "bad.json"),
        (&["render", "--spp", "0"], "--spp"),
        (&["render", "-o", "no/such/folder/x.png"], "does not exist"),
    ];
    for (args, expected) in cases {
        let out = niebla().current_dir(&dir).args(args).arg("--quiet").output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: expected {expected:?} in {stderr:?}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    assert_eq!(files_in(&dir), ["bad.json", "broken.json", "typo.json"], "no image may be left behind");
}

#[test]
fn help_explains_every_render_option() {
    let out = niebla().args(["render", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    for option in ["--output", "--spp", "--integrator", "--sampling", "--threads", "--seed", "--exposure"] {
        assert!(help.contains(option), "{option} missing from:\n{help}");
    }
    let out = niebla().arg("--help").output().unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    for command in ["render", "info", "bench"] {
        assert!(help.contains(command));
    }
}

#[test]
fn info_describes_the_default_scene() {
    let out = niebla().arg("info").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("haze: homogeneous"), "{text}");
    assert!(text.contains("camera medium: haze"), "{text}");
    assert!(text.contains("lights (3)"), "{text}");
}

#[test]
fn a_medium_nothing_refers_to_is_warned_about_by_info_and_render() {
    let dir = temp_dir("cli_unused_medium");
    // A grid medium from a file-less procedural density, neither bounded by
    // a shape nor the ambient medium: it would render only the background.
    let scene = r#"{"version": 1,
        "camera": {"type": "perspective", "position": [0, 0, 5], "target": [0, 0, 0], "width": 8, "height": 8},
        "media": {"plume": {"type": "grid", "sigma_t": 2, "albedo": 0.9,
                            "density": {"type": "procedural", "shape": "cloud", "resolution": 8}}},
        "lights": [{"type": "constant", "radiance": 1}]}"#;
    std::fs::write(dir.join("plume.json"), scene).unwrap();
    for args in [vec!["info", "plume.json"], vec!["render", "plume.json", "-o", "x.png", "--spp", "1", "--quiet"]] {
        let out = niebla().current_dir(&dir).args(&args).output().unwrap();
        assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.matches("warning: ").count(), 1, "{args:?}: {err}");
        assert!(err.contains(r#"warning: plume.json: media.plume: medium "plume" is not used"#), "{err}");
        assert!(err.contains(r#""interior": "plume""#) && err.contains(r#""ambient_medium": "plume""#), "{err}");
    }
    // Bounded by a shape, it is used: no warning.
    let bounded = scene.replace(
        r#""lights""#,
        r#""shapes": [{"type": "box", "min": [-1, -1, -1], "max": [1, 1, 1], "interior": "plume"}], "lights""#,
    );
    std::fs::write(dir.join("bounded.json"), bounded).unwrap();
    let out = niebla().current_dir(&dir).args(["info", "bounded.json"]).output().unwrap();
    assert!(out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"), "{}", String::from_utf8_lossy(&out.stderr));
}

/// `niebla bench adaptive` on a tiny image: the table's columns parse, and
/// the sample counts agree with the sweep lines and with what the adaptive
/// schedule allows (no pixel stops before 16 samples, so up to 16 spp the
/// adaptive render takes every sample and is the plain render of the same
/// seed); times are not checked.
#[test]
fn bench_adaptive_prints_a_consistent_table() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../bench/scenes/fog_spot.json");
    let output = niebla()
        .args(["bench", "adaptive"])
        .arg(&scene)
        .args(["--width", "8", "--reference-spp", "1024", "--variance-spp", "16", "--spp", "4,16,64,256"])
        .args(["--thresholds", "0.3,0.2", "--target", "0.05", "--threads", "2"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{text}\n{}", String::from_utf8_lossy(&output.stderr));
    // Sweep lines: "plain <spp> spp: rel MSE <e> ..." and
    // "adaptive <threshold> <spp> spp: rel MSE <e> in <t> s, <taken> spp taken".
    let mut plain = Vec::new();
    let mut adaptive = Vec::new();
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.first() {
            Some(&"plain") => plain.push((words[1].parse::<f64>().unwrap(), words[5].parse::<f64>().unwrap())),
            Some(&"adaptive") => adaptive.push((
                words[2].parse::<f64>().unwrap(),
                words[6].parse::<f64>().unwrap(),
                words[10].parse::<f64>().unwrap(),
            )),
            _ => {}
        }
    }
    assert_eq!(plain.iter().map(|p| p.0).collect::<Vec<_>>(), [4.0, 16.0, 64.0, 256.0], "{text}");
    assert_eq!(adaptive.len(), 8, "{text}");
    for &(spp, error, taken) in &adaptive {
        assert!(taken <= spp && taken >= spp.min(16.0), "{spp} spp scheduled, {taken} taken\n{text}");
        if spp <= 16.0 {
            assert_eq!(taken, spp, "{text}");
            let plain_error = plain.iter().find(|p| p.0 == spp).unwrap().1;
            assert_eq!(error, plain_error, "the adaptive render that stops nothing is the plain one\n{text}");
        }
    }
    // The table: a header and one row of 6 + 2 columns.
    let lines: Vec<&str> = text.lines().collect();
    let h = lines.iter().position(|l| l.starts_with("scene")).unwrap_or_else(|| panic!("{text}"));
    let header: Vec<&str> = lines[h].split_whitespace().collect();
    assert_eq!(header, ["scene", "bound", "plain_spp", "plain_s", "a0.3_spp", "a0.3_s", "a0.2_spp", "a0.2_s"]);
    let row: Vec<&str> = lines[h + 1].split_whitespace().collect();
    assert_eq!(row.len(), header.len(), "{text}");
    assert_eq!(row[0], "fog_spot");
    let bound: f64 = row[1].trim_end_matches('x').parse().unwrap();
    assert!(bound >= 1.0, "{text}");
    for cell in &row[2..] {
        assert!(*cell == "-" || cell.trim_start_matches('<').parse::<f64>().is_ok(), "{cell}\n{text}");
    }
    // Plain samples to the target lie between the sweep points that bracket it.
    let first_below = plain.iter().position(|p| p.1 < 0.05);
    match (first_below, row[2]) {
        (None, cell) => assert_eq!(cell, "-", "{text}"),
        (Some(0), cell) => assert!(cell.starts_with('<'), "{text}"),
        (Some(i), cell) => {
            let spp: f64 = cell.parse().unwrap();
            assert!(spp >= plain[i - 1].0 && spp <= plain[i].0, "{spp} not in the bracket\n{text}");
        }
    }
    for (k, &threshold) in [0.3, 0.2].iter().enumerate() {
        let sweep: Vec<_> = adaptive.iter().skip(4 * k).take(4).collect();
        assert!(sweep.iter().all(|a| a.0 <= 256.0));
        let cell = row[4 + 2 * k];
        if let Ok(spp) = cell.parse::<f64>() {
            assert!(spp > 0.0 && spp <= 256.0, "threshold {threshold}: {spp}\n{text}");
        }
    }
}

/// `niebla render --adaptive-pilot` writes the image with its spp map and
/// the pilot's header; bad pilot requests are errors naming the flag.
#[test]
fn render_adaptive_pilot_writes_the_spp_map_and_checks_its_flags() {
    let dir = temp_dir("cli_adaptive_pilot");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../bench/scenes/fog_spot.json");
    let out = dir.join("pilot.exr");
    let run = niebla()
        .args(["render", "--width", "12", "--spp", "8", "--adaptive-pilot", "--pilot-spp", "4", "--sampler", "sobol"])
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    assert!(String::from_utf8_lossy(&run.stdout).contains("4 pilot spp, then 8 spp on average"));
    let bytes = std::fs::read(&out).unwrap();
    let header = String::from_utf8_lossy(&bytes[..bytes.len().min(2000)]);
    for name in ["spp.Z", "variance.R", "nieblaAdaptiveRule", "pilot", "nieblaPilotSpp"] {
        assert!(header.contains(name), "{name} missing from the EXR header");
    }
    for (args, flag) in [
        (vec!["--adaptive-pilot", "--pilot-spp", "1"], "--pilot-spp"),
        (vec!["--adaptive-pilot", "--adaptive", "0.1"], "--adaptive"),
        (vec!["--pilot-spp", "4"], "--adaptive-pilot"),
    ] {
        let run = niebla()
            .args(["render", "--width", "4", "--spp", "4"])
            .args(&args)
            .arg(&scene)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success() && err.contains(flag), "{args:?}: {err}");
    }
}
