//! `niebla render --aovs` and `--transparent`: the layers in the EXR, the
//! RGBA PNG, resuming a render with layers bit for bit, and clear errors
//! for unknown layers, layers an integrator cannot give and checkpoints
//! without layers.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

const SCENE: &str = r#"{
  "version": 1,
  "camera": {"type": "perspective", "position": [0, 1, 4], "target": [0, 1, 0], "width": 20, "height": 15},
  "render": {"integrator": {"type": "volpath"}, "spp": 4, "seed": 11},
  "media": {"fog": {"sigma_a": 0.05, "sigma_s": 1.5, "phase": {"type": "hg", "g": 0.4}}},
  "shapes": [{"type": "sphere", "center": [0, 1, 0], "radius": 1, "interior": "fog"},
             {"type": "rectangle", "to_world": {"scale": 4, "rotate_x": -90}, "bsdf": {"type": "diffuse"}}],
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

fn run_ok(dir: &Path, args: &[&str]) -> String {
    let out = niebla().current_dir(dir).args(args).output().unwrap();
    assert!(out.status.success(), "niebla {args:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn run_err(dir: &Path, args: &[&str]) -> String {
    let out = niebla().current_dir(dir).args(args).output().unwrap();
    assert!(!out.status.success(), "niebla {args:?} succeeded");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Every channel of an EXR as raw bits (f32 and u32 alike).
fn channels(path: &Path) -> HashMap<String, Vec<u32>> {
    use exr::prelude::*;
    let image = read().no_deep_data().largest_resolution_level().all_channels().first_valid_layer().all_attributes();
    let image = image.from_file(path).unwrap();
    let mut out = HashMap::new();
    for c in &image.layer_data.channel_data.list {
        let bits = match &c.sample_data {
            FlatSamples::F32(v) => v.iter().map(|x| x.to_bits()).collect(),
            FlatSamples::U32(v) => v.clone(),
            FlatSamples::F16(v) => v.iter().map(|x| x.to_f32().to_bits()).collect(),
        };
        out.insert(c.name.to_string(), bits);
    }
    out
}

#[test]
fn layers_are_written_and_resume_bit_for_bit() {
    let dir = temp_dir("cli_aovs");
    std::fs::write(dir.join("fog.json"), SCENE).unwrap();
    run_ok(&dir, &["render", "fog.json", "-o", "all.exr", "--aovs", "all", "--spp", "8", "--quiet"]);
    let all = channels(&dir.join("all.exr"));
    for name in [
        "R",
        "G",
        "B",
        "A",
        "direct.R",
        "indirect.G",
        "emission.B",
        "surface.R",
        "albedo.G",
        "normal.X",
        "depth.Z",
        "variance.B",
    ] {
        assert!(all.contains_key(name), "channel {name} missing: {:?}", all.keys().collect::<Vec<_>>());
    }
    // The beauty is that of a render without layers.
    run_ok(&dir, &["render", "fog.json", "-o", "plain.exr", "--spp", "8", "--quiet"]);
    let plain = channels(&dir.join("plain.exr"));
    for c in ["R", "G", "B"] {
        assert_eq!(plain[c], all[c], "channel {c}");
    }
    assert!(!plain.contains_key("A"), "a render without layers writes RGB alone");
    // Four samples, then resumed to eight: every channel as one render's.
    run_ok(&dir, &["render", "fog.json", "-o", "resumed.exr", "--aovs", "all", "--spp", "4", "--quiet"]);
    run_ok(
        &dir,
        &[
            "render",
            "fog.json",
            "-o",
            "resumed.exr",
            "--aovs",
            "all",
            "--spp",
            "8",
            "--resume",
            "resumed.exr",
            "--quiet",
        ],
    );
    assert_eq!(channels(&dir.join("resumed.exr")), all);
    // A checkpoint without layers cannot continue with layers.
    let err = run_err(
        &dir,
        &["render", "fog.json", "-o", "p2.exr", "--aovs", "albedo", "--spp", "16", "--resume", "plain.exr"],
    );
    assert!(err.contains("holds no layer sums"), "{err}");
    // A transparent render cannot continue an opaque one.
    run_ok(&dir, &["render", "fog.json", "-o", "a.exr", "--aovs", "alpha", "--spp", "2", "--quiet"]);
    let err =
        run_err(&dir, &["render", "fog.json", "-o", "a2.exr", "--transparent", "--spp", "4", "--resume", "a.exr"]);
    assert!(err.contains("opaque background"), "{err}");
}

#[test]
fn transparent_png_is_rgba_and_the_plain_png_rgb() {
    let dir = temp_dir("cli_aovs_png");
    std::fs::write(dir.join("fog.json"), SCENE).unwrap();
    run_ok(&dir, &["render", "fog.json", "-o", "t.png", "--transparent", "--spp", "2", "--quiet"]);
    run_ok(&dir, &["render", "fog.json", "-o", "p.png", "--aovs", "albedo", "--spp", "2", "--quiet"]);
    let color = |name: &str| {
        let decoder = png::Decoder::new(std::fs::File::open(dir.join(name)).unwrap());
        decoder.read_info().unwrap().info().color_type
    };
    assert_eq!(color("t.png"), png::ColorType::Rgba);
    assert_eq!(color("p.png"), png::ColorType::Rgb);
}

#[test]
fn bad_layer_requests_are_clear_errors() {
    let dir = temp_dir("cli_aovs_errors");
    std::fs::write(dir.join("fog.json"), SCENE).unwrap();
    let err = run_err(&dir, &["render", "fog.json", "-o", "x.exr", "--aovs", "albedo,shadow"]);
    assert!(err.contains("--aovs") && err.contains("unknown layer \"shadow\""), "{err}");
    let err = run_err(&dir, &["render", "fog.json", "-o", "x.exr", "--aovs", "direct", "--integrator", "single"]);
    assert!(err.contains("only the volpath integrator"), "{err}");
    let err = run_err(&dir, &["render", "fog.json", "-o", "x.exr", "--aovs", "alpha", "--integrator", "photon"]);
    assert!(err.contains("photon integrator writes no layers"), "{err}");
    std::fs::write(
        dir.join("bad.json"),
        SCENE.replace("\"version\": 1,", "\"version\": 1, \"film\": {\"aovs\": [\"depth\", \"zdepth\"]},"),
    )
    .unwrap();
    let err = run_err(&dir, &["render", "bad.json", "-o", "x.exr"]);
    assert!(err.contains("film.aovs[1]") && err.contains("unknown layer \"zdepth\""), "{err}");
}

#[test]
fn denoise_keeps_the_raw_image_or_says_what_is_missing() {
    let dir = temp_dir("cli_denoise");
    std::fs::write(dir.join("fog.json"), SCENE).unwrap();
    let args = ["render", "fog.json", "-o", "x.exr", "--denoise", "--spp", "2", "--quiet"];
    let out =
        niebla().current_dir(&dir).args(args).env("NIEBLA_OIDN_LIBRARY", "/nonexistent/libOIDN.so").output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--denoise") && err.contains("pip install pyoidn"), "{err}");
    assert!(!dir.join("x.exr").exists(), "nothing is rendered without the library");
    if std::env::var_os("NIEBLA_OIDN_LIBRARY").is_none() && std::env::var_os("NIEBLA_REQUIRE_OIDN").is_none() {
        eprintln!("skipped the denoised render: NIEBLA_OIDN_LIBRARY is not set");
        return;
    }
    run_ok(&dir, &args);
    run_ok(&dir, &["render", "fog.json", "-o", "plain.exr", "--spp", "2", "--quiet"]);
    let (raw, plain, denoised) =
        (channels(&dir.join("x.exr")), channels(&dir.join("plain.exr")), channels(&dir.join("x.denoised.exr")));
    for c in ["R", "G", "B"] {
        assert_eq!(raw[c], plain[c], "the raw image is kept, channel {c}");
        assert_eq!(denoised[c].len(), raw[c].len());
        assert_ne!(denoised[c], raw[c]);
    }
    assert!(raw.contains_key("albedo.R") && raw.contains_key("normal.Z"), "the features are written");
}

#[test]
fn adaptive_writes_the_spp_map_and_refuses_bad_thresholds() {
    let dir = temp_dir("cli_adaptive");
    std::fs::write(dir.join("fog.json"), SCENE).unwrap();
    for bad in ["0", "1", "-0.5", "nan"] {
        let flag = format!("--adaptive={bad}");
        let err = run_err(&dir, &["render", "fog.json", "-o", "a.exr", &flag, "--spp", "8"]);
        assert!(err.contains("--adaptive"), "{bad}: {err}");
    }
    let err = run_err(&dir, &["render", "fog.json", "-o", "a.exr", "--adaptive", "0.1", "--sampler", "sobol"]);
    assert!(err.contains("--adaptive") && err.contains("sobol"), "{err}");
    let err = run_err(&dir, &["render", "fog.json", "-o", "a.exr", "--adaptive", "0.1", "--resume", "x.exr"]);
    assert!(err.contains("--resume") || err.contains("cannot be used"), "{err}");
    run_ok(&dir, &["render", "fog.json", "-o", "a.exr", "--adaptive", "0.2", "--spp", "64", "--quiet"]);
    let exr = channels(&dir.join("a.exr"));
    let spp: Vec<f32> = exr["spp.Z"].iter().map(|&b| f32::from_bits(b)).collect();
    // Passes end at 1, 2, 3, 4, 6, 8, 12, 16, 24, ... and decisions wait
    // for 8 decided samples, so a pixel takes 16, 24, 32, 48 or 64.
    assert!(spp.iter().all(|&s| [16.0, 24.0, 32.0, 48.0, 64.0].contains(&s)), "{spp:?}");
    assert!(spp.iter().any(|&s| s < 64.0), "some pixels stop early");
    assert!(exr.contains_key("variance.G") && exr.contains_key("R"));
    // With layers: the split layers add up to the beauty; the spp map is
    // that of the render without layers (same samples, same decisions).
    let list = "direct,indirect,emission,surface,albedo,depth";
    run_ok(&dir, &["render", "fog.json", "-o", "b.exr", "--adaptive", "0.2", "--spp", "64", "--aovs", list, "--quiet"]);
    let layered = channels(&dir.join("b.exr"));
    let f = |name: &str| -> Vec<f32> { layered[name].iter().map(|&b| f32::from_bits(b)).collect() };
    assert_eq!(f("spp.Z"), spp);
    assert_eq!(f("R"), exr["R"].iter().map(|&b| f32::from_bits(b)).collect::<Vec<_>>());
    for c in ["R", "G", "B"] {
        let beauty = f(c);
        let parts: Vec<Vec<f32>> =
            ["direct", "indirect", "emission", "surface"].iter().map(|l| f(&format!("{l}.{c}"))).collect();
        for (i, b) in beauty.iter().enumerate() {
            let sum: f32 = parts.iter().map(|p| p[i]).sum();
            assert!((sum - b).abs() <= 1e-5 * b.abs() + 1e-7, "pixel {i} {c}: layers {sum}, beauty {b}");
        }
    }
    assert!(layered.contains_key("albedo.G") && layered.contains_key("depth.Z"));
    let err = run_err(&dir, &["render", "fog.json", "-o", "c.exr", "--adaptive", "0.2", "--denoise"]);
    assert!(err.contains("--denoise") || err.contains("cannot be used"), "{err}");
    // The cost rule: an spp map of the same schedule, the old rule's image
    // unchanged without the flag, and the flag needs --adaptive.
    run_ok(
        &dir,
        &["render", "fog.json", "-o", "d.exr", "--adaptive", "0.2", "--adaptive-cost", "--spp", "64", "--quiet"],
    );
    let cost = channels(&dir.join("d.exr"));
    let cost_spp: Vec<f32> = cost["spp.Z"].iter().map(|&b| f32::from_bits(b)).collect();
    assert!(cost_spp.iter().all(|&s| [16.0, 24.0, 32.0, 48.0, 64.0].contains(&s)), "{cost_spp:?}");
    assert!(cost.contains_key("variance.G") && cost.contains_key("R"));
    let err = run_err(&dir, &["render", "fog.json", "-o", "e.exr", "--adaptive-cost", "--spp", "8"]);
    assert!(err.contains("--adaptive"), "{err}");
}
